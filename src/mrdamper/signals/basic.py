"""Deterministic basic signals: constant, sine and ramped sine, plus the uniform time grid."""

from __future__ import annotations

import math

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.signals.common import check_positive, n_samples, time_grid

__all__ = ["constant", "n_samples", "ramped_sine", "sine", "time_grid"]


def constant(fs: float, duration: float, *, value: float) -> np.ndarray:
    """Constant signal (e.g. a constant coil current [A]).

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].
    value : float
        The value, in the unit of the quantity.

    Returns
    -------
    ndarray
        ``round(duration * fs)`` copies of ``value``.

    Examples
    --------
    >>> constant(1000.0, 0.003, value=0.5).tolist()
    [0.5, 0.5, 0.5]
    """
    v = float(value)
    if not math.isfinite(v):
        raise DataValidationError("value", f"expected a finite number, got {value!r}")
    return np.full(n_samples(fs, duration), v)


def _sine_arguments(fs: float, frequency: float, amplitude: float) -> tuple[float, float, float]:
    """A sine's sampling rate and frequency [Hz] (positive, the frequency below ``fs / 2``) and
    amplitude (finite, >= 0)."""
    fs = check_positive("fs", fs, "Hz")
    f = check_positive("frequency", frequency, "Hz")
    if f >= fs / 2:
        raise DataValidationError(
            "frequency", f"{f:g} Hz is not below the Nyquist frequency fs/2 = {fs / 2:g} Hz"
        )
    a = float(amplitude)
    if not (math.isfinite(a) and a >= 0):
        raise DataValidationError("amplitude", f"expected a finite value >= 0, got {amplitude!r}")
    return fs, f, a


def sine(
    fs: float,
    duration: float,
    *,
    amplitude: float,
    frequency: float,
    offset: float = 0.0,
    phase: float = 0.0,
) -> np.ndarray:
    """``offset + amplitude * sin(2 pi frequency t + phase)`` on the grid ``t = k / fs``.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].
    amplitude : float
        Amplitude (>= 0), in the unit of the quantity (e.g. [m] or [A]).
    frequency : float
        Frequency [Hz], below the Nyquist rate ``fs / 2``.
    offset : float
        Mean value.
    phase : float
        Phase at t = 0 [rad].

    Returns
    -------
    ndarray
        The sine, one value per sample.

    Examples
    --------
    >>> x = sine(1000.0, 1.0, amplitude=0.005, frequency=3.0)
    >>> round(float(x.max()), 6)
    0.005
    """
    fs, f, a = _sine_arguments(fs, frequency, amplitude)
    off, ph = float(offset), float(phase)
    if not (math.isfinite(off) and math.isfinite(ph)):
        raise DataValidationError(
            "offset/phase", f"expected finite values, got {offset!r}, {phase!r}"
        )
    t = time_grid(fs, duration)
    return off + a * np.sin(2.0 * np.pi * f * t + ph)


def ramped_sine(fs: float, *, amplitude: float, frequency: float, cycles: int) -> np.ndarray:
    """``cycles`` sine periods at full amplitude between half-period raised-cosine ramps.

    The displacement of a rig's sine test (as in Quiroz's records, which start and end with a
    ramp): the record lasts ``cycles + 1`` periods, starts and ends at rest at zero.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    amplitude : float
        Amplitude (>= 0) [m].
    frequency : float
        Frequency [Hz], below the Nyquist rate ``fs / 2``.
    cycles : int
        Periods at full amplitude (>= 1).

    Returns
    -------
    ndarray
        ``round((cycles + 1) fs / frequency)`` samples.

    Examples
    --------
    >>> x = ramped_sine(1000.0, amplitude=0.01, frequency=1.0, cycles=2)
    >>> x.size, round(float(abs(x).max()), 4), float(x[0])
    (3000, 0.01, 0.0)
    """
    fs, f, a = _sine_arguments(fs, frequency, amplitude)
    if isinstance(cycles, bool) or not isinstance(cycles, int | np.integer) or cycles < 1:
        raise DataValidationError("cycles", f"expected an integer >= 1, got {cycles!r}")
    half = 0.5 / f
    t = np.arange(round((cycles / f + 2 * half) * fs)) / fs
    ramp = np.clip(np.minimum(t, t[-1] - t) / half, 0.0, 1.0)
    return a * np.sin(2 * np.pi * f * t) * (0.5 - 0.5 * np.cos(np.pi * ramp))
