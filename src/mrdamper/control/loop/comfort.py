"""ISO 2631-1 frequency weighting ``Wk`` (vertical whole-body vibration) and weighted RMS.

The weighting is the product of four analogue filters (ISO 2631-1:1997 Annex A; the same
parameters are listed in ISO 8041), with ``s = j 2 pi f`` and ``w_n = 2 pi f_n``:

* band limiting, high-pass ``H_h = s^2 / (s^2 + w1 s / Q1 + w1^2)`` and low-pass
  ``H_l = w2^2 / (s^2 + w2 s / Q2 + w2^2)``; ``f1 = 0.4 Hz``, ``f2 = 100 Hz``,
  ``Q1 = Q2 = 1/sqrt(2)``;
* acceleration-velocity transition ``H_t = (1 + s / w3) / (1 + s / (Q4 w4) + s^2 / w4^2)``;
  ``f3 = f4 = 12.5 Hz``, ``Q4 = 0.63``;
* upward step ``H_s = (s^2 + w5 s / Q5 + w5^2) / (s^2 + w6 s / Q6 + w6^2)``;
  ``f5 = 2.37 Hz``, ``Q5 = 0.91``, ``f6 = 3.35 Hz``, ``Q6 = 0.91`` (gain ``(f5/f6)^2`` at low
  frequency, 1 at high).

:func:`weighted_rms` applies the weighting in the frequency domain on the record's FFT grid
(``|Wk(f)|`` times the spectrum; Parseval gives the RMS): exact for the record taken as one period,
with no filter start-up transient. :func:`weight_signal` returns the weighted time history
(the same product, inverse FFT).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["WK_PARAMETERS", "weight_signal", "weighted_rms", "wk_response"]

#: Parameters of Wk [Hz] and [-] (ISO 2631-1 Table A.2 / ISO 8041).
WK_PARAMETERS: dict[str, float] = {
    "f1": 0.4,
    "Q1": 1.0 / np.sqrt(2.0),
    "f2": 100.0,
    "Q2": 1.0 / np.sqrt(2.0),
    "f3": 12.5,
    "f4": 12.5,
    "Q4": 0.63,
    "f5": 2.37,
    "Q5": 0.91,
    "f6": 3.35,
    "Q6": 0.91,
}


def wk_response(f: Any) -> np.ndarray:
    """Complex frequency response of ``Wk`` at frequencies ``f`` [Hz] (``f >= 0``).

    Parameters
    ----------
    f : array_like
        Frequencies [Hz], non-negative.
    """
    fa = np.asarray(f, dtype=float)
    if np.any(fa < 0) or not np.all(np.isfinite(fa)):
        raise DataValidationError("f", "expected finite frequencies >= 0 [Hz]")
    p = WK_PARAMETERS
    s = 2j * np.pi * fa
    w1, w2, w3, w4, w5, w6 = (2 * np.pi * p[k] for k in ("f1", "f2", "f3", "f4", "f5", "f6"))
    hh = s**2 / (s**2 + w1 * s / p["Q1"] + w1**2)
    hl = w2**2 / (s**2 + w2 * s / p["Q2"] + w2**2)
    ht = (1 + s / w3) / (1 + s / (p["Q4"] * w4) + s**2 / w4**2)
    hs = (s**2 + w5 * s / p["Q5"] + w5**2) / (s**2 + w6 * s / p["Q6"] + w6**2)
    return np.asarray(hh * hl * ht * hs)


def _check(a: Any, fs: float) -> np.ndarray:
    x = np.asarray(a, dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)):
        raise DataValidationError(
            "acceleration", f"expected a finite 1-D array of >= 2 samples, got shape {x.shape}"
        )
    if not (np.isfinite(fs) and fs > 0):
        raise DataValidationError("fs", f"expected a positive sampling rate [Hz], got {fs!r}")
    return x


def weight_signal(acceleration: Any, fs: float) -> np.ndarray:
    """``Wk``-weighted acceleration [m/s^2] of a record sampled at ``fs`` [Hz] (FFT, circular)."""
    a = _check(acceleration, fs)
    spec = np.fft.rfft(a)
    f = np.fft.rfftfreq(a.size, 1.0 / fs)
    return np.fft.irfft(spec * wk_response(f), a.size)


def weighted_rms(acceleration: Any, fs: float) -> float:
    """RMS of the ``Wk``-weighted acceleration [m/s^2] (ISO 2631-1 ``a_w``).

    Parameters
    ----------
    acceleration : array_like
        Vertical acceleration [m/s^2] sampled at ``fs``.
    fs : float
        Sampling rate [Hz].
    """
    return float(np.sqrt(np.mean(weight_signal(acceleration, fs) ** 2)))
