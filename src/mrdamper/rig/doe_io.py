"""Writing a generated design of experiments to disk: one CSV per record plus a manifest."""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal

from mrdamper._io import atomic_write_text, check_output, write_folder
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.readers.manifest import (
    MANIFEST_COLUMNS,
    MANIFEST_NAME,
    OPTIONAL_COLUMNS,
    is_doe_folder,
    manifest_rows,
)
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel

__all__ = [
    "MANIFEST_COLUMNS",
    "MANIFEST_NAME",
    "RECORD_FORMATS",
    "is_doe_folder",
    "read_doe",
    "write_doe",
    "write_records",
]

RecordFormat = Literal["csv", "parquet"]
#: Record file formats :func:`write_records` writes.
RECORD_FORMATS: tuple[str, ...] = ("csv", "parquet")


def _write_csv(record: Experiment, path: Path, force: bool) -> None:
    from mrdamper.data.writers import write_csv

    write_csv(record, path, force=force)


def _check_out_dir(out_dir: Path, force: bool) -> None:
    """Refuse an unsafe or occupied output folder (see :func:`mrdamper._io.check_output`)."""
    check_output(out_dir, force=force, folder=True)


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return repr(value)
    return "" if value is None else str(value)


def write_records(
    records: ExperimentSet,
    out_dir: str | os.PathLike[str],
    *,
    force: bool = False,
    format: RecordFormat = "csv",
    progress: Callable[[Path], None] | None = None,
) -> Path:
    """Write every record as ``<name>.csv`` (SI columns) and ``manifest.csv`` into ``out_dir``.

    Parameters
    ----------
    records : ExperimentSet
        Records with DoE metadata (missing keys leave empty manifest cells).
    out_dir : path-like
        Output folder; created if missing.
    force : bool
        Write into an existing, non-empty folder (overwriting files of the same name).
    format : {"csv", "parquet"}
        Record file format (``<name>.csv`` or ``<name>.parquet``; Parquet needs pyarrow and
        keeps name and metadata in the file).
    progress : callable, optional
        Called with the path of each record file once it is written.

    Returns
    -------
    Path
        The manifest file.

    Raises
    ------
    OutputExistsError
        If ``out_dir`` is a non-empty folder (or a file) and ``force`` is false.
    """
    if format not in RECORD_FORMATS:
        raise DataValidationError(
            "format", f"expected one of {list(RECORD_FORMATS)}, got {format!r}"
        )
    out = Path(out_dir)
    _check_out_dir(out, force)

    def build(tmp: Path) -> None:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        columns = (*MANIFEST_COLUMNS, *OPTIONAL_COLUMNS)
        w.writerow(columns)
        for rec in records:
            file = f"{rec.name}.{format}"
            if format == "parquet":
                from mrdamper.data.writers import write_parquet

                write_parquet(rec, tmp / file)
            else:
                _write_csv(rec, tmp / file, False)
            if progress is not None:
                progress(tmp / file)
            meta = dict(rec.metadata)
            row = {**meta, "name": rec.name, "samples": rec.n, "file": file}
            w.writerow([_cell(row.get(c)) for c in columns])
        atomic_write_text(tmp / MANIFEST_NAME, buf.getvalue())

    # built in a private sibling folder, then moved into place (with force: merged into the
    # existing folder), so a failure leaves neither partial files nor an empty folder
    write_folder(out, build, force=force, mode="merge")
    return out / MANIFEST_NAME


def write_doe(
    out_dir: str | os.PathLike[str],
    seed: int = 0,
    scale: float = 1.0,
    fs: float = 1000.0,
    force: bool = False,
    damper: FittedModel | None = None,
) -> Path:
    """Generate the Table II DoE (:func:`~mrdamper.rig.doe.table_ii`) and write it to ``out_dir``.

    One CSV per record (columns ``t, x, v, i, F`` in SI units, written atomically by
    :func:`mrdamper.data.writers.write_csv`) and ``manifest.csv`` (name, experiment, replicate,
    pattern, displacement, duration [s], max_frequency [Hz], samples, seed, file). The same
    arguments give byte-identical files.

    Parameters
    ----------
    out_dir : path-like
        Output folder; must be absent or empty unless ``force``.
    seed : int
        Root seed.
    scale : float
        Duration factor.
    fs : float
        Sampling rate [Hz].
    force : bool
        Write into a non-empty folder, overwriting files of the same name.
    damper : FittedModel, optional
        Damper under test (default: the shipped reference damper).

    Returns
    -------
    Path
        The manifest file.
    """
    from mrdamper.rig.doe import table_ii

    _check_out_dir(Path(out_dir), force)  # fail before the (long) generation
    records = table_ii(seed=seed, scale=scale, fs=fs, damper=damper)
    return write_records(records, out_dir, force=force)


def read_doe(folder: str | os.PathLike[str]) -> ExperimentSet:
    """Read a folder written by :func:`write_doe` / ``mrdamper rig doe`` back into an ExperimentSet.

    The manifest gives the record files, names and metadata (``experiment``, ``replicate``,
    ``pattern``, ``displacement``, ``duration``, ``max_frequency``, ``seed``;
    ``source="virtual rig"``; :func:`mrdamper.data.readers.manifest.manifest_rows`). Every
    reader of folders (:func:`mrdamper.data.readers.read_records`) reads such a folder this way.

    Parameters
    ----------
    folder : path-like
        The output folder of a DoE run.

    Returns
    -------
    ExperimentSet
        Records in manifest order.

    Raises
    ------
    FileNotFoundError
        If the folder has no ``manifest.csv`` or a listed file is missing.
    DataValidationError
        If the manifest lacks a column, a cell has the wrong type, or a record's sample count
        differs from the manifest.
    """
    from mrdamper.data.readers import RecordFile

    rows = manifest_rows(folder)  # raises for a missing manifest, column, cell type or file
    files = [RecordFile(str(f), name, meta, {}, samples) for f, name, meta, samples in rows]
    return ExperimentSet([f.read() for f in files], name=Path(folder).name)
