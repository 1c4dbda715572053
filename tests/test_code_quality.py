"""The project's own lint and type checks pass: ``ruff check src tests benchmarks`` and
``mypy src``.

Both run as subprocesses of this interpreter (``python -m ruff`` / ``python -m mypy``) from the
repository root, so they read the settings in ``pyproject.toml``. mypy runs without its
incremental cache (a fresh cache folder per run), about 15 s on two cores; the test is marked
slow. Each test skips with a reason when its tool is not installed or when the tests are not run
from a source checkout.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: Upper bound on one checker run [s]; far above the measured times, it only stops a hung tool.
TIMEOUT_S = 300


def _run_module(tool: str, *args: str) -> subprocess.CompletedProcess[str]:
    if importlib.util.find_spec(tool) is None:
        pytest.skip(f"{tool} is not installed (pip install -e '.[dev]')")
    if not (REPO / "pyproject.toml").is_file() or not (REPO / "src" / "mrdamper").is_dir():
        pytest.skip(f"{REPO} is not a source checkout of mrdamper")
    return subprocess.run(
        [sys.executable, "-m", tool, *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )


def test_ruff_check_passes() -> None:
    proc = _run_module("ruff", "check", "--no-cache", "src", "tests", "benchmarks")
    assert proc.returncode == 0, f"ruff check failed:\n{proc.stdout}\n{proc.stderr}"


@pytest.mark.slow
def test_mypy_passes(tmp_path: Path) -> None:
    proc = _run_module("mypy", "--cache-dir", str(tmp_path / "mypy_cache"), "src")
    assert proc.returncode == 0, f"mypy failed:\n{proc.stdout}\n{proc.stderr}"
    assert "Success" in proc.stdout, proc.stdout
