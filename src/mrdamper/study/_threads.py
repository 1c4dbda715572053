"""Run study tasks with single-threaded BLAS.

A study runs many independent fits and simulations side by side, one per worker. Multi-threaded
BLAS inside each of them oversubscribes the cores: on the 2-core reference machine the full demo
took 58 s with two workers and 45 s with one, against 21 s with one BLAS thread per task
(``docs/performance.md``). Each task therefore limits BLAS to one thread while it runs, through
``threadpoolctl``, which restores the previous setting afterwards.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

__all__ = ["single_threaded_blas"]


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Limit BLAS to one thread inside the block; restore the previous thread counts after it."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
