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

#: File name of the manifest written beside the records.
MANIFEST_NAME = "manifest.csv"
#: Manifest columns, in order.
MANIFEST_COLUMNS: tuple[str, ...] = (
    "name",
    "experiment",
    "replicate",
    "pattern",
    "displacement",
    "duration",
    "max_frequency",
    "samples",
    "seed",
    "file",
)


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
        w.writerow(MANIFEST_COLUMNS)
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
            w.writerow([_cell(row.get(c)) for c in MANIFEST_COLUMNS])
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


_MANIFEST_TYPES: dict[str, type] = {
    "experiment": int,
    "replicate": int,
    "pattern": str,
    "displacement": str,
    "duration": float,
    "max_frequency": float,
    "samples": int,
    "seed": int,
}


def is_doe_folder(folder: str | os.PathLike[str]) -> bool:
    """True when ``folder`` holds a manifest written by :func:`write_records` (every manifest column).

    The one test of "this folder came from ``mrdamper rig doe``" that every reader of folders uses
    before :func:`read_doe`; a folder with some other ``manifest.csv`` is read as ordinary records.
    """
    manifest = Path(folder) / MANIFEST_NAME
    if not manifest.is_file():
        return False
    with manifest.open(newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh), [])
    return all(c in header for c in MANIFEST_COLUMNS)


def read_doe(folder: str | os.PathLike[str]) -> ExperimentSet:
    """Read a folder written by :func:`write_doe` / ``mrdamper rig doe`` back into an ExperimentSet.

    The manifest gives the record files, names and metadata (``experiment``, ``replicate``,
    ``pattern``, ``displacement``, ``duration``, ``max_frequency``, ``seed``;
    ``source="virtual rig"``); each CSV is read with :func:`mrdamper.data.readers.read_csv`.

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
    from mrdamper.data.readers import read_csv

    root = Path(folder)
    manifest = root / MANIFEST_NAME
    if not manifest.is_file():
        raise FileNotFoundError(f"{manifest}: no DoE manifest (write one with mrdamper rig doe)")
    with manifest.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    missing = [c for c in MANIFEST_COLUMNS if rows and c not in rows[0]]
    if missing:
        raise DataValidationError("manifest", f"{manifest}: missing column(s) {missing}")
    records = []
    for k, row in enumerate(rows):
        meta: dict[str, Any] = {"source": "virtual rig"}
        for col, typ in _MANIFEST_TYPES.items():
            try:
                meta[col] = typ(row[col])
            except ValueError:
                raise DataValidationError(
                    col, f"{manifest} row {k + 1}: {row[col]!r} is not a valid {typ.__name__}"
                ) from None
        samples = meta.pop("samples")
        path = root / row["file"]
        if not path.is_file():
            raise FileNotFoundError(f"{path}: listed in {manifest} but missing")
        if path.suffix.lower() == ".parquet":
            from mrdamper.data.readers import read_parquet

            rec = read_parquet(path, name=row["name"], metadata=meta)
        else:
            rec = read_csv(path, name=row["name"], metadata=meta)
        if rec.n != samples:
            raise DataValidationError(
                "samples", f"{path}: {rec.n} samples, manifest says {samples}"
            )
        records.append(rec)
    return ExperimentSet(records, name=root.name)
