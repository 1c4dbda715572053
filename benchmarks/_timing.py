"""Timing helper shared by the benchmark scripts (imported as ``_timing`` when a script is run
as ``python benchmarks/<name>.py``, which puts this folder first on ``sys.path``)."""

from __future__ import annotations

import time
from collections.abc import Callable


def best_time(fn: Callable[[], object], repeat: int = 5) -> float:
    """Smallest wall time [s] of ``repeat`` calls of ``fn`` (the least disturbed by other load)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)
