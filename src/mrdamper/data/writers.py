"""Write records to CSV or Parquet: atomic, never overwriting without ``force``.

Channels are written in SI with plain headers (``t,x,v,i,F``, the layout every reader accepts)
unless ``units=`` asks for other units; such columns get the unit in their header
(``x [mm]``), so the readers convert them back without being told. CSV values are written with
the shortest text that reads back to the same float64, so an SI round trip is exact.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from mrdamper._io import atomic_write_with
from mrdamper.data.experiment import Experiment
from mrdamper.data.units import CHANNEL_QUANTITY, SI_UNIT, canonical_unit, from_si
from mrdamper.errors import UnitError

__all__ = ["to_unit_frame", "write_csv", "write_parquet"]


def to_unit_frame(experiment: Experiment, units: Mapping[str, str] | None = None) -> pd.DataFrame:
    """Return the channels as a DataFrame, converted to ``units`` where given.

    Parameters
    ----------
    experiment : Experiment
        The record.
    units : mapping, optional
        ``{channel: unit}``, e.g. ``{"x": "mm", "F": "kN"}``; other channels stay SI.

    Returns
    -------
    DataFrame
        Column ``c`` for an SI channel, ``"c [unit]"`` for a converted one.

    Raises
    ------
    UnitError
        If a key is not a channel of the record or a unit is unknown / of the wrong quantity.
    """
    units = dict(units or {})
    for ch in units:
        if ch not in CHANNEL_QUANTITY or getattr(experiment, ch) is None:
            raise UnitError(
                ch,
                f"units given for {ch!r}, which is not a channel of record {experiment.name!r} "
                f"(channels: {list(experiment.channel_names)})",
            )
    cols: dict[str, np.ndarray] = {}
    for ch in experiment.channel_names:
        values = getattr(experiment, ch)
        if ch in units:
            unit = canonical_unit(units[ch], column=ch)
            if unit != SI_UNIT[CHANNEL_QUANTITY[ch]]:
                cols[f"{ch} [{unit}]"] = from_si(values, unit, channel=ch)
                continue
        cols[ch] = np.array(values)
    return pd.DataFrame(cols)


def write_csv(
    experiment: Experiment,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    units: Mapping[str, str] | None = None,
    sep: str = ",",
) -> Path:
    """Write one record as delimited text with a header row.

    Parameters
    ----------
    experiment : Experiment
        The record.
    path : path-like
        Output file (parent folders are created).
    force : bool
        Overwrite an existing file.
    units : mapping, optional
        ``{channel: unit}`` to write some channels in other units (header ``"x [mm]"``).
    sep : str
        Column delimiter.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``force`` is false.
    UnitError
        For an unknown unit or a unit of the wrong quantity.

    Examples
    --------
    >>> write_csv(e, "out/rec.csv", units={"x": "mm", "F": "kN"})  # doctest: +SKIP
    """
    frame = to_unit_frame(experiment, units)

    def writer(tmp: Path) -> None:
        frame.to_csv(tmp, sep=sep, index=False, lineterminator="\n")

    return atomic_write_with(path, writer, force=force)


def _json_safe(value: Any) -> Any:
    if isinstance(value, (str, bool)) or value is None:
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, Mapping):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_json_safe(v) for v in list(value)]
    return repr(value)


def write_parquet(
    experiment: Experiment,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    units: Mapping[str, str] | None = None,
) -> Path:
    """Write one record as a Parquet file (needs pyarrow).

    The record name and its metadata (made JSON-safe; other objects are stored as their
    ``repr``) go into the file's key/value metadata, so
    :func:`~mrdamper.data.readers.read_parquet` restores them.

    Parameters
    ----------
    experiment : Experiment
        The record.
    path : path-like
        Output file (parent folders are created).
    force : bool
        Overwrite an existing file.
    units : mapping, optional
        ``{channel: unit}``, as for :func:`write_csv`.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``force`` is false.
    UnitError
        For an unknown unit or a unit of the wrong quantity.
    MrDamperError
        If pyarrow is not installed.
    """
    from mrdamper.data.readers.parquet_reader import PARQUET_METADATA_KEY, _pyarrow

    pq = _pyarrow()
    import pyarrow as pa

    frame = to_unit_frame(experiment, units)
    table = pa.Table.from_pandas(frame, preserve_index=False)
    info = {"name": experiment.name, "metadata": _json_safe(dict(experiment.metadata))}
    meta = dict(table.schema.metadata or {})
    meta[PARQUET_METADATA_KEY] = json.dumps(info, sort_keys=True).encode("utf-8")
    table = table.replace_schema_metadata(meta)

    def writer(tmp: Path) -> None:
        pq.write_table(table, tmp)

    return atomic_write_with(path, writer, force=force)
