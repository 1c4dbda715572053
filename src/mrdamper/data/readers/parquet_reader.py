"""Read a Parquet file (one record per file) into an Experiment; needs ``pyarrow``."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mrdamper.data.experiment import DEFAULT_TIME_TOLERANCE, Experiment, NanPolicy
from mrdamper.data.readers._build import build_experiment, existing_file
from mrdamper.data.readers._columns import resolve_columns
from mrdamper.errors import DataValidationError, MrDamperError

__all__ = ["PARQUET_METADATA_KEY", "read_parquet"]

#: Key of the file-level key/value metadata where :func:`~mrdamper.data.write_parquet` stores
#: the record name and JSON-safe metadata.
PARQUET_METADATA_KEY = b"mrdamper"


def _pyarrow() -> Any:
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise MrDamperError(
            "parquet: reading and writing Parquet needs pyarrow; install the 'parquet' extra "
            "(pip install 'mrdamper[parquet]')"
        ) from None
    return pq


def read_parquet(
    path: str | os.PathLike[str],
    *,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    nan_policy: NanPolicy = "raise",
    max_gap: int = 5,
    resample_fs: float | None = None,
    fs: float | None = None,
    derive_velocity: bool | float = False,
    name: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    time_tolerance: float = DEFAULT_TIME_TOLERANCE,
    plausible_max: Mapping[str, float] | None = None,
) -> Experiment:
    """Read one record from a Parquet file.

    Column matching, units and repair policies are those of
    :func:`~mrdamper.data.readers.read_csv`. Files written by
    :func:`~mrdamper.data.write_parquet` also restore the record name and metadata stored in
    them (arguments given here take precedence).

    Parameters
    ----------
    path : path-like
        The file.
    columns, units, nan_policy, max_gap, resample_fs, fs, derive_velocity, name, metadata
        See :func:`~mrdamper.data.readers.read_csv`.
    time_tolerance, plausible_max
        See :func:`~mrdamper.data.readers.read_csv`.

    Returns
    -------
    Experiment
        The record in SI units, with provenance in ``metadata``.

    Raises
    ------
    FileNotFoundError, DataValidationError, UnitError
        As for :func:`~mrdamper.data.readers.read_csv`; a file that is not Parquet raises
        :class:`DataValidationError` for field ``"file"``.
    MrDamperError
        If pyarrow is not installed.
    """
    p = existing_file(path)
    pq = _pyarrow()
    try:
        file = pq.ParquetFile(p)
    except Exception as exc:  # noqa: BLE001 - pyarrow raises ArrowInvalid / OSError for non-Parquet input
        raise DataValidationError("file", f"{p} could not be read as Parquet: {exc}") from None
    with file:
        schema = file.schema_arrow
        stored, stored_name = _stored_metadata(schema.metadata or {}, p)
        headers = [str(c) for c in schema.names]
        specs = resolve_columns(headers, columns=columns, units=units, source=str(p))
        raw = _read_columns(file, [spec.source for spec in specs.values()], p)
    return build_experiment(
        raw,
        path=p,
        columns=columns,
        units=units,
        nan_policy=nan_policy,
        max_gap=max_gap,
        resample_fs=resample_fs,
        fs=fs,
        derive_velocity=derive_velocity,
        name=name if name is not None else stored_name,
        metadata=metadata,
        time_tolerance=time_tolerance,
        plausible_max=plausible_max,
        stored_metadata=stored,
        headers=headers,
    )


def _stored_metadata(kv: Mapping[bytes, bytes], p: Path) -> tuple[dict[str, Any], str | None]:
    """The record name and metadata that :func:`~mrdamper.data.write_parquet` stored in ``p``."""
    if PARQUET_METADATA_KEY not in kv:
        return {}, None
    try:
        info = json.loads(kv[PARQUET_METADATA_KEY].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataValidationError(
            "file", f"{p}: stored mrdamper metadata is not JSON ({exc})"
        ) from None
    stored = dict(info.get("metadata", {}))
    for key in ("source", "columns", "units", "ignored_columns"):
        stored.pop(key, None)  # provenance of the original file; this file is the source now
    for key in ("repairs", "processing"):  # tuples in memory, lists in JSON
        if isinstance(stored.get(key), list):
            stored[key] = tuple(stored[key])
    return stored, info.get("name")


def _read_columns(file: Any, names: list[str], p: Path) -> dict[str, Any]:
    """Read the columns ``names`` of an open ``pyarrow.parquet.ParquetFile``, row group by row
    group.

    Integer and floating-point columns are written straight into one float64 array each (nulls
    become NaN), so reading costs the columns themselves and one row group in transit, not the
    whole table plus its copies; other types are read whole and left to
    :func:`~mrdamper.data.readers._build.numeric_column` to refuse or convert.
    """
    import pyarrow as pa

    schema = file.schema_arrow
    n = int(file.metadata.num_rows)
    raw: dict[str, Any] = {}
    numeric: list[str] = []
    try:
        for name in dict.fromkeys(names):
            kind = schema.field(name).type
            if pa.types.is_integer(kind) or pa.types.is_floating(kind):
                raw[name] = np.empty(n, dtype=np.float64)
                numeric.append(name)
            else:
                raw[name] = file.read(columns=[name]).column(name).to_numpy(zero_copy_only=False)
        start = 0
        for group in range(file.num_row_groups if numeric else 0):
            part = file.read_row_group(group, columns=numeric)
            stop = start + part.num_rows
            for name in numeric:
                raw[name][start:stop] = part.column(name).to_numpy(zero_copy_only=False)
            start = stop
    except Exception as exc:  # noqa: BLE001 - pyarrow raises ArrowInvalid / OSError for broken files
        raise DataValidationError("file", f"{p} could not be read as Parquet: {exc}") from None
    if numeric and start != n:
        raise DataValidationError(
            "file", f"{p}: its row groups hold {start} rows but its footer says {n}"
        )
    return raw
