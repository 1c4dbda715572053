"""Run study tasks with single-threaded BLAS.

A study runs many independent fits and simulations side by side, one per worker. Multi-threaded
BLAS inside each of them oversubscribes the cores: on the 2-core reference machine the full demo
took 58 s with two workers and 45 s with one, against 21 s with one BLAS thread per task
(``docs/performance.md``). Each task therefore limits BLAS to one thread while it runs and restores
the previous setting afterwards. ``threadpoolctl`` is used when installed; otherwise the OpenBLAS
libraries loaded in the process (NumPy's and SciPy's wheels) are driven directly through their
``*_set_num_threads`` entry points. Where neither is available the tasks run unchanged.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

__all__ = ["single_threaded_blas"]

_PREFIXES = ("scipy_openblas", "openblas")
_SUFFIXES = ("64_", "")


def _openblas_controls() -> tuple[tuple[Callable[[], int], Callable[[int], None]], ...]:
    """(get, set) pairs of every OpenBLAS library mapped into this process (Linux)."""
    import scipy.linalg  # noqa: F401 - loads SciPy's BLAS too, so both libraries are found

    maps = Path("/proc/self/maps")
    if not maps.exists():
        return ()
    paths = sorted({line.split()[-1] for line in maps.read_text().splitlines() if "openblas" in line.lower()
                    and line.split()[-1].startswith("/")})
    return _controls_of(tuple(paths))


@lru_cache(maxsize=8)
def _controls_of(paths: tuple[str, ...]) -> tuple[tuple[Callable[[], int], Callable[[int], None]], ...]:
    out = []
    for p in paths:
        try:
            lib = ctypes.CDLL(p)
        except OSError:
            continue
        for pre in _PREFIXES:
            for suf in _SUFFIXES:
                get = getattr(lib, f"{pre}_get_num_threads{suf}", None)
                set_ = getattr(lib, f"{pre}_set_num_threads{suf}", None)
                if get is not None and set_ is not None:
                    get.restype = ctypes.c_int
                    set_.argtypes = [ctypes.c_int]
                    out.append((get, set_))
                    break
            else:
                continue
            break
    return tuple(out)


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Limit BLAS to one thread inside the block; restore the previous thread counts after it."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    if threadpool_limits is not None:
        with threadpool_limits(limits=1, user_api="blas"):
            yield
        return
    controls = _openblas_controls()
    before = [get() for get, _ in controls]
    for _, set_ in controls:
        set_(1)
    try:
        yield
    finally:
        for (_, set_), n in zip(controls, before):
            set_(n)
