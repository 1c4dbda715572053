"""Explicit preprocessing steps; each returns a new :class:`~mrdamper.data.Experiment`.

Nothing here mutates its input. Every step appends a line to ``metadata["processing"]`` so the
record says what was done to it. Filters are zero-phase (forward-backward), so no step shifts a
channel in time relative to the others.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.data.experiment import ElectricalSource, Experiment
from mrdamper.errors import DataValidationError

__all__ = [
    "apply_drive_lag",
    "decimate",
    "dominant_frequency",
    "estimate_velocity_cutoff",
    "remove_offsets",
    "trim",
    "velocity_from_displacement",
]

_SIGNAL_CHANNELS = ("x", "v", "F", "i", "voltage")


def _log(exp: Experiment, note: str, **extra: Any) -> dict[str, Any]:
    meta = dict(exp.metadata)
    meta["processing"] = tuple(meta.get("processing", ())) + (note,)
    meta.update(extra)
    return meta


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise DataValidationError(name, f"expected a positive number, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise DataValidationError(name, f"expected a positive, finite number, got {value}")
    return value


def _zero_phase_lowpass(
    values: np.ndarray, cutoff: float, fs: float, order: int, field: str
) -> np.ndarray:
    from scipy.signal import butter, sosfiltfilt

    if not cutoff < 0.5 * fs:
        raise DataValidationError(
            "cutoff", f"{cutoff:g} Hz is not below the Nyquist frequency {0.5 * fs:g} Hz"
        )
    sos = butter(order, cutoff, btype="low", fs=fs, output="sos")
    padlen = 3 * (2 * len(sos) + 1)
    if values.size <= padlen:
        raise DataValidationError(
            field,
            f"{values.size} samples are too few for a zero-phase filter of order {order} "
            f"(need more than {padlen})",
        )
    return np.asarray(sosfiltfilt(sos, values), dtype=np.float64)


def dominant_frequency(x: Any, fs: float, *, min_share: float = 0.5) -> float:
    """Frequency [Hz] of the largest spectral peak of ``x``.

    The peak is located in the Hann-windowed spectrum (mean removed), then refined to the
    frequency of the best least-squares sine fit within one bin of it.

    Parameters
    ----------
    x : array_like
        Signal, e.g. displacement [m].
    fs : float
        Sampling rate [Hz].
    min_share : float
        Smallest share of the (non-DC) power that the peak (its bin +- 3 bins) must hold [-].

    Raises
    ------
    DataValidationError
        If the signal is constant or has no dominant peak (broadband excitation).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.size
    if n < 8:
        raise DataValidationError("x", f"{n} samples are too few to estimate a frequency")
    p = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(n))) ** 2
    p[0] = 0.0
    total = float(p.sum())
    if total == 0.0:
        raise DataValidationError("x", "is constant; no excitation frequency can be estimated")
    k = int(np.argmax(p))
    share = float(p[max(k - 3, 1) : k + 4].sum() / total)
    if share < min_share:
        raise DataValidationError(
            "x",
            f"has no dominant frequency (largest peak holds {share:.0%} of the power, expected at "
            f"least {min_share:.0%}); give the period or frequency explicitly",
        )
    # Refine within +-1 bin: the frequency whose least-squares sine (with offset) leaves the
    # smallest residual. Unlike interpolating the windowed spectrum, this is unbiased for short
    # records holding a non-integer number of cycles.
    from scipy.optimize import minimize_scalar

    t = np.arange(n) / fs

    def residual(f: float) -> float:
        basis = np.column_stack((np.ones(n), np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)))
        coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
        return float(np.sum((x - basis @ coef) ** 2))

    bin_hz = fs / n
    lo, hi = max(k - 1, 0.5) * bin_hz, (k + 1) * bin_hz
    res = minimize_scalar(residual, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7 * hi})
    return float(res.x)


def estimate_velocity_cutoff(exp: Experiment) -> float:
    """Cut-off [Hz] used by :func:`velocity_from_displacement` when none is given.

    * With ``metadata["frequency"]`` f (a sine test): ``max(10 f, 20 Hz)``, the rule used for
      the velocities of the shared constant-current sine records.
    * Otherwise, from the spectrum of x: ``max(2 f99, 20 Hz)``, where ``f99`` is the frequency
      below which 99 % of the (non-DC) power of x lies; broadband excitation keeps its band.

    The result is capped at 0.45 fs.

    Parameters
    ----------
    exp : Experiment
        The record (its x and ``metadata["frequency"]`` are used).

    Returns
    -------
    float
        Cut-off frequency [Hz].
    """
    f = exp.metadata.get("frequency")
    if isinstance(f, (int, float, np.integer, np.floating)) and not isinstance(f, bool) and f > 0:
        cut = max(10.0 * float(f), 20.0)
    else:
        x = exp.x - exp.x.mean()
        p = np.abs(np.fft.rfft(x)) ** 2
        p[0] = 0.0
        if p.sum() == 0.0:
            raise DataValidationError("x", f"record {exp.name!r}: displacement is constant")
        cum = np.cumsum(p) / p.sum()
        k99 = int(np.searchsorted(cum, 0.99))
        f99 = k99 * exp.fs / exp.n
        cut = max(2.0 * f99, 20.0)
    return float(min(cut, 0.45 * exp.fs))


def velocity_from_displacement(
    exp: Experiment, cutoff: float | None = None, order: int = 4
) -> Experiment:
    """Return a copy whose velocity is the derivative of the low-passed displacement.

    x is filtered with a zero-phase Butterworth low-pass (``scipy.signal.sosfiltfilt``, so the
    effective order is ``2 * order`` and there is no lag), then differentiated by central
    differences (one-sided at the two end samples).

    Parameters
    ----------
    exp : Experiment
        The record (its v is replaced; x is kept unfiltered).
    cutoff : float, optional
        Low-pass cut-off [Hz]; default from :func:`estimate_velocity_cutoff`.
    order : int
        Butterworth order of one pass.

    Returns
    -------
    Experiment
        New record; ``metadata["velocity_cutoff"]`` [Hz] records the cut-off.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(2000) / 1000.0
    >>> x = 0.005 * np.sin(2 * np.pi * 2 * t)
    >>> e = Experiment(t=t, x=x, v=0 * t, F=0 * t, i=0 * t, metadata={"frequency": 2.0})
    >>> e2 = velocity_from_displacement(e)
    >>> bool(abs(e2.v[1000] - 0.005 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t[1000])) < 1e-4)
    True
    """
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise DataValidationError("order", f"expected a positive integer, got {order!r}")
    cut = estimate_velocity_cutoff(exp) if cutoff is None else _positive("cutoff", cutoff)
    xf = _zero_phase_lowpass(exp.x, cut, exp.fs, int(order), "x")
    v = np.gradient(xf, exp.t)
    note = (
        "v = central difference of x after zero-phase Butterworth low-pass "
        f"(order {order}, {cut:g} Hz)"
    )
    return exp.replace(v=v, metadata=_log(exp, note, velocity_cutoff=cut))


def decimate(exp: Experiment, factor: int, order: int = 8) -> Experiment:
    """Keep every ``factor``-th sample after a zero-phase anti-alias low-pass.

    Every channel except t goes through a zero-phase Butterworth low-pass of ``order`` at
    0.8 times the new Nyquist frequency (``0.4 fs / factor``) before down-sampling. Step-like
    electrical inputs therefore get the filter's ringing; decimate before applying a drive lag
    only if that is acceptable.

    Parameters
    ----------
    exp : Experiment
        The record.
    factor : int
        Down-sampling factor (>= 1; 1 returns an unchanged copy).
    order : int
        Butterworth order of one pass.

    Returns
    -------
    Experiment
        New record at ``fs / factor``.
    """
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise DataValidationError("factor", f"expected an integer >= 1, got {factor!r}")
    factor = int(factor)
    if factor == 1:
        return exp.replace(metadata=_log(exp, "decimate by 1 (unchanged)"))
    if exp.n // factor < 2:
        raise DataValidationError("factor", f"{factor} leaves fewer than 2 of the {exp.n} samples")
    cut = 0.4 * exp.fs / factor
    chans: dict[str, np.ndarray] = {"t": exp.t[::factor]}
    for ch in exp.channel_names:
        if ch != "t":
            chans[ch] = _zero_phase_lowpass(getattr(exp, ch), cut, exp.fs, order, ch)[::factor]
    note = (
        f"decimated by {factor} after zero-phase Butterworth low-pass (order {order}, {cut:g} Hz)"
    )
    return exp.replace(**chans, metadata=_log(exp, note))


def remove_offsets(
    exp: Experiment, channels: Sequence[str] = ("x", "F"), period: float | None = None
) -> Experiment:
    """Subtract each channel's mean over the largest whole number of excitation cycles.

    The averaging window is centred in the record, so ramps at both ends weigh equally.

    Parameters
    ----------
    exp : Experiment
        The record.
    channels : sequence of str
        Channels to correct (any of ``x, v, F, i, voltage``).
    period : float, optional
        Excitation period [s]. Default: measured from x, the period of its dominant spectral
        peak (:func:`dominant_frequency`), because a nominal frequency can be off (the shared
        sine records run about 1.7 % faster than their file names say, and over many cycles
        that misplaces the window by a sizeable part of a cycle). If x has no dominant frequency,
        ``1 / metadata["frequency"]`` is used; without it, the error is raised.

    Returns
    -------
    Experiment
        New record; ``metadata["offsets"]`` holds the total subtracted value per channel [SI].
    """
    if isinstance(channels, str):
        channels = (channels,)
    for ch in channels:
        if ch not in _SIGNAL_CHANNELS:
            raise DataValidationError(
                "channels", f"{ch!r} is not a signal channel; expected any of {_SIGNAL_CHANNELS}"
            )
        if getattr(exp, ch) is None:
            raise DataValidationError(ch, f"record {exp.name!r} has no {ch!r} channel")
    if period is None:
        f = exp.metadata.get("frequency")
        f_meta = (
            float(f)
            if isinstance(f, (int, float, np.integer, np.floating))
            and not isinstance(f, bool)
            and f > 0
            else None
        )
        try:
            f_x = dominant_frequency(exp.x, exp.fs)
        except DataValidationError:
            if f_meta is None:
                raise
            period, how = 1.0 / f_meta, "metadata frequency; x has no dominant frequency"
        else:
            period = 1.0 / f_x
            how = f"spectrum of x, {f_x:.6g} Hz"
            if f_meta is not None:
                how += f"; nominal metadata frequency {f_meta:g} Hz"
    else:
        period, how = _positive("period", period), "given"
    per_samples = period * exp.fs
    cycles = math.floor((exp.n - 1) / per_samples + 1e-9)
    if cycles < 1:
        raise DataValidationError(
            "period", f"{period:g} s is longer than record {exp.name!r} ({exp.duration:g} s)"
        )
    length = round(cycles * per_samples)
    start = (exp.n - length) // 2
    offsets = dict(exp.metadata.get("offsets", {}))
    changes: dict[str, np.ndarray] = {}
    for ch in channels:
        arr = getattr(exp, ch)
        mean = float(arr[start : start + length].mean())
        changes[ch] = arr - mean
        offsets[ch] = offsets.get(ch, 0.0) + mean
    note = (
        f"offsets of {list(channels)} removed: mean over {cycles} cycle(s) of {period:g} s "
        f"(period from {how})"
    )
    return exp.replace(**changes, metadata=_log(exp, note, offsets=offsets))


def trim(exp: Experiment, t_start: float | None = None, t_stop: float | None = None) -> Experiment:
    """Keep the samples with ``t_start <= t <= t_stop`` (time is not re-zeroed).

    Parameters
    ----------
    exp : Experiment
        The record.
    t_start, t_stop : float, optional
        Window limits [s] on the record's own time axis; default: its first / last sample.

    Raises
    ------
    DataValidationError
        If a limit is not finite, ``t_start >= t_stop``, or fewer than 2 samples remain.
    """
    lo = exp.t[0] if t_start is None else t_start
    hi = exp.t[-1] if t_stop is None else t_stop
    for fld, val in (("t_start", lo), ("t_stop", hi)):
        if (
            isinstance(val, bool)
            or not isinstance(val, (int, float, np.integer, np.floating))
            or not math.isfinite(val)
        ):
            raise DataValidationError(fld, f"expected a finite time [s], got {val!r}")
    if not lo < hi:
        raise DataValidationError("t_stop", f"{hi:g} s must exceed t_start {lo:g} s")
    eps = 1e-6 * exp.dt
    idx = np.flatnonzero((exp.t >= lo - eps) & (exp.t <= hi + eps))
    if idx.size < 2:
        raise DataValidationError(
            "t_start",
            f"window [{lo:g}, {hi:g}] s keeps {idx.size} sample(s) of record {exp.name!r} "
            f"(which spans [{exp.t[0]:g}, {exp.t[-1]:g}] s); need at least 2",
        )
    out = exp.slice(int(idx[0]), int(idx[-1]) + 1)
    return out.replace(metadata=_log(exp, f"trimmed to [{lo:g}, {hi:g}] s"))


def apply_drive_lag(
    exp: Experiment, eta: float, source: ElectricalSource = "voltage"
) -> Experiment:
    """Pass the command through the first-order lag ``du/dt = -eta (u - command)``.

    The lag (drive electronics and fluid response, as in Spencer et al. 1997) is discretised
    exactly for a command held constant over each sample interval:
    ``u[k+1] = a u[k] + (1 - a) command[k]`` with ``a = exp(-eta dt)``, starting at rest
    (``u[0] = command[0]``), computed with ``scipy.signal.lfilter``.

    Parameters
    ----------
    exp : Experiment
        The record.
    eta : float
        Lag rate [1/s] (time constant ``1 / eta``).
    source : {"voltage", "i"}
        Channel holding the command; the lagged signal replaces it (by default the ``voltage``
        channel, which then holds the filtered voltage u [V]).

    Returns
    -------
    Experiment
        New record with ``metadata["drive_lag_eta"] = eta`` and ``metadata["drive_lag_source"]``.

    Raises
    ------
    DataValidationError
        If eta is not positive, the channel is missing, or a drive lag was already applied.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(100) * 1e-3
    >>> e = Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, voltage=(t >= 0.01) * 2.0)
    >>> u = apply_drive_lag(e, eta=100.0).voltage
    >>> bool(np.isclose(u[20], 2.0 * (1 - np.exp(-100.0 * 0.01))))
    True
    """
    eta = _positive("eta", eta)
    if source not in ("voltage", "i"):
        raise DataValidationError("source", f"expected 'voltage' or 'i', got {source!r}")
    if "drive_lag_eta" in exp.metadata:
        raise DataValidationError(
            "drive_lag_eta",
            f"record {exp.name!r} already has a drive lag (eta={exp.metadata['drive_lag_eta']!r}); "
            "apply it to the original command only once",
        )
    w = exp.electrical(source)
    from scipy.signal import lfilter

    a = math.exp(-eta * exp.dt)
    u = lfilter([0.0, 1.0 - a], [1.0, -a], w, zi=[float(w[0])])[0]
    note = (
        f"first-order drive lag on {source!r}: du/dt = -{eta:g} (u - {source}) (exact, held input)"
    )
    meta = _log(exp, note, drive_lag_eta=eta, drive_lag_source=source)
    return exp.replace(**{source: np.asarray(u, dtype=np.float64)}, metadata=meta)
