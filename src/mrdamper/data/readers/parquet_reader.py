"""Read a Parquet file (one record per file) into an Experiment; needs ``pyarrow``."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

from mrdamper.data.experiment import DEFAULT_TIME_TOLERANCE, Experiment, NanPolicy
from mrdamper.data.readers._build import build_experiment, existing_file
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
        table = pq.read_table(p)
    except Exception as exc:  # noqa: BLE001 - pyarrow raises ArrowInvalid / OSError for non-Parquet input
        raise DataValidationError("file", f"{p} could not be read as Parquet: {exc}") from None
    stored: dict[str, Any] = {}
    stored_name = None
    kv = table.schema.metadata or {}
    if PARQUET_METADATA_KEY in kv:
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
        stored_name = info.get("name")
    raw = {str(c): table.column(c).to_numpy(zero_copy_only=False) for c in table.column_names}
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
    )
