"""Worker processes that end with the process that started them.

:func:`init_worker` is the initializer of every local process pool (the study's workers, the
virtual rig's generators). In a worker it

* restores the default action of SIGTERM (a forked worker inherits the command line's handler,
  which turns SIGTERM into an interruption; a worker must simply end when it is stopped);
* on Linux, asks the kernel to send it SIGTERM when its parent ends (``PR_SET_PDEATHSIG``), so
  no worker outlives a command that was killed outright (SIGKILL) before it could stop them;
* adds the kind-table rows that the parent added at run time (families registered with
  :func:`mrdamper.models.register`), so a worker started by spawn knows them too (plug-ins with
  an entry point it finds by itself).
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence
from typing import Any

from mrdamper import kinds
from mrdamper.kinds import KindSpec

__all__ = ["init_worker", "stop_pool"]

#: ``prctl`` option that sets the signal a process gets when its parent ends (Linux).
_PR_SET_PDEATHSIG = 1


def _die_with_parent(parent: int) -> None:
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - no prctl: the pool still stops them
        return
    if os.getppid() != parent:  # the parent ended before the request was in place
        os._exit(1)


def init_worker(parent: int | None = None, rows: Sequence[KindSpec] = ()) -> None:
    """Initializer of a local worker process (see the module docstring).

    Parameters
    ----------
    parent : int, optional
        Process id of the process that starts the pool (default: this worker's parent).
    rows : sequence of KindSpec
        Kind-table rows the parent added at run time (:func:`mrdamper.kinds.added`).
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _die_with_parent(parent if parent is not None else os.getppid())
    for row in rows:
        kinds.add(row)


def stop_pool(pool: Any) -> None:
    """Stop a :class:`concurrent.futures.ProcessPoolExecutor` now: drop the queued tasks and end
    the running ones instead of waiting for them (after an interruption).

    Returns once the pool's management thread has ended too (at most 5 s): on Python 3.11 the
    interpreter's exit hook wakes that thread through a pipe the thread closes when its workers
    are gone, without a lock, and a thread still closing it then prints a traceback
    (``OSError: [Errno 9] Bad file descriptor``) after the command's last line.
    """
    procs = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5)
    if manager is not None:
        manager.join(timeout=5)
