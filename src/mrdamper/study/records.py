"""The records a study works on: in memory (:class:`~mrdamper.data.Experiment`) or read where
they are used (:class:`~mrdamper.data.RecordSource`).

Planning a study (selections, folds, roles, tables) needs only a record's header (name,
metadata, sample count, duration), which both kinds have. The samples are needed by the
force-velocity analysis and the figure records (read in the study's process, one at a time) and
by the fit and simulation tasks (read by the worker that runs them).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from typing import Any, Literal, overload

from mrdamper.data import (
    Experiment,
    ExperimentSet,
    RecordSource,
    SourceSet,
    read_records,
    record_sources,
)
from mrdamper.errors import DataValidationError

__all__ = [
    "LOAD_MODES",
    "Load",
    "Record",
    "Records",
    "as_list",
    "as_loaded",
    "load_all",
    "same_kind",
    "study_records",
]

#: Where a study reads records given as files: ``"worker"`` (each task reads what it uses; the
#: study's process keeps headers only) or ``"parent"`` (all read first, into memory).
Load = Literal["parent", "worker"]
LOAD_MODES: tuple[str, ...] = ("worker", "parent")

#: One record of a study: in memory or a source read where it is used.
Record = Experiment | RecordSource
#: The records of a study, all of one kind.
Records = ExperimentSet | SourceSet


@overload
def same_kind(like: ExperimentSet, items: Iterable[Experiment]) -> ExperimentSet: ...
@overload
def same_kind(like: SourceSet, items: Iterable[RecordSource]) -> SourceSet: ...
@overload
def same_kind(like: Records, items: Iterable[Record]) -> Records: ...
def same_kind(like: Records, items: Iterable[Record]) -> Records:
    """A set of the kind and name of ``like`` holding ``items``.

    Parameters
    ----------
    like : ExperimentSet or SourceSet
        The set whose kind and name are kept.
    items : iterable
        Records of that kind.

    Returns
    -------
    ExperimentSet or SourceSet
    """
    if isinstance(like, SourceSet):
        return SourceSet(items, name=like.name)  # type: ignore[arg-type]
    return ExperimentSet(items, name=like.name)  # type: ignore[arg-type]


def as_loaded(record: Record) -> Experiment:
    """The record itself, or a source read now.

    Parameters
    ----------
    record : Experiment or RecordSource
        A record of the study.

    Returns
    -------
    Experiment
    """
    return record.load() if isinstance(record, RecordSource) else record


def load_all(records: Records) -> ExperimentSet:
    """Every record in memory (for steps that need all samples at once, as the analysis).

    Parameters
    ----------
    records : ExperimentSet or SourceSet
        Records of the study.

    Returns
    -------
    ExperimentSet
    """
    if isinstance(records, SourceSet):
        return records.load()
    return records


def as_list(records: Records) -> list[Record]:
    """The records of a set as a list (one element type for either kind of set).

    Parameters
    ----------
    records : ExperimentSet or SourceSet
        Records of the study.

    Returns
    -------
    list of Experiment or RecordSource
    """
    return list(records)


def study_records(
    paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    pattern: str | None = None,
    *,
    load: Load = "worker",
    **read_kw: Any,
) -> Records:
    """The records of a study from files and folders, read now or where they are used.

    Folders are resolved by :func:`mrdamper.data.readers.record_files` (the same rule for every
    command). Both modes give the same study, byte for byte (a test checks it).

    Parameters
    ----------
    paths : path-like or sequence of path-like
        Record files and folders.
    pattern : str, optional
        File-name regex for folders (named groups become metadata).
    load : {"worker", "parent"}
        ``"worker"``: each file is read once here for its header (one at a time), then again by
        the tasks that use it (:class:`~mrdamper.data.SourceSet`); peak memory of this process
        stays near one record. ``"parent"``: every record is read into memory here
        (:class:`~mrdamper.data.ExperimentSet`) and shared with the workers.
    **read_kw
        Reader options.

    Returns
    -------
    ExperimentSet or SourceSet
    """
    if load == "worker":
        return record_sources(paths, pattern, **read_kw)
    if load == "parent":
        return read_records(paths, pattern, **read_kw)
    raise DataValidationError("load", f"expected one of {list(LOAD_MODES)}, got {load!r}")
