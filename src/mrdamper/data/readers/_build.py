"""Turn raw source columns into a validated :class:`~mrdamper.data.Experiment`.

Shared by every file reader: numeric checks, unit conversion (once, through
:mod:`mrdamper.data.units`), the declared-rate time base, velocity derivation and provenance.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.data.experiment import DEFAULT_TIME_TOLERANCE, Experiment, NanPolicy
from mrdamper.data.plausibility import check_plausibility
from mrdamper.data.readers._columns import COLUMN_ALIASES, ColumnSpec, resolve_columns
from mrdamper.data.units import si_factor
from mrdamper.errors import DataValidationError, Note

__all__ = [
    "JITTER_LIMIT",
    "ReadOptions",
    "build_experiment",
    "estimate_rate",
    "existing_file",
    "numeric_column",
]

#: Largest deviation of a time column from a straight line, in sample intervals, that is taken
#: as rounding of the printed time (rate estimated, time regenerated, with a note) rather than
#: irregular sampling (an error asking for ``fs=`` or ``resample_fs=``).
JITTER_LIMIT = 0.1

#: Keyword arguments every file reader accepts (documented in each reader).
ReadOptions = dict[str, Any]


def missing(p: Path, what: str = "file") -> FileNotFoundError:
    """The error for a path with nothing readable behind it (``what``: "file", "file or
    folder"): it says when the path is a broken symbolic link or a link loop."""
    if os.path.lexists(p):
        return FileNotFoundError(f"{p}: a broken symbolic link or a symbolic link loop")
    return FileNotFoundError(f"{p}: no such {what}")


def existing_file(path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as a Path; raise :class:`FileNotFoundError` if nothing is there."""
    p = Path(path)
    if not p.exists():
        raise missing(p)
    return p


def _owned_float64(values: Any) -> bool:
    """True for a writable 1-D float64 array that owns its memory (not a view of anything)."""
    return (
        isinstance(values, np.ndarray)
        and type(values) is np.ndarray
        and values.dtype == np.float64
        and values.ndim == 1
        and values.base is None
        and values.flags.writeable
        and values.flags.c_contiguous
    )


def numeric_column(name: str, values: Any, source: str) -> np.ndarray:
    """Return ``values`` as a new float64 array or raise naming the column and the first
    non-numeric entry.

    Missing entries (empty CSV fields, ``NaN``) stay NaN and are handled by ``nan_policy``.
    Booleans, complex numbers and text are refused. A writable 1-D float64 array that owns its
    memory (as the Parquet reader builds them) is taken over without a copy: readers hand their
    columns to :func:`build_experiment` and keep no reference to them.
    """
    if _owned_float64(values):
        return cast(np.ndarray, values)
    arr = np.asarray(values)
    if arr.dtype.kind in "iuf":
        return np.array(arr.ravel(), dtype=np.float64)  # a new array, not a view of one
    if arr.dtype.kind == "b":
        raise DataValidationError(name, f"holds booleans in {source}; expected numbers")
    if arr.dtype.kind == "c":
        raise DataValidationError(name, f"holds complex numbers in {source}; expected real numbers")
    import pandas as pd

    ser = pd.Series(arr.ravel(), dtype=object)
    num = pd.to_numeric(ser, errors="coerce")
    suspects = np.flatnonzero(num.isna().to_numpy() & ser.notna().to_numpy())
    bad = [int(k) for k in suspects if str(ser.iloc[k]).strip().lower() not in ("", "nan")]
    if bad:
        k = bad[0]
        raise DataValidationError(
            name,
            f"non-numeric value {ser.iloc[k]!r} at data row {k} of {source} "
            f"({len(bad)} such value(s)); expected numbers (a decimal comma needs decimal=',', "
            "command line --decimal ,)",
        )
    return np.array(num.to_numpy(dtype=np.float64, na_value=np.nan), dtype=np.float64)


def _regenerate_time(t: np.ndarray | None, n: int, fs: Any, source: str) -> tuple[np.ndarray, str]:
    if isinstance(fs, bool) or not isinstance(fs, (int, float, np.integer, np.floating)):
        raise DataValidationError("fs", f"expected a sampling rate [Hz] as a number, got {fs!r}")
    fs = float(fs)
    if not (np.isfinite(fs) and fs > 0):
        raise DataValidationError("fs", f"expected a positive, finite sampling rate [Hz], got {fs}")
    if t is None:
        return np.arange(n) / fs, f"time generated as k / {fs:g} Hz (no time column)"
    ok = np.isfinite(t)
    if not ok.any():
        raise DataValidationError("t", f"time column of {source} has no finite value")
    k0 = int(np.flatnonzero(ok)[0])
    t0 = float(t[k0]) - k0 / fs
    tn = t0 + np.arange(n) / fs
    dev = float(np.max(np.abs(t[ok] - tn[ok])))
    if dev > 0.5 / fs:
        k = int(np.argmax(np.abs(np.where(ok, t - tn, 0.0))))
        raise DataValidationError(
            "t",
            f"time column of {source} departs from t0 + k/{fs:g} by {dev:.6g} s "
            f"(> half a sample interval) at sample {k}: samples are missing or fs is wrong "
            "(fs / --fs declares the records' own sampling rate; a model's rate is the estimator "
            "setting model_fs, command line --set model_fs=...)",
        )
    return tn, (
        f"time regenerated as t0 + k / {fs:g} Hz; largest deviation of the file's time column "
        f"{dev:.3g} s ({dev * fs:.3g} sample intervals)"
    )


def estimate_rate(t: np.ndarray) -> tuple[float, float] | None:
    """Sampling rate [Hz] of a time column with rounding jitter, and its largest jitter [intervals].

    The rate is the inverse slope of a least-squares line through ``(k, t[k])`` (finite samples),
    rounded to the fewest significant digits that move the last sample by less than 1 % of an
    interval. Returns None when the column is not increasing or deviates from the line by more
    than :data:`JITTER_LIMIT` intervals (missing samples, irregular sampling).
    """
    k = np.flatnonzero(np.isfinite(t))
    if k.size < 3:
        return None
    tk = t[k]
    if np.any(np.diff(tk) <= 0):
        return None
    slope = float(np.polyfit(k.astype(np.float64), tk, 1)[0])
    if not slope > 0:
        return None
    fs = 1.0 / float(slope)
    n = float(k[-1] - k[0] + 1)
    for digits in range(3, 16):
        rounded = float(f"{fs:.{digits}g}")
        if n * abs(fs / rounded - 1.0) < 0.01:
            fs = rounded
            break
    t0 = float(np.median(tk - k / fs))
    dev = float(np.max(np.abs(tk - (t0 + k / fs)))) * fs
    if dev > JITTER_LIMIT:
        return None
    return fs, dev


def _missing(
    channel: str, what: str, headers: list[str], source: str, hint: str = ""
) -> DataValidationError:
    return DataValidationError(
        channel,
        f"no {what} column in {source} (found {headers}; recognised names: "
        f"{list(COLUMN_ALIASES[channel])}); map one with columns={{'<name>': {channel!r}}} "
        f"(command line: --column <name>={channel}){hint}",
    )


def build_experiment(
    raw: Mapping[str, Any],
    *,
    path: str | os.PathLike[str],
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
    stored_metadata: Mapping[str, Any] | None = None,
    headers: Sequence[str] | None = None,
) -> Experiment:
    """Build an Experiment from ``{source column: values}``; see
    :func:`~mrdamper.data.readers.read_csv`.

    Each channel is converted once: to float64 (no copy for a float64 array that owns its
    memory), scaled to SI in place, and kept read-only by the record, so a record of ``n``
    samples costs its channels and at most one column in transit.

    Parameters
    ----------
    raw : mapping
        Source column name -> values (any array-like, in source units). The values are taken
        over: a writable float64 array that owns its memory is scaled in place and kept.
    path : path-like
        Source file, recorded as ``metadata["source"]``.
    stored_metadata : mapping, optional
        Metadata saved in the file itself (Parquet written by mrdamper); ``metadata`` wins.
    headers : sequence of str, optional
        Every column name of the source, when ``raw`` holds only the columns that map to
        channels (a reader that reads only those); default: the keys of ``raw``.

    Other Parameters
    ----------------
    columns, units, nan_policy, max_gap, resample_fs, fs, derive_velocity, name, metadata
        As for :func:`~mrdamper.data.readers.read_csv`.
    time_tolerance, plausible_max
        As for :func:`~mrdamper.data.readers.read_csv`.
    """
    src = str(path)
    headers = [str(h) for h in (raw if headers is None else headers)]
    specs: dict[str, ColumnSpec] = resolve_columns(
        headers, columns=columns, units=units, source=src
    )
    n_rows = {np.size(v) for v in raw.values()}
    if len(n_rows) > 1:
        lengths = {h: np.size(v) for h, v in raw.items()}
        raise DataValidationError("columns", f"columns of {src} differ in length: {lengths}")
    n = n_rows.pop() if n_rows else 0
    if n == 0:
        raise DataValidationError("file", f"{src} has no data rows")

    if fs is not None and resample_fs is not None:
        raise DataValidationError(
            "fs",
            "give either fs (declared rate, time regenerated) or resample_fs (interpolation), "
            "not both",
        )
    if "t" not in specs and fs is None:
        raise _missing("t", "time", headers, src, " or declare the rate with fs= (--fs)")
    if "x" not in specs:
        raise _missing("x", "displacement", headers, src)
    if "F" not in specs:
        raise _missing("F", "force", headers, src)
    if "i" not in specs and "voltage" not in specs:
        raise DataValidationError(
            "i",
            f"no electrical input in {src}: found {headers}; need a current column (names "
            f"{list(COLUMN_ALIASES['i'])}) or a voltage column "
            f"(names {list(COLUMN_ALIASES['voltage'])})",
        )
    derive = _check_derive(derive_velocity)
    if "v" not in specs and derive is None:
        raise _missing(
            "v",
            "velocity",
            headers,
            src,
            ", or pass derive_velocity=True (or a cut-off [Hz]; command line: --derive-velocity) "
            "to compute it from x; see mrdamper.data.preprocessing.velocity_from_displacement",
        )
    if "v" in specs and derive is not None:
        raise DataValidationError(
            "derive_velocity",
            f"{src} has a velocity column {specs['v'].source!r}; derive_velocity applies only when "
            "velocity is missing (use preprocessing.velocity_from_displacement to recompute it)",
        )

    arrays: dict[str, np.ndarray] = {}
    for ch, spec in specs.items():
        factor = si_factor(ch, spec.unit, column=spec.source)
        values = numeric_column(spec.source, raw[spec.source], src)
        if factor != 1.0:
            values *= factor
        values.setflags(write=False)  # the record keeps it as it is (no further copy)
        arrays[ch] = values

    notes: list[str] = []
    if fs is not None:
        arrays["t"], note = _regenerate_time(arrays.get("t"), n, fs, src)
        notes.append(note)
    if derive is not None:
        arrays["v"] = np.zeros(n)  # placeholder, replaced below once time and x are repaired

    meta: dict[str, Any] = dict(stored_metadata or {})
    meta["source"] = src
    meta["columns"] = {ch: spec.source for ch, spec in specs.items()}
    meta["units"] = {ch: spec.unit for ch, spec in specs.items()}
    ignored = [h for h in headers if h not in meta["columns"].values()]
    if ignored:
        meta["ignored_columns"] = ignored
    meta.update(metadata or {})
    if notes:
        meta["repairs"] = tuple(meta.get("repairs", ())) + tuple(notes)
    rec_name = name if name is not None else os.path.splitext(os.path.basename(src))[0]

    def assemble() -> Experiment:
        return Experiment.from_arrays(
            **arrays,
            name=rec_name,
            metadata=meta,
            nan_policy=nan_policy,
            max_gap=max_gap,
            resample_fs=resample_fs,
            time_tolerance=time_tolerance,
        )

    try:
        exp = assemble()
    except DataValidationError as exc:
        if not (
            exc.field == "t" and "not uniform" in str(exc) and fs is None and resample_fs is None
        ):
            raise
        est = estimate_rate(arrays["t"])
        if est is None:
            raise DataValidationError(
                "t",
                f"{src}: {str(exc)[3:]}; if the file's time column is only rounded, declare the "
                "rate with fs= (command line: --fs); if the sampling really was irregular, "
                "interpolate with resample_fs= (command line: --resample-fs)",
            ) from None
        fs_est, jitter = est
        arrays["t"], _ = _regenerate_time(arrays["t"], n, fs_est, src)
        note = (
            f"time column of {src} is not uniform but stays within {jitter:.3g} sample intervals "
            f"of a straight line (rounded values); rate estimated as {fs_est:.10g} Hz and time "
            "regenerated as t0 + k/fs (declare the rate with fs= / --fs to silence this)"
        )
        warn_user(note, Note)
        meta["repairs"] = tuple(meta.get("repairs", ())) + (note,)
        exp = assemble()
    if derive is not None:
        from mrdamper.data.preprocessing import velocity_from_displacement

        exp = velocity_from_displacement(exp, cutoff=None if derive is True else float(derive))
    found = check_plausibility(
        {c: getattr(exp, c) for c in ("x", "v", "F", "i", "voltage")}, src, plausible_max
    )
    if found:
        exp = exp.replace(metadata={**dict(exp.metadata), "implausible": tuple(found)})
    return exp


def _check_derive(derive_velocity: Any) -> bool | float | None:
    if derive_velocity is False or derive_velocity is None:
        return None
    if derive_velocity is True:
        return True
    if (
        isinstance(derive_velocity, (int, float, np.integer, np.floating))
        and np.isfinite(derive_velocity)
        and derive_velocity > 0
    ):
        return float(derive_velocity)
    raise DataValidationError(
        "derive_velocity",
        f"expected False, True or a positive cut-off [Hz], got {derive_velocity!r}",
    )
