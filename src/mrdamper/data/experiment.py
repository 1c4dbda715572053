"""One test-rig record of an MR damper: the :class:`Experiment` value type.

An :class:`Experiment` is immutable and always valid: equal-length, finite, SI-unit channels on a
strictly increasing, uniform time base. Policies for imperfect data (NaN samples, jittered time)
are explicit arguments of :meth:`Experiment.from_arrays`; nothing is repaired silently.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
import pandas as pd

from mrdamper.errors import DataValidationError

__all__ = ["CHANNELS", "ElectricalSource", "Experiment", "NanPolicy", "require_experiment"]

#: Channel names and their SI units, in the order they are stored and written.
CHANNELS: dict[str, str] = {"t": "s", "x": "m", "v": "m/s", "i": "A", "voltage": "V", "F": "N"}

ElectricalSource = Literal["i", "voltage"]
NanPolicy = Literal["raise", "drop-edges", "interpolate"]

#: Relative tolerance on the sampling interval for a time base to count as uniform.
DEFAULT_TIME_TOLERANCE = 1e-3


def _frozen(values: Any) -> bool:
    """True for a float64 array that nothing can write to: read-only down its chain of bases
    (a channel of another record, a slice of one, a read-only memory map)."""
    arr = values
    while isinstance(arr, np.ndarray):
        if arr.flags.writeable:
            return False
        arr = arr.base
    return (
        isinstance(values, np.ndarray)
        and values.dtype == np.float64
        and not isinstance(arr, np.ndarray)
    )


def _as_channel(name: str, values: Any) -> np.ndarray:
    """Return a read-only float64 1-D copy of ``values`` or raise naming ``name``.

    An array that is already float64 and read-only down its chain of bases is kept as it is
    (no copy: it cannot change under the record).
    """
    if _frozen(values) and values.ndim == 1:
        return np.asarray(values).view(np.ndarray)
    try:
        arr = np.array(values, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise DataValidationError(name, f"could not be read as numbers ({exc})") from None
    if arr.ndim != 1:
        raise DataValidationError(name, f"expected a 1-D array, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Experiment:
    """One record of an MR damper test, in SI units.

    Parameters
    ----------
    t : array_like
        Time [s], strictly increasing and uniformly sampled.
    x : array_like
        Damper displacement [m].
    v : array_like
        Damper velocity [m/s].
    F : array_like
        Measured damper force [N].
    i : array_like, optional
        Coil current [A]. At least one of ``i`` and ``voltage`` is required.
    voltage : array_like, optional
        Command voltage to the damper's drive circuit [V] (when current was not measured).
    name : str
        Record name, unique within an :class:`~mrdamper.data.ExperimentSet`.
    metadata : mapping
        Free-form facts about the record (``current`` [A], ``amplitude`` [m], ``frequency``
        [Hz], ``replicate``, ``source``, ...). Stored read-only.
    time_tolerance : float
        Largest accepted relative deviation of a sampling interval from the median interval [-].

    Raises
    ------
    DataValidationError
        If lengths differ, a value is not finite, time is not strictly increasing or not
        uniform, or neither ``i`` nor ``voltage`` is given. The message names the field and the
        first offending sample.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(5) * 1e-3
    >>> e = Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, i=0 * t + 0.5, name="rest")
    >>> e.fs
    1000.0
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    F: np.ndarray
    i: np.ndarray | None = None
    voltage: np.ndarray | None = None
    name: str = "experiment"
    metadata: Mapping[str, Any] = field(default_factory=dict)
    time_tolerance: float = DEFAULT_TIME_TOLERANCE

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for ch in ("t", "x", "v", "F"):
            set_(self, ch, _as_channel(ch, getattr(self, ch)))
        for ch in ("i", "voltage"):
            if getattr(self, ch) is not None:
                set_(self, ch, _as_channel(ch, getattr(self, ch)))
        if self.i is None and self.voltage is None:
            raise DataValidationError(
                "i",
                "no electrical input: give the coil current 'i' [A] or the command 'voltage' [V]",
            )
        if not isinstance(self.name, str) or not self.name:
            raise DataValidationError("name", f"expected a non-empty string, got {self.name!r}")
        set_(self, "metadata", MappingProxyType(dict(self.metadata)))
        n = self.t.size
        if n < 2:
            raise DataValidationError("t", f"expected at least 2 samples, got {n}")
        for ch in self.channel_names:
            arr = getattr(self, ch)
            if arr.size != n:
                raise DataValidationError(ch, f"has {arr.size} samples but 't' has {n}")
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                raise DataValidationError(
                    ch,
                    f"{bad.size} non-finite value(s), first at sample {bad[0]} "
                    f"(t index {bad[0]}); use nan_policy in Experiment.from_arrays or a reader "
                    "(command line: --nan-policy interpolate)",
                )
        _check_time_base(self.t, self.time_tolerance)

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        """Pickle support (for worker processes): rebuild through the validating constructor."""
        state = {c: getattr(self, c) for c in self.channel_names}
        state.update(
            name=self.name, metadata=dict(self.metadata), time_tolerance=self.time_tolerance
        )
        return (_rebuild_experiment, (state,))

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_arrays(
        cls,
        *,
        t: Any,
        x: Any,
        v: Any,
        F: Any,
        i: Any = None,
        voltage: Any = None,
        name: str = "experiment",
        metadata: Mapping[str, Any] | None = None,
        nan_policy: NanPolicy = "raise",
        max_gap: int = 5,
        resample_fs: float | None = None,
        time_tolerance: float = DEFAULT_TIME_TOLERANCE,
    ) -> Experiment:
        """Build an Experiment from raw arrays, applying explicit repair policies.

        Parameters
        ----------
        t, x, v, F, i, voltage : array_like
            Channels in SI units (see :class:`Experiment`).
        name : str
            Record name.
        metadata : mapping, optional
            Free-form facts about the record.
        nan_policy : {"raise", "drop-edges", "interpolate"}
            ``"raise"``: any non-finite value is an error. ``"drop-edges"``: leading and
            trailing samples where any channel is non-finite are removed; interior gaps still
            raise. ``"interpolate"``: interior gaps of at most ``max_gap`` samples are linearly
            interpolated (edges are dropped); longer gaps raise.
        max_gap : int
            Longest gap [samples] that ``"interpolate"`` fills.
        resample_fs : float, optional
            If given, the record is linearly interpolated onto a uniform grid at this rate [Hz]
            starting at ``t[0]``; needed for non-uniform time bases.
        time_tolerance : float
            See :class:`Experiment`.

        Returns
        -------
        Experiment
            The validated record. ``metadata["repairs"]`` lists what was done.
        """
        raw = {"t": t, "x": x, "v": v, "F": F, "i": i, "voltage": voltage}
        arrays = {k: _as_channel(k, a) for k, a in raw.items() if a is not None}
        n = arrays["t"].size
        for k, a in arrays.items():
            if a.size != n:
                raise DataValidationError(k, f"has {a.size} samples but 't' has {n}")
        repairs: list[str] = []
        if nan_policy not in ("raise", "drop-edges", "interpolate"):
            raise DataValidationError(
                "nan_policy", f"expected 'raise', 'drop-edges' or 'interpolate', got {nan_policy!r}"
            )
        if nan_policy != "raise":
            arrays, repairs = _repair_nan(arrays, nan_policy, max_gap)
        if resample_fs is not None:
            arrays = _resample(arrays, float(resample_fs))
            repairs.append(f"resampled to {float(resample_fs):g} Hz (linear interpolation)")
        meta = dict(metadata or {})
        if repairs:
            meta["repairs"] = tuple(meta.get("repairs", ())) + tuple(repairs)
        return cls(**arrays, name=name, metadata=meta, time_tolerance=time_tolerance)

    def replace(self, **changes: Any) -> Experiment:
        """Return a validated copy with some fields replaced (the original is untouched)."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ properties
    @property
    def channel_names(self) -> tuple[str, ...]:
        """Names of the channels present, in storage order."""
        return tuple(c for c in CHANNELS if getattr(self, c) is not None)

    @property
    def electrical_channel(self) -> ElectricalSource:
        """The electrical channel the record carries: ``"i"`` (coil current) when present, else
        ``"voltage"`` (command voltage); the default input of :meth:`electrical` for it."""
        return "i" if self.i is not None else "voltage"

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Sampling interval [s] (mean over the record)."""
        return float((self.t[-1] - self.t[0]) / (self.n - 1))

    @property
    def fs(self) -> float:
        """Sampling rate [Hz]."""
        return float(np.round(1.0 / self.dt, 9))

    @property
    def duration(self) -> float:
        """Duration from first to last sample [s]."""
        return float(self.t[-1] - self.t[0])

    def electrical(self, source: ElectricalSource = "i") -> np.ndarray:
        """Return the electrical input channel used as model input or scheduling signal.

        Parameters
        ----------
        source : {"i", "voltage"}
            Coil current [A] or command voltage [V].

        Raises
        ------
        DataValidationError
            If the record has no such channel.
        """
        if source not in ("i", "voltage"):
            raise DataValidationError("source", f"expected 'i' or 'voltage', got {source!r}")
        arr = getattr(self, source)
        if arr is None:
            have = "voltage" if source == "i" else "i"
            raise DataValidationError(
                source,
                f"record {self.name!r} has no {source!r} channel (it has {have!r}); "
                f"choose input={have!r}",
            )
        return arr

    def require_samples(self, minimum: int, purpose: str) -> None:
        """Raise :class:`DataValidationError` if the record has fewer than ``minimum`` samples."""
        if self.n < minimum:
            raise DataValidationError(
                "t",
                f"record {self.name!r} has {self.n} samples; {purpose} needs at least {minimum}",
            )

    # ------------------------------------------------------------------ slicing & export
    def slice(self, start: int, stop: int | None = None, name: str | None = None) -> Experiment:
        """Return samples ``start:stop`` as a new record (time kept, not re-zeroed)."""
        sl = slice(start, stop)
        chans = {c: getattr(self, c)[sl] for c in self.channel_names}
        return Experiment(
            **chans,
            name=name or self.name,
            metadata=self.metadata,
            time_tolerance=self.time_tolerance,
        )

    def to_frame(self) -> pd.DataFrame:
        """Return the channels as a DataFrame with SI column names (``t, x, v, i, voltage, F``)."""
        return pd.DataFrame({c: getattr(self, c) for c in self.channel_names})

    def plot(self, axes: Any = None) -> Any:
        """Plot x, v, electrical input and F against time; returns the array of Axes."""
        import matplotlib.pyplot as plt

        chans = [c for c in self.channel_names if c != "t"]
        if axes is None:
            _, axes = plt.subplots(len(chans), 1, sharex=True, figsize=(7, 1.6 * len(chans)))
        for ax, c in zip(np.atleast_1d(axes), chans):
            ax.plot(self.t, getattr(self, c), lw=0.8)
            ax.set_ylabel(f"{c} [{CHANNELS[c]}]")
        np.atleast_1d(axes)[-1].set_xlabel("t [s]")
        np.atleast_1d(axes)[0].set_title(self.name)
        return axes

    def __repr__(self) -> str:
        return (
            f"Experiment(name={self.name!r}, n={self.n}, fs={self.fs:g} Hz, "
            f"duration={self.duration:g} s, input={self.electrical_channel!r})"
        )


def require_experiment(value: object, field_name: str = "experiment") -> Experiment:
    """``value`` itself when it is an :class:`Experiment`.

    Raises
    ------
    DataValidationError
        Otherwise, naming ``field_name`` and the type given.
    """
    if not isinstance(value, Experiment):
        raise DataValidationError(field_name, f"expected an Experiment, got {type(value).__name__}")
    return value


def _rebuild_experiment(state: dict[str, Any]) -> Experiment:
    return Experiment(**state)


#: Samples per block of the time-base check (bounds its temporary arrays on long records).
_TIME_BLOCK = 1 << 20


def _check_time_base(t: np.ndarray, tol: float) -> None:
    """Raise unless ``t`` is strictly increasing with every interval within ``tol`` (relative)
    of the median interval.

    The intervals are formed block by block (:data:`_TIME_BLOCK` samples) except once for the
    median, so the check of a record of ``n`` samples needs one array of ``n`` intervals at a
    time, not several.
    """
    n = t.size
    for start in range(0, n - 1, _TIME_BLOCK):
        d = np.diff(t[start : start + _TIME_BLOCK + 1])
        bad = np.flatnonzero(d <= 0)
        if bad.size:
            k = start + int(bad[0]) + 1
            raise DataValidationError(
                "t",
                f"time must be strictly increasing; sample {k} (t={t[k]:.9g} s) does not exceed "
                f"sample {k - 1} (t={t[k - 1]:.9g} s)",
            )
    dt = float(np.median(np.diff(t), overwrite_input=True))
    for start in range(0, n - 1, _TIME_BLOCK):
        d = np.diff(t[start : start + _TIME_BLOCK + 1])
        bad = np.flatnonzero(np.abs(d - dt) / dt > tol)
        if bad.size:
            k = start + int(bad[0]) + 1
            raise DataValidationError(
                "t",
                f"time base is not uniform: interval before sample {k} is {d[k - 1 - start]:.6g} "
                f"s, median interval {dt:.6g} s (relative tolerance {tol:g}); resample with "
                "Experiment.from_arrays(resample_fs=...) or a reader's resample_fs "
                "(command line: --resample-fs)",
            )


def _repair_nan(
    arrays: dict[str, np.ndarray], policy: str, max_gap: int
) -> tuple[dict[str, np.ndarray], list[str]]:
    ok = np.logical_and.reduce([np.isfinite(a) for a in arrays.values()])
    if not ok.any():
        raise DataValidationError("t", "every sample has a non-finite value in some channel")
    good = np.flatnonzero(ok)
    first, last = int(good[0]), int(good[-1])
    repairs: list[str] = []
    if first > 0 or last < ok.size - 1:
        repairs.append(
            f"dropped {first} leading and {ok.size - 1 - last} trailing non-finite samples"
        )
    arrays = {k: a[first : last + 1] for k, a in arrays.items()}
    if policy == "drop-edges":
        return arrays, repairs
    if not np.isfinite(arrays["t"]).all():
        raise DataValidationError("t", "time has interior non-finite values; cannot interpolate")
    t = arrays["t"]
    out = {}
    for k, a in arrays.items():
        bad = ~np.isfinite(a)
        if bad.any():
            edges = np.diff(np.concatenate(([0], bad.astype(np.int8), [0])))
            starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
            longest = int((stops - starts).max())
            if longest > max_gap:
                raise DataValidationError(
                    k,
                    f"gap of {longest} non-finite samples starting at sample "
                    f"{int(starts[np.argmax(stops - starts)]) + first} exceeds max_gap={max_gap}",
                )
            a = a.copy()
            a[bad] = np.interp(t[bad], t[~bad], a[~bad])
            repairs.append(f"interpolated {int(bad.sum())} non-finite samples of {k!r}")
        out[k] = a
    return out, repairs


def _resample(arrays: dict[str, np.ndarray], fs: float) -> dict[str, np.ndarray]:
    if not fs > 0:
        raise DataValidationError("resample_fs", f"expected a positive rate [Hz], got {fs}")
    t = arrays["t"]
    if np.any(np.diff(t) <= 0):
        raise DataValidationError("t", "time must be strictly increasing to resample")
    n = int(np.floor((t[-1] - t[0]) * fs + 1e-9)) + 1
    tn = t[0] + np.arange(n) / fs
    return {k: (tn if k == "t" else np.interp(tn, t, a)) for k, a in arrays.items()}
