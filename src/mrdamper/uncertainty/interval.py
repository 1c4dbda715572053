"""Prediction intervals of a model that carries a band, and their measured coverage."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.uncertainty.band import Band, band_of, check_level

__all__ = ["Interval", "coverage", "predict_interval", "require_band"]


class Interval(NamedTuple):
    """A free-run prediction with its band, all [N], one value per sample."""

    F_pred: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


def require_band(model: Any, field_name: str = "interval") -> Band:
    """The band of ``model``, or one line (naming ``field_name``) saying that none is stored.

    Raises
    ------
    DataValidationError
        ``interval: ... no band stored ...`` for a model fitted without one (or saved before
        bands existed).
    """
    band = band_of(model)
    if band is None:
        raise DataValidationError(
            field_name,
            f"the {model.kind!r} model has no band stored; fit it with a band "
            "('mrdamper fit ... --band' or mrdamper.uncertainty.fit_with_band)",
        )
    return band


def predict_interval(model: Any, experiment: Any, level: float = 0.9) -> Interval:
    """Free-run prediction of ``experiment`` and its band at coverage ``level``.

    Parameters
    ----------
    model : FittedModel
        A model with a band (:func:`mrdamper.uncertainty.fit_with_band`).
    experiment : Experiment
        The record to predict.
    level : float
        Nominal coverage [-], 0.5 to 0.99.

    Returns
    -------
    Interval
        ``F_pred``, ``lower`` and ``upper`` [N].
    """
    check_level(level)
    band = require_band(model)
    F = np.asarray(model.predict(experiment), dtype=np.float64)
    lo, hi = band.interval(F, level, experiment.dt)
    return Interval(F, lo, hi)


def coverage(F: np.ndarray, interval: Interval) -> tuple[float, float]:
    """Share of the measured force ``F`` [N] inside the band [-], and the mean band width as a
    fraction of the RMS of ``F`` [-]."""
    F = np.asarray(F, dtype=np.float64)
    inside = (F >= interval.lower) & (F <= interval.upper)
    rms = float(np.sqrt(np.mean(F**2)))
    width = float(np.mean(interval.upper - interval.lower))
    return float(np.mean(inside)), width / rms if rms > 0 else float("nan")
