"""Move signals between a record's sampling rate and a discrete model's own rate.

Discrete-time models (LPV, LTI, NARX) run at one rate ``fs`` fixed at identification; records at
other rates are resampled on the way in and the predicted force is interpolated back.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.signal as sps

from mrdamper.data import Experiment

__all__ = ["to_model_rate", "to_record_rate"]


def to_model_rate(x: np.ndarray, fs_in: float, fs_out: float) -> np.ndarray:
    """Resample ``x`` [any unit] from ``fs_in`` to ``fs_out`` [Hz].

    Integer down-sampling ratios use anti-aliased polyphase filtering
    (``scipy.signal.resample_poly`` with ``padtype="line"``); other ratios linear interpolation.
    Equal rates return ``x`` itself (as float64). A model rate above the record rate
    (up-sampling) interpolates linearly and says so with a ``RuntimeWarning``: the model then
    sees no content above the record's Nyquist frequency.
    """
    if abs(fs_in - fs_out) <= 1e-9 * fs_out:
        return np.asarray(x, dtype=np.float64)
    if fs_out > fs_in:
        warnings.warn(
            f"model rate {fs_out:g} Hz is above the record rate {fs_in:g} Hz: the record is "
            f"up-sampled by linear interpolation",
            RuntimeWarning,
            stacklevel=3,
        )
    q = fs_in / fs_out
    if abs(q - round(q)) < 1e-9 and round(q) >= 2:
        return np.asarray(sps.resample_poly(x, 1, round(q), padtype="line"), dtype=np.float64)
    n = int(np.floor((x.size - 1) * fs_out / fs_in + 1e-9)) + 1
    return np.interp(np.arange(n) / fs_out, np.arange(x.size) / fs_in, x)


def to_record_rate(y: np.ndarray, fs_model: float, experiment: Experiment) -> np.ndarray:
    """Interpolate a model-rate signal ``y`` back onto the record's samples (identity at equal rates)."""
    if abs(experiment.fs - fs_model) <= 1e-9 * fs_model:
        return y
    return np.interp(np.arange(experiment.n) * experiment.dt, np.arange(y.size) / fs_model, y)
