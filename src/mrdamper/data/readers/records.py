"""Records named by paths: the one way files and folders become records, read now or later.

:func:`record_files` decides, once for every command and for the study, what a list of paths
means: a file is one record; a folder written by ``mrdamper rig doe`` is read through its
manifest (:mod:`mrdamper.data.readers.manifest`); another folder with ``pattern`` takes the files
whose names match it (named groups become metadata); without a pattern, the sine-record pattern
(:data:`~mrdamper.data.readers.DEFAULT_PATTERN`) if any file name matches it, else every record
file (:data:`ANY_RECORD_FILE`).

:func:`read_records` reads them all. :func:`record_sources` reads each file once, one at a time,
keeps only its header (name, metadata, sample count, duration, channels) and returns
:class:`RecordSource` values that read the samples again where they are needed: the study sends
sources to its workers, so the process that plans a large campaign never holds all of its records.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, overload

from mrdamper.data.experiment import Experiment
from mrdamper.data.experiment_set import ExperimentSet
from mrdamper.data.readers._build import missing
from mrdamper.data.readers.directory import (
    DEFAULT_PATTERN,
    directory_files,
    parse_file_name,
    read_file,
)
from mrdamper.data.readers.manifest import is_doe_folder, manifest_rows
from mrdamper.errors import DataValidationError, interrupt_in_chain
from mrdamper.metrics import MIN_SCORED_SAMPLES
from mrdamper.progress import report

__all__ = [
    "ANY_RECORD_FILE",
    "RecordFile",
    "RecordSource",
    "SourceSet",
    "read_files",
    "read_records",
    "record_files",
    "record_sources",
]

#: Regex for any record file in a folder (used when the sine-record pattern matches nothing).
ANY_RECORD_FILE = r".*\.(csv|txt|tsv|dat|parquet|pq|mat)"


def _frozen(m: Mapping[str, Any] | None) -> Mapping[str, Any]:
    return MappingProxyType(dict(m or {}))


@dataclass(frozen=True)
class RecordFile:
    """One record file and how to read it.

    Attributes
    ----------
    path : str
        The file.
    name : str or None
        Record name given to the reader (None: the reader's default, the file stem).
    metadata : mapping
        Metadata given to the reader (it wins over metadata stored in the file).
    read_kw : mapping
        Reader options (see :func:`~mrdamper.data.readers.read_csv`).
    samples : int or None
        Sample count the record must have (from a manifest), or None.
    """

    path: str
    name: str | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)
    read_kw: Mapping[str, Any] = field(default_factory=dict)
    samples: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "metadata", _frozen(self.metadata))
        object.__setattr__(self, "read_kw", _frozen(self.read_kw))

    def __reduce__(self) -> tuple[Any, ...]:  # mapping proxies do not pickle
        args = (self.path, self.name, dict(self.metadata), dict(self.read_kw), self.samples)
        return (RecordFile, args)

    def read(self) -> Experiment:
        """Read the record.

        Returns
        -------
        Experiment

        Raises
        ------
        DataValidationError
            The file's sample count differs from ``samples``, or is below
            :data:`~mrdamper.metrics.MIN_SCORED_SAMPLES` (such a record can be neither fitted nor
            scored); errors of the reader, naming the file when they did not.
        """
        kw = dict(self.read_kw)
        if self.name is not None:
            kw["name"] = self.name
        if self.metadata:
            kw["metadata"] = dict(self.metadata)
        try:
            e = read_file(self.path, **kw)
        except DataValidationError as exc:
            if interrupt_in_chain(exc):  # Ctrl-C inside a parser: the file is not to blame
                raise KeyboardInterrupt from exc
            raise _naming_file(exc, self.path) from None
        if self.samples is not None and e.n != self.samples:
            raise DataValidationError(
                "samples", f"{self.path}: {e.n} samples, manifest says {self.samples}"
            )
        if e.n < MIN_SCORED_SAMPLES:
            raise DataValidationError(
                "samples",
                f"{self.path}: record has {e.n} sample(s); fitting and scoring need at least "
                f"{MIN_SCORED_SAMPLES}",
            )
        return e


def _naming_file(exc: DataValidationError, path: str) -> DataValidationError:
    """``exc`` itself when its message names the file ``path``, else the same error (same class
    and field) with the file named."""
    text = str(exc)
    if path in text or Path(path).name in text:
        return exc
    field = exc.field
    rest = text[len(field) + 2 :] if text.startswith(f"{field}: ") else text
    new = DataValidationError.__new__(type(exc))
    DataValidationError.__init__(new, field, f"{rest} (in {path})")
    return new


def _check_pattern(pattern: str) -> None:
    try:
        re.compile(pattern)
    except re.error as exc:
        raise DataValidationError(
            "pattern", f"{pattern!r} is not a valid regular expression ({exc})"
        ) from None


def record_files(
    paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    pattern: str | None = None,
    **read_kw: Any,
) -> list[RecordFile]:
    """The record files ``paths`` name, in order, without reading them (see the module docstring).

    Parameters
    ----------
    paths : path-like or sequence of path-like
        Record files and folders.
    pattern : str, optional
        File-name regex for folders (named groups become metadata).
    **read_kw
        Reader options for the files (not used for the SI files of a DoE manifest).

    Returns
    -------
    list of RecordFile

    Raises
    ------
    FileNotFoundError
        If a path does not exist.
    DataValidationError
        If ``pattern`` is not a valid regex or matches no file of a folder.
    """
    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    if pattern is not None:
        _check_pattern(pattern)
    out: list[RecordFile] = []
    for item in items:
        p = Path(item)
        if not p.exists():
            raise missing(p, "file or folder")
        if not p.is_dir():
            out.append(RecordFile(str(p), read_kw=read_kw))
            continue
        if pattern is None and is_doe_folder(p):  # SI files listed with their metadata
            out.extend(
                RecordFile(str(f), name, meta, {}, samples)
                for f, name, meta, samples in manifest_rows(p)
            )
            continue
        pat = pattern
        if pat is None:
            sine = any(parse_file_name(f.name, DEFAULT_PATTERN) for f in p.iterdir())
            pat = DEFAULT_PATTERN if sine else ANY_RECORD_FILE
        out.extend(
            RecordFile(str(f), name, meta, read_kw) for name, f, meta in directory_files(p, pat)
        )
    return out


def _set_name(paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]]) -> str:
    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    if len(items) != 1:
        return "records"
    p = Path(items[0])
    return p.name if p.is_dir() else p.stem


def read_records(
    paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    pattern: str | None = None,
    **read_kw: Any,
) -> ExperimentSet:
    """Read every record ``paths`` name (:func:`record_files`) into one set.

    Parameters
    ----------
    paths : path-like or sequence of path-like
        Record files and folders.
    pattern : str, optional
        File-name regex for folders (named groups become metadata).
    **read_kw
        Reader options.

    Returns
    -------
    ExperimentSet
        Named after the one path given (folder name or file stem), else ``"records"``.

    Notes
    -----
    Reports the stage ``"reading records"`` to :mod:`mrdamper.progress` before each file, with
    the number of files read so far and the number of files.
    """
    return ExperimentSet(read_files(record_files(paths, pattern, **read_kw)), name=_set_name(paths))


def read_files(files: Sequence[RecordFile]) -> list[Experiment]:
    """Read ``files`` in order, reporting the stage ``"reading records"`` to
    :mod:`mrdamper.progress` before each (files read so far, of all).

    Parameters
    ----------
    files : sequence of RecordFile
        As :func:`record_files` gives them.

    Returns
    -------
    list of Experiment
    """
    records = []
    for k, f in enumerate(files):
        report("reading records", k, len(files))
        records.append(f.read())
    return records


@dataclass(frozen=True)
class RecordSource:
    """A record known by its header, read from its file where it is used.

    Has the header of an :class:`~mrdamper.data.Experiment` (``name``, ``metadata``, ``n``,
    ``duration``, ``channel_names``) and :meth:`load` for the samples. Cheap to copy and to send
    to another process: a study's workers receive sources and read the records themselves.

    Attributes
    ----------
    file : RecordFile
        Where and how the record is read.
    name : str
        Record name.
    metadata : mapping
        Record metadata (as the reader gives it).
    n : int
        Number of samples (of the window, when one is set).
    duration : float
        First to last sample [s] (of the window).
    channel_names : tuple of str
        Channels present.
    window : (int, int or None)
        Samples ``start:stop`` of the file's record this source stands for.
    """

    file: RecordFile
    name: str
    metadata: Mapping[str, Any]
    n: int
    duration: float
    channel_names: tuple[str, ...]
    window: tuple[int, int | None] = (0, None)

    def __post_init__(self) -> None:
        object.__setattr__(self, "metadata", _frozen(self.metadata))

    def __reduce__(self) -> tuple[Any, ...]:  # mapping proxies do not pickle
        args = (
            self.file,
            self.name,
            dict(self.metadata),
            self.n,
            self.duration,
            self.channel_names,
            self.window,
        )
        return (RecordSource, args)

    @classmethod
    def of(cls, file: RecordFile) -> RecordSource:
        """Read ``file`` once and keep its header only.

        Parameters
        ----------
        file : RecordFile
            The record file.

        Returns
        -------
        RecordSource
        """
        e = file.read()
        return cls(file, e.name, e.metadata, e.n, e.duration, e.channel_names)

    def load(self) -> Experiment:
        """Read the record (its window) from the file.

        Returns
        -------
        Experiment

        Raises
        ------
        DataValidationError
            The file no longer has the samples this source was planned with.
        """
        e = self.file.read()
        start, stop = self.window
        if (start, stop) != (0, None):
            e = e.slice(start, stop, name=self.name)
        if e.n != self.n:
            raise DataValidationError(
                "samples", f"{self.file.path}: {e.n} samples, {self.n} when the study was planned"
            )
        return e

    def slice(self, start: int, stop: int | None = None, name: str | None = None) -> RecordSource:
        """The source of samples ``start:stop`` (as :meth:`Experiment.slice`).

        The record is read once to measure the duration of the window (the times as stored).

        Parameters
        ----------
        start, stop : int
            Sample window, relative to this source.
        name : str, optional
            Name of the window (default: this name).

        Returns
        -------
        RecordSource
        """
        part = self.load().slice(start, stop, name=name)
        base = self.window[0]
        stop_abs = None if stop is None else base + (stop if stop >= 0 else self.n + stop)
        return replace(
            self,
            name=part.name,
            n=part.n,
            duration=part.duration,
            window=(base + (start if start >= 0 else self.n + start), stop_abs),
        )


class SourceSet(Sequence[RecordSource]):
    """Ordered collection of uniquely named record sources (the lazy peer of ExperimentSet).

    Parameters
    ----------
    sources : iterable of RecordSource
        The sources; names must be unique.
    name : str
        Name of the set.
    """

    def __init__(self, sources: Iterable[RecordSource], name: str = "set") -> None:
        items = tuple(sources)
        seen: set[str] = set()
        for k, s in enumerate(items):
            if not isinstance(s, RecordSource):
                raise DataValidationError(
                    "sources", f"item {k} is {type(s).__name__}, expected RecordSource"
                )
            if s.name in seen:
                raise DataValidationError(
                    "name", f"duplicate record name {s.name!r} in set {name!r}"
                )
            seen.add(s.name)
        self._items = items
        self.name = name

    @overload
    def __getitem__(self, key: int) -> RecordSource: ...
    @overload
    def __getitem__(self, key: slice) -> SourceSet: ...
    def __getitem__(self, key: int | slice | str) -> Any:  # type: ignore[override]
        if isinstance(key, str):
            for s in self._items:
                if s.name == key:
                    return s
            raise KeyError(f"no record named {key!r} in set {self.name!r}")
        if isinstance(key, slice):
            return SourceSet(self._items[key], name=self.name)
        return self._items[key]

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self) -> Iterator[RecordSource]:
        return iter(self._items)

    @property
    def names(self) -> list[str]:
        """Record names in order."""
        return [s.name for s in self._items]

    def load(self) -> ExperimentSet:
        """Read every record (all in memory, as :func:`read_records` would).

        Returns
        -------
        ExperimentSet
        """
        return ExperimentSet([s.load() for s in self._items], name=self.name)


def record_sources(
    paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    pattern: str | None = None,
    **read_kw: Any,
) -> SourceSet:
    """Sources of every record ``paths`` name: each file is read once, one at a time, for its
    header; the samples are read again by :meth:`RecordSource.load` where they are used.

    Parameters
    ----------
    paths : path-like or sequence of path-like
        Record files and folders (as :func:`record_files`).
    pattern : str, optional
        File-name regex for folders.
    **read_kw
        Reader options.

    Returns
    -------
    SourceSet
        Named as :func:`read_records` names its set.
    """
    files = record_files(paths, pattern, **read_kw)
    return SourceSet([RecordSource.of(f) for f in files], name=_set_name(paths))
