"""Every ``mrdamper`` name a benchmark script imports exists.

The benchmarks are run by hand, most of them for minutes, so a moved module would otherwise
show only when somebody next runs one. This reads each script's imports (at any depth, also
inside functions) and imports what they name, without running the script.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("*.py"))


def _mrdamper_imports(path: Path) -> list[tuple[str, str | None]]:
    """(module, name) for each ``mrdamper`` import of ``path``; name None for ``import m``."""
    found: list[tuple[str, str | None]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("mrdamper"):
            found.extend((node.module, alias.name) for alias in node.names)
        elif isinstance(node, ast.Import):
            found.extend((a.name, None) for a in node.names if a.name.startswith("mrdamper"))
    return found


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_benchmark_imports_resolve(script: Path) -> None:
    missing = []
    for module_name, name in _mrdamper_imports(script):
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            missing.append(f"{module_name} ({exc})")
            continue
        if name is None or hasattr(module, name):
            continue
        try:
            importlib.import_module(f"{module_name}.{name}")
        except ImportError:
            missing.append(f"{module_name}.{name}")
    assert not missing, f"{script.name} imports what does not exist: {', '.join(missing)}"
