"""The manifest of a folder of records written by ``mrdamper rig doe``: format and parsing.

A manifest (``manifest.csv``) lists one record per row: its name, design-of-experiments metadata,
sample count and file. Writing it is :func:`mrdamper.rig.doe_io.write_records`; reading it lives
here, beside the other readers, so that every reader of folders (the command line, the study)
recognises such a folder the same way without depending on the virtual rig.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

from mrdamper.errors import DataValidationError

__all__ = [
    "MANIFEST_COLUMNS",
    "MANIFEST_NAME",
    "OPTIONAL_COLUMNS",
    "is_doe_folder",
    "manifest_rows",
]

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

#: Columns a manifest may have beyond :data:`MANIFEST_COLUMNS` (older manifests lack them): the
#: damper's model kind and which damper it was (a shipped reference damper's name, or
#: ``"custom"``), so a study of the folder knows the truth behind the records.
OPTIONAL_COLUMNS: tuple[str, ...] = ("damper", "reference_damper")

#: Columns left empty by records outside Table II (the control extension has no experiment,
#: replicate or band): an empty cell is left out of the record's metadata.
_MAY_BE_EMPTY: tuple[str, ...] = ("experiment", "replicate", "max_frequency")
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
    """True when ``folder`` holds a manifest with every manifest column.

    The one test of "this folder came from ``mrdamper rig doe``" that every reader of folders
    uses; a folder with some other ``manifest.csv`` is read as ordinary records.

    Parameters
    ----------
    folder : path-like
        A folder.

    Returns
    -------
    bool
    """
    manifest = Path(folder) / MANIFEST_NAME
    if not manifest.is_file():
        return False
    with manifest.open(newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh), [])
    return all(c in header for c in MANIFEST_COLUMNS)


def manifest_rows(folder: str | os.PathLike[str]) -> list[tuple[Path, str, dict[str, Any], int]]:
    """The records a manifest lists, checked, without reading them.

    Parameters
    ----------
    folder : path-like
        The output folder of a DoE run.

    Returns
    -------
    list of (Path, str, dict, int)
        ``(file, record name, metadata, samples)`` in manifest order; the metadata holds
        ``experiment``, ``replicate``, ``pattern``, ``displacement``, ``duration`` [s],
        ``max_frequency`` [Hz], ``seed``, ``source="virtual rig"`` and, when the manifest has
        them (:data:`OPTIONAL_COLUMNS`), ``damper`` and ``reference_damper``; a record of the
        control extension has no ``experiment``, ``replicate`` or ``max_frequency`` (empty
        cells).

    Raises
    ------
    FileNotFoundError
        If the folder has no ``manifest.csv`` or a listed file is missing.
    DataValidationError
        If the manifest lacks a column or a cell has the wrong type.
    """
    root = Path(folder)
    manifest = root / MANIFEST_NAME
    if not manifest.is_file():
        raise FileNotFoundError(f"{manifest}: no DoE manifest (write one with mrdamper rig doe)")
    with manifest.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    missing = [c for c in MANIFEST_COLUMNS if rows and c not in rows[0]]
    if missing:
        raise DataValidationError("manifest", f"{manifest}: missing column(s) {missing}")
    out = []
    for k, row in enumerate(rows):
        meta: dict[str, Any] = {"source": "virtual rig"}
        for col, typ in _MANIFEST_TYPES.items():
            if col in _MAY_BE_EMPTY and row[col] == "":
                continue
            try:
                meta[col] = typ(row[col])
            except ValueError:
                raise DataValidationError(
                    col, f"{manifest} row {k + 1}: {row[col]!r} is not a valid {typ.__name__}"
                ) from None
        for col in OPTIONAL_COLUMNS:
            if row.get(col):
                meta[col] = row[col]
        samples = int(meta.pop("samples"))
        path = root / row["file"]
        if not path.is_file():
            raise FileNotFoundError(f"{path}: listed in {manifest} but missing")
        out.append((path, row["name"], meta, samples))
    return out
