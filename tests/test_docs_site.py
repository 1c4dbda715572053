"""The documentation site builds with ``mkdocs build --strict`` (no broken link, no docstring that
mkdocstrings cannot parse) and its API reference is generated from the docstrings.

Runs ``python -m mkdocs`` from the repository root into a temporary folder, about 10 s. Skips with
a reason when mkdocs or mkdocstrings is not installed (``pip install -e ".[dev]"``) or when the
tests are not run from a source checkout.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_mkdocs_build_strict(tmp_path: Path) -> None:
    for mod in ("mkdocs", "mkdocstrings", "mkdocstrings_handlers.python", "material"):
        if importlib.util.find_spec(mod.split(".")[0]) is None:
            pytest.skip(f"{mod} is not installed (pip install -e '.[dev]')")
    if not (REPO / "mkdocs.yml").is_file():
        pytest.skip(f"{REPO} is not a source checkout of mrdamper")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(REPO / "src")}
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env=env,
    )
    assert proc.returncode == 0, (
        f"mkdocs build --strict failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    )
    site = tmp_path / "site"
    tutorial = (site / "tutorial" / "index.html").read_text(encoding="utf-8")
    assert "read_directory" in tutorial
    api = (site / "api" / "study" / "index.html").read_text(encoding="utf-8")
    # generated from the docstrings: the function's anchor and its numpydoc parameter table
    assert 'id="mrdamper.study.run_study"' in api
    assert "Fit every model of" in api and "Parameters" in api
    for page in (
        "data",
        "models",
        "analysis",
        "metrics",
        "plotting",
        "rig",
        "signals",
        "control",
        "errors",
        "progress",
    ):
        assert f'id="mrdamper.{page}' in (site / "api" / page / "index.html").read_text(
            encoding="utf-8"
        ), page
