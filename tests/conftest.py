"""Shared fixtures. Real-data tests read ``../shared/data`` beside the repository and skip with a
clear reason where it is absent (CI always has it)."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

import matplotlib
import pytest
from threadpoolctl import threadpool_limits

matplotlib.use("Agg")

#: One BLAS thread per test process. The suite runs one worker per core (``-n auto``); a second
#: BLAS thread in each worker only competes with the other worker (on the 2-core machine the quick
#: generalisation test took 29.8 s of CPU for 16.4 s of wall time with two threads, 14.5 s for
#: 13.2 s with one). The pinned real-data values were measured with one thread too. The variables
#: reach the libraries loaded later (SciPy's own OpenBLAS) and the subprocesses; the limit those
#: already loaded.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
BLAS_LIMIT = threadpool_limits(limits=1, user_api="blas")

REPO_ROOT = Path(__file__).resolve().parents[1]


def load_benchmark(name: str) -> ModuleType:
    """The script ``benchmarks/<name>.py`` imported as a module (its folder on ``sys.path``, for
    the modules it imports beside it), registered as ``<name>_bench`` (dataclasses look their
    module up)."""
    path = REPO_ROOT / "benchmarks" / f"{name}.py"
    if str(path.parent) not in sys.path:
        sys.path.insert(0, str(path.parent))
    spec = importlib.util.spec_from_file_location(f"{name}_bench", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


SHARED_DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))


def package_kinds() -> list[str]:
    """The kinds of the package's kind table, in ``known_kinds()`` order: not the toy families
    that some test modules register at import (``known_kinds()`` lists them once collected)."""
    from mrdamper import known_kinds
    from mrdamper.kinds import KINDS

    own = {row.kind for row in KINDS}
    return [k for k in known_kinds() if k in own]


def _require(path: Path) -> Path:
    if not path.exists():
        pytest.skip(
            f"real measured data not found at {path} (set MRDAMPER_SHARED_DATA to its folder)"
        )
    return path


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Folder holding the shared measured data sets."""
    return _require(SHARED_DATA)


@pytest.fixture(scope="session")
def quiroz_unfiltered_dir(shared_data: Path) -> Path:
    """Folder of the 30 unfiltered constant-current sine records (Quiroz 2022)."""
    return _require(shared_data / "quiroz2022_utfsm" / "sine_unfiltered")


@pytest.fixture(scope="session")
def quiroz_filtered_dir(shared_data: Path) -> Path:
    """Folder of the 30 author-filtered constant-current sine records (Quiroz 2022)."""
    return _require(shared_data / "quiroz2022_utfsm" / "sine_filtered")


@pytest.fixture(scope="session")
def dyke_csv(shared_data: Path) -> Path:
    """The Dyke (1996) random-excitation record with command voltage."""
    return _require(shared_data / "dyke1996_nees" / "ranran_50.csv")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Start the longest tests first: the documentation blocks, then the modules holding ``slow``
    tests (each module kept together, so its module-scoped fixtures are built once per worker),
    then the rest, each group in collection order. The test workers steal work from each other
    (``--dist worksteal``), so what is left at the end is short tests and both cores stay busy."""
    slow_modules = {item.module for item in items if item.get_closest_marker("slow")}

    def group(item: pytest.Item) -> int:
        if getattr(item, "originalname", "") == "test_page_blocks_run":
            return 0
        return 1 if getattr(item, "module", None) in slow_modules else 2

    order = {id(item): (group(item), k) for k, item in enumerate(items)}
    items.sort(key=lambda item: order[id(item)])
