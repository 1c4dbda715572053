"""Read a delimited text file (CSV, TSV, semicolon or blank separated) into an Experiment."""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping
from typing import Any

import pandas as pd

from mrdamper.data.experiment import DEFAULT_TIME_TOLERANCE, Experiment, NanPolicy
from mrdamper.data.readers._build import build_experiment, existing_file
from mrdamper.errors import DataValidationError, interrupt_in_chain

__all__ = ["read_csv", "sniff_delimiter"]

_CANDIDATES = ",;\t| "


def sniff_delimiter(sample: str) -> str:
    """Return the delimiter of a delimited-text sample (``","``, ``";"``, tab, ``"|"``, blanks).

    Blank-separated files (one or more spaces or tabs) return the regular expression
    ``r"\\s+"``.

    Raises
    ------
    DataValidationError
        If no consistent delimiter is found.
    """
    lines = [ln for ln in sample.splitlines() if ln.strip()][:50]
    if not lines:
        raise DataValidationError("file", "is empty; expected a header row and data rows")
    if len(lines) == 1:
        # Header only: pick the candidate that splits it.
        for d in _CANDIDATES[:-1]:
            if d in lines[0]:
                return d
        return r"\s+"
    try:
        d = csv.Sniffer().sniff("\n".join(lines), delimiters=_CANDIDATES).delimiter
    except csv.Error:
        d = ""
    if d == " " or not d:
        counts = {len(ln.split()) for ln in lines}
        if len(counts) == 1 and counts.pop() > 1:
            return r"\s+"
        if not d:
            raise DataValidationError(
                "sep", "could not detect the column delimiter; pass sep= (e.g. sep=';')"
            )
    return d


def read_csv(
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
    sep: str | None = None,
    decimal: str = ".",
    comment: str | None = "#",
) -> Experiment:
    """Read one record from a delimited text file with a header row.

    Columns are matched to the standard channels ``t, x, v, F, i, voltage`` by ``columns`` or by
    the alias table :data:`~mrdamper.data.readers.COLUMN_ALIASES`; each is converted once to SI
    from its unit (``units=``, or a bracketed unit in its header such as ``"x [mm]"``, else SI).

    Parameters
    ----------
    path : path-like
        The file.
    columns : mapping, optional
        ``{header: channel}``, e.g. ``{"Force_kN": "F"}``.
    units : mapping, optional
        ``{channel or header: unit}``, e.g. ``{"F": "kN", "x": "mm"}``; see
        :data:`mrdamper.data.units.UNITS`.
    nan_policy : {"raise", "drop-edges", "interpolate"}
        What to do with empty or NaN cells; see :meth:`Experiment.from_arrays`.
    max_gap : int
        Longest run of missing samples that ``"interpolate"`` fills [samples].
    resample_fs : float, optional
        Linearly interpolate onto a uniform grid at this rate [Hz] (for jittered time).
    fs : float, optional
        Declared sampling rate [Hz]: time is regenerated as ``t0 + k / fs`` after checking that
        the file's time column (if any) agrees within half a sample interval. Use it for files
        whose time column is rounded. Without a time column, ``t = k / fs``.
    derive_velocity : bool or float
        If the file has no velocity column: ``True`` derives it from x with
        :func:`~mrdamper.data.preprocessing.velocity_from_displacement` (cut-off estimated), a
        number gives the cut-off [Hz]. ``False`` (default) raises instead.
    name : str, optional
        Record name (default: the file stem).
    metadata : mapping, optional
        Extra metadata, added to the provenance (``source``, ``columns``, ``units``).
    time_tolerance : float
        Relative tolerance on the sampling interval [-]; see :class:`Experiment`.
    plausible_max : mapping, optional
        Overrides of the plausibility bounds (``stroke`` [m], ``v`` [m/s], ``F`` [N], ``i`` [A],
        ``voltage`` [V]); values beyond them give a :class:`~mrdamper.errors.PlausibilityWarning`
        (see :mod:`mrdamper.data.plausibility`).
    sep : str, optional
        Column delimiter; detected from the first lines when omitted.
    decimal : str
        Decimal mark (``","`` for files written with a decimal comma).
    comment : str or None
        Lines starting with this character are ignored.

    Returns
    -------
    Experiment
        The record in SI units; ``metadata`` holds ``source`` (path), ``columns`` (channel ->
        header) and ``units`` (channel -> unit in the file).

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    DataValidationError
        Empty file, no data rows, missing or ambiguous column, duplicated header, non-numeric
        value, NaN (under ``nan_policy="raise"``), non-uniform time; the message names the field.
    UnitError
        Unknown unit or unit of the wrong quantity for its column.

    Examples
    --------
    >>> from mrdamper.data.readers import read_csv
    >>> e = read_csv(  # doctest: +SKIP
    ...     "rig.csv", columns={"Force_kN": "F"}, units={"F": "kN", "x": "mm"}
    ... )
    """
    p = existing_file(path)
    if p.is_dir():
        raise DataValidationError("path", f"{p} is a directory; use read_directory")
    with p.open("r", encoding="utf-8-sig", errors="replace") as fh:
        sample = fh.read(65536)
    body = "\n".join(
        ln for ln in sample.splitlines() if not (comment and ln.lstrip().startswith(comment))
    )
    if not body.strip():
        raise DataValidationError("file", f"{p} is empty; expected a header row and data rows")
    delim = sep if sep is not None else sniff_delimiter(body)
    try:
        df = pd.read_csv(
            p,
            sep=delim,
            decimal=decimal,
            comment=comment,
            encoding="utf-8-sig",
            skipinitialspace=True,
            engine="c" if len(delim) == 1 or delim == r"\s+" else "python",
        )
    except pd.errors.EmptyDataError:
        raise DataValidationError(
            "file", f"{p} is empty; expected a header row and data rows"
        ) from None
    except pd.errors.ParserError as exc:
        if interrupt_in_chain(exc):  # Ctrl-C while parsing: not a fault of the file
            raise KeyboardInterrupt from exc
        raise DataValidationError(
            "file", f"{p} could not be parsed with sep={delim!r}: {exc}"
        ) from None
    headers = _raw_headers(body, delim)
    if headers is not None and len(headers) != len(set(headers)):
        dup = next(h for h in headers if headers.count(h) > 1)
        raise DataValidationError(dup, f"column name appears more than once in {p}")
    raw = {str(c).strip(): df[c].to_numpy() for c in df.columns}
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
        name=name,
        metadata=metadata,
        time_tolerance=time_tolerance,
        plausible_max=plausible_max,
    )


def _raw_headers(body: str, delim: str) -> list[str] | None:
    first = next((ln for ln in body.splitlines() if ln.strip()), None)
    if first is None:
        return None
    if delim == r"\s+":
        return first.split()
    if len(delim) != 1:
        return None
    return [h.strip() for h in next(csv.reader([first], delimiter=delim))]
