"""A small executor abstraction: one study code path for several back ends.

The study runs in-process, on local processes or on Dask.

Three implementations share one interface (:class:`StudyExecutor`):

* :class:`SerialExecutor` runs each task at submission, in the calling process (``workers=1``).
* :class:`ProcessExecutor` uses :class:`concurrent.futures.ProcessPoolExecutor`. Records are
  shared once through ``.npy`` files in a private temporary folder (memory-mapped by the workers)
  instead of being pickled into every task.
* :class:`DaskExecutor` submits to a ``dask.distributed`` scheduler; records are scattered once.

Records in memory travel as plain arrays and a metadata dict (``Experiment`` holds a read-only
mapping that does not pickle) and are rebuilt, validated, in the worker. Records given as
:class:`~mrdamper.data.RecordSource` travel as their source (a path, reader options and a header)
and are read by the worker that needs them, with every executor: the study's process never holds
them all. On a Dask cluster the sources travel with absolute paths, and the executor checks once
(:meth:`DaskExecutor.prepare`) that every worker can read every file; when one cannot, the records
are read by the study's process and scattered instead, with a note.
"""

from __future__ import annotations

import abc
import concurrent.futures as cf
import dataclasses
import multiprocessing
import os
import shutil
import tempfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mrdamper import kinds
from mrdamper._io.processes import init_worker, stop_pool
from mrdamper._warn import warn_user
from mrdamper.data import Experiment, RecordSource
from mrdamper.errors import DataValidationError, Note

__all__ = [
    "DaskExecutor",
    "DiskRecord",
    "PackedRecord",
    "ProcessExecutor",
    "RecordHandle",
    "SerialExecutor",
    "StudyExecutor",
    "check_scheduler_address",
    "compile_kernels",
    "default_workers",
    "loops_ahead",
    "make_executor",
    "resolve_record",
    "unreadable",
]


#: Schemes of a Dask scheduler address that need ``host:port``.
_NET_SCHEMES: tuple[str, ...] = ("tcp", "tls", "ws", "wss", "ucx")


def check_scheduler_address(address: str) -> str:
    """Check the form of a Dask scheduler address before connecting; return it.

    Accepted: ``SCHEME://HOST:PORT`` with a scheme of :data:`_NET_SCHEMES` (or ``HOST:PORT``,
    taken as TCP) and a port in 1..65535, or ``inproc://...``.

    Raises
    ------
    DataValidationError
        Not of that form (the message shows the expected form).
    """
    expected = f"expected an address such as tcp://HOST:8786, got {address!r}"
    if not isinstance(address, str) or not address.strip():
        raise DataValidationError("--scheduler", expected)
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme == "inproc":
        return address
    if scheme not in _NET_SCHEMES:
        raise DataValidationError(
            "--scheduler", f"unknown scheme {scheme!r} (one of {list(_NET_SCHEMES)}); {expected}"
        )
    host, colon, port = rest.rstrip("/").rpartition(":")
    if not colon or not host.strip("[]") or not port.isdigit() or not 0 < int(port) < 65536:
        raise DataValidationError("--scheduler", expected)
    return address


def default_workers() -> int:
    """Default number of local worker processes: ``min(2, cpu count)``."""
    return max(1, min(2, os.cpu_count() or 1))


@dataclass(frozen=True)
class PackedRecord:
    """A record as plain picklable data: arrays by channel, name and metadata."""

    name: str
    metadata: dict[str, Any]
    arrays: dict[str, np.ndarray]


@dataclass(frozen=True)
class DiskRecord:
    """A record stored as ``.npy`` files (one per channel) in a shared folder."""

    name: str
    metadata: dict[str, Any]
    paths: dict[str, str]


#: What a task receives for a record: the record itself (in-process), its source (read by the
#: task), its arrays, its ``.npy`` files, or (Dask) a future of a :class:`PackedRecord`.
RecordHandle = Experiment | RecordSource | PackedRecord | DiskRecord


def pack(e: Experiment) -> PackedRecord:
    """Picklable form of an Experiment."""
    return PackedRecord(
        e.name, dict(e.metadata), {c: np.asarray(getattr(e, c)) for c in e.channel_names}
    )


def resolve_record(handle: RecordHandle) -> Experiment:
    """Rebuild an :class:`Experiment` from whatever handle a task received.

    Parameters
    ----------
    handle : Experiment, RecordSource, PackedRecord or DiskRecord
        The record as shared by an executor (a source is read here).

    Returns
    -------
    Experiment
    """
    if isinstance(handle, Experiment):
        return handle
    if isinstance(handle, RecordSource):
        return handle.load()
    if isinstance(handle, PackedRecord):
        return Experiment(**handle.arrays, name=handle.name, metadata=handle.metadata)  # type: ignore[arg-type]
    if isinstance(handle, DiskRecord):
        arrays = {c: np.load(p, mmap_mode="r") for c, p in handle.paths.items()}
        return Experiment(**arrays, name=handle.name, metadata=handle.metadata)
    raise DataValidationError("record", f"unexpected record handle of type {type(handle).__name__}")


class StudyExecutor(abc.ABC):
    """Common interface of the study executors."""

    #: Human description shown in the report (e.g. ``"2 local processes"``).
    description: str = ""

    def prepare(self, records: Iterable[Experiment | RecordSource]) -> None:
        """Called once with every record of the study before the first :meth:`share`.

        Parameters
        ----------
        records : iterable of Experiment or RecordSource
            The records the tasks will receive.
        """

    def share(self, e: Experiment | RecordSource) -> Any:
        """Make a record available to tasks; returns the handle to pass as a task argument.

        Parameters
        ----------
        e : Experiment or RecordSource
            The record; a source is passed as it is (tasks read it).
        """
        return e

    @abc.abstractmethod
    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Schedule ``fn(*args)``; returns a future with ``result()`` and ``cancel()``."""

    @abc.abstractmethod
    def wait_first(self, pending: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        """Block until at least one of ``pending`` is done; return ``(done, not_done)``."""

    def close(self, cancel: bool = False) -> None:
        """Release workers and temporary files; ``cancel`` drops queued tasks."""


class SerialExecutor(StudyExecutor):
    """Runs every task in the calling process at submission time."""

    description = "in-process (1 worker)"

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future[Any]:
        fut: cf.Future[Any] = cf.Future()
        try:
            fut.set_result(fn(*args))
        except Exception as exc:  # noqa: BLE001 - tasks catch their own errors; this is a safety net
            fut.set_exception(exc)
        return fut

    def wait_first(self, pending: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        done, not_done = cf.wait(set(pending), return_when=cf.FIRST_COMPLETED)
        return set(done), set(not_done)


def _ping(_: int = 0) -> int:
    return os.getpid()


class ProcessExecutor(StudyExecutor):
    """Local worker processes; records shared through memory-mapped ``.npy`` files.

    Parameters
    ----------
    workers : int
        Number of processes (>= 1).
    """

    def __init__(self, workers: int) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise DataValidationError("workers", f"expected a positive integer, got {workers!r}")
        methods = multiprocessing.get_all_start_methods()
        ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        self._pool = cf.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=ctx,
            initializer=init_worker,
            initargs=(os.getpid(), kinds.added()),
        )
        # start the workers now, before any progress-display thread exists in this process
        list(self._pool.map(_ping, range(workers)))
        self._dir = Path(tempfile.mkdtemp(prefix="mrdamper-study-"))
        self._count = 0
        self.workers = workers
        self.description = f"{workers} local process{'es' if workers > 1 else ''}"

    def share(self, e: Experiment | RecordSource) -> DiskRecord | RecordSource:
        if isinstance(e, RecordSource):
            return e
        self._count += 1
        paths = {}
        for c in e.channel_names:
            p = self._dir / f"r{self._count:05d}_{c}.npy"
            np.save(p, np.asarray(getattr(e, c)))
            paths[c] = str(p)
        return DiskRecord(e.name, dict(e.metadata), paths)

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future[Any]:
        return self._pool.submit(fn, *args)

    def wait_first(self, pending: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        done, not_done = cf.wait(set(pending), return_when=cf.FIRST_COMPLETED)
        return set(done), set(not_done)

    def close(self, cancel: bool = False) -> None:
        if cancel:
            # interrupted: drop queued tasks and stop running ones instead of waiting for them
            # (ProcessPoolExecutor has no public way to stop a running task)
            stop_pool(self._pool)
        else:
            self._pool.shutdown(wait=True)
        shutil.rmtree(self._dir, ignore_errors=True)


class DaskExecutor(StudyExecutor):
    """Tasks on a ``dask.distributed`` cluster.

    Parameters
    ----------
    scheduler : str or distributed.Client
        Scheduler address (``"tcp://host:8786"``) or an existing client (not closed by
        :meth:`close`).
    """

    def __init__(self, scheduler: Any) -> None:
        try:
            import distributed
        except ImportError:  # pragma: no cover - depends on the installation
            raise ImportError(
                "a Dask scheduler was given but dask.distributed is not installed; "
                "install the 'distributed' extra: pip install 'mrdamper[distributed]'"
            ) from None
        # dask.distributed has no type hints: its objects are handled as Any here
        self._distributed: Any = distributed
        client_type: Any = distributed.Client
        self._client: Any
        if isinstance(scheduler, client_type):
            self._client = scheduler
            self._own = False
        elif isinstance(scheduler, str) and scheduler:
            self._client = client_type(check_scheduler_address(scheduler))
            self._own = True
        else:
            raise DataValidationError(
                "scheduler", f"expected an address string or a Client, got {scheduler!r}"
            )
        self.description = f"Dask scheduler {self._client.scheduler.address}"
        self._ship = False

    def prepare(self, records: Iterable[Experiment | RecordSource]) -> None:
        """Check once that every worker can read the record files; if one cannot, the records
        are read here and sent to the workers instead (with a note saying so)."""
        paths = sorted({_absolute(e).file.path for e in records if isinstance(e, RecordSource)})
        if not paths:
            return
        answers: dict[str, list[str]] = self._client.run(unreadable, paths)
        blind = {w: bad for w, bad in answers.items() if bad}
        if not answers or blind:
            self._ship = True
            worker, bad = next(iter(blind.items())) if blind else ("", paths)
            where = f"worker {worker}" if worker else "no worker is connected and"
            warn_user(
                f"{where} cannot read {len(bad)} of the {len(paths)} record files (e.g. "
                f"{bad[0]}): the records are read here and sent to the workers; to let the "
                "workers read them, give them the same files at the same absolute paths",
                Note,
            )

    def share(self, e: Experiment | RecordSource) -> Any:
        if isinstance(e, RecordSource):
            if not self._ship:
                return _absolute(e)  # the workers resolve no path against their own folder
            e = e.load()
        return self._client.scatter(pack(e), hash=False)

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        return self._client.submit(fn, *args, pure=False)

    def wait_first(self, pending: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        res = self._distributed.wait(list(pending), return_when="FIRST_COMPLETED")
        return set(res.done), set(res.not_done)

    def close(self, cancel: bool = False) -> None:
        if self._own:
            self._client.close()


def _absolute(e: RecordSource) -> RecordSource:
    """``e`` with an absolute file path (relative to this process's working folder)."""
    path = os.path.abspath(e.file.path)
    if path == e.file.path:
        return e
    return dataclasses.replace(e, file=dataclasses.replace(e.file, path=path))


def unreadable(paths: list[str]) -> list[str]:
    """The ``paths`` this process cannot open for reading (run on each Dask worker).

    Parameters
    ----------
    paths : list of str
        Absolute file paths.

    Returns
    -------
    list of str
    """
    bad = []
    for p in paths:
        try:
            with open(p, "rb") as fh:
                fh.read(1)
        except OSError:
            bad.append(p)
    return bad


def make_executor(workers: int | None = None, scheduler: Any = None) -> StudyExecutor:
    """Pick the executor: Dask when ``scheduler`` is given, else processes, or in-process for 1.

    Parameters
    ----------
    workers : int, optional
        Local processes; default :func:`default_workers`. ``1`` runs in the calling process.
    scheduler : str or distributed.Client, optional
        Dask scheduler address or client; overrides ``workers``.
    """
    if scheduler is not None:
        return DaskExecutor(scheduler)
    n = default_workers() if workers is None else workers
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise DataValidationError("workers", f"expected a positive integer, got {workers!r}")
    return SerialExecutor() if n == 1 else ProcessExecutor(n)


def compile_kernels(ex: StudyExecutor, kinds: Sequence[str]) -> None:
    """Compile the kernels the models need before the first fit, each once on the machine, in
    parallel: every local worker (and a background compilation the command started, see
    :func:`mrdamper.compiled.compile_ahead`) takes whole kernel modules not cached yet. The fits
    then load them from numba's cache. Nothing to do with one worker and no background
    compilation, or when every kernel is cached."""
    from mrdamper import compiled

    claim_dir = compiled.claim_folder()
    workers = ex.workers if isinstance(ex, ProcessExecutor) else 1
    parallel = workers > 1
    if claim_dir is None and not parallel:
        return
    own = claim_dir is None
    claim_dir = claim_dir or tempfile.mkdtemp(prefix="mrdamper-kernels-")
    try:
        if parallel:
            futures = [
                ex.submit(compiled.compile_claimed, list(kinds), claim_dir) for _ in range(workers)
            ]
            for fut in futures:
                fut.exception()  # wait; a kernel that failed here compiles at first use
        else:
            compiled.compile_claimed(list(kinds), claim_dir)
    finally:
        compiled.finish_ahead()
        if own:
            shutil.rmtree(claim_dir, ignore_errors=True)


def loops_ahead() -> Any | None:
    """Start compiling the quarter-car loops (:func:`mrdamper.control.loop.ahead.compile_loops`)
    in a background process (forked where the platform can), now, and return it.

    For a study with the control-relevance step and local workers: the loops compile once on
    the machine while the fits run, instead of once in every worker that runs the step (they
    are cached on disk; join the process before the step). None, and nothing started, when they
    are cached already (:func:`mrdamper.control.loop.ahead.loops_cached`).
    """
    from mrdamper.control.loop.ahead import compile_loops, loops_cached

    if loops_cached():
        return None
    methods = multiprocessing.get_all_start_methods()
    ctx: Any = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    proc = ctx.Process(target=compile_loops, daemon=True)
    proc.start()
    return proc
