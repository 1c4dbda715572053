"""Move signals between a record's sampling rate and a discrete model's own rate.

Discrete-time models (LPV, LTI, NARX) run at one rate ``fs`` fixed at identification; records at
other rates are resampled on the way in and the predicted force is interpolated back.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.signal as sps

from mrdamper._warn import warn_user
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, Note

__all__ = ["model_rate", "rate_rule", "rename_setting", "to_model_rate", "to_record_rate"]


def model_rate(
    rates: Sequence[float], model_fs: float | None, kind: str, minimum: float | None = None
) -> float:
    """The model rate [Hz] of a discrete model, by one rule for every model kind that has one.

    ``model_fs`` when set; otherwise the lowest sampling rate of the training records, raised to
    ``minimum`` when the kind has one (the estimator's ``min_model_fs``; the LPV family:
    :data:`~mrdamper.models.lpv.estimator.MIN_MODEL_FS`). When the records have different rates
    and ``model_fs`` is not set, a one-line :class:`Note` says which rate was taken (records at
    other rates are resampled to it, see :func:`to_model_rate`). Records below the model rate are
    up-sampled by linear interpolation, which one line says: a :class:`Note` when the kind's
    minimum asked for it, a ``RuntimeWarning`` when ``model_fs`` did (the model then sees no
    content above those records' Nyquist frequency).

    Parameters
    ----------
    rates : sequence of float
        Sampling rates of the training records [Hz].
    model_fs : float or None
        Model rate set by the user [Hz].
    kind : str
        Model kind (for the note).
    minimum : float, optional
        Lowest default model rate of the kind [Hz].
    """
    distinct = sorted({float(r) for r in rates})
    if not distinct:
        raise DataValidationError("model_fs", "no training record to take the model rate from")
    fs = rate_rule(distinct, model_fs, minimum)
    up = ", ".join(f"{r:g}" for r in distinct if r < fs)
    if model_fs is not None:
        if up:
            warn_user(
                f"{kind}: model rate model_fs = {fs:g} Hz is above the record rate {up} Hz: "
                f"those records are up-sampled by linear interpolation",
                RuntimeWarning,
            )
    elif up:
        warn_user(
            f"{kind}: model rate model_fs = {fs:g} Hz (the kind's lowest default rate); "
            f"training records at {up} Hz are up-sampled by linear interpolation (set model_fs "
            f"to choose)",
            Note,
        )
    elif len(distinct) > 1:
        listed = ", ".join(f"{r:g}" for r in distinct)
        warn_user(
            f"{kind}: training records are sampled at {listed} Hz; model rate model_fs = "
            f"{fs:g} Hz (the lowest; the others are resampled; set model_fs to choose)",
            Note,
        )
    return fs


def rate_rule(rates: Sequence[float], model_fs: float | None, minimum: float | None) -> float:
    """The rule of :func:`model_rate` without its notes [Hz]: ``model_fs`` when set, else the
    lowest of ``rates`` raised to ``minimum`` (when not None).

    Parameters
    ----------
    rates : sequence of float
        Sampling rates of the training records [Hz] (at least one).
    model_fs : float or None
        Model rate set by the user [Hz].
    minimum : float or None
        Lowest default model rate of the kind [Hz].
    """
    if model_fs is not None:
        return float(model_fs)
    lowest = float(min(rates))
    return lowest if minimum is None else max(lowest, float(minimum))


def rename_setting(
    kind: str,
    old: str,
    new: str,
    old_value: object,
    new_value: object,
    reason: str = "",
) -> object:
    """Value of a setting given under its old name ``old`` (with a :class:`Note`); ``new_value``
    when the old name was not used. Both names with different values is an error.

    Parameters
    ----------
    kind : str
        Model kind (for the messages).
    old, new : str
        Old and current setting names.
    old_value, new_value : object
        Values given under each name (None: not given).
    reason : str
        Why the name changed, appended to the note in brackets (optional).
    """
    if old_value is None:
        return new_value
    if new_value is not None and new_value != old_value:
        raise DataValidationError(
            old,
            f"{kind}: both {old}={old_value!r} and {new}={new_value!r} given; {old} is the old "
            f"name of {new}",
        )
    why = f" ({reason})" if reason else ""
    warn_user(
        f"{kind}: setting {old!r} is now called {new!r}{why}; using {new}={old_value!r}",
        Note,
    )
    return old_value


#: Reason given in the note for the old name ``fs`` of ``model_fs``.
MODEL_FS_REASON = "the model's own rate, not a record's sampling rate"


def to_model_rate(x: np.ndarray, fs_in: float, fs_out: float) -> np.ndarray:
    """Resample ``x`` [any unit] from ``fs_in`` to ``fs_out`` [Hz].

    Integer down-sampling ratios use anti-aliased polyphase filtering
    (``scipy.signal.resample_poly`` with ``padtype="line"``); other ratios linear interpolation.
    Equal rates return ``x`` itself (as float64). A model rate above the record rate
    (up-sampling) interpolates linearly: the model then sees no content above the record's
    Nyquist frequency (:func:`model_rate` says so once, at identification).

    Parameters
    ----------
    x : ndarray
        Signal at ``fs_in``.
    fs_in, fs_out : float
        Rates of the signal and of the result [Hz].
    """
    if abs(fs_in - fs_out) <= 1e-9 * fs_out:
        return np.asarray(x, dtype=np.float64)
    q = fs_in / fs_out
    if abs(q - round(q)) < 1e-9 and round(q) >= 2:
        return np.asarray(sps.resample_poly(x, 1, round(q), padtype="line"), dtype=np.float64)
    n = int(np.floor((x.size - 1) * fs_out / fs_in + 1e-9)) + 1
    return np.asarray(np.interp(np.arange(n) / fs_out, np.arange(x.size) / fs_in, x))


def to_record_rate(y: np.ndarray, fs_model: float, experiment: Experiment) -> np.ndarray:
    """Interpolate a model-rate signal ``y`` back onto the record's samples.

    The identity at equal rates.

    Parameters
    ----------
    y : ndarray
        Signal at the model rate.
    fs_model : float
        Model rate [Hz].
    experiment : Experiment
        The record whose samples the result is interpolated onto.
    """
    if abs(experiment.fs - fs_model) <= 1e-9 * fs_model:
        return y
    t_record = np.arange(experiment.n) * experiment.dt
    return np.asarray(np.interp(t_record, np.arange(y.size) / fs_model, y))
