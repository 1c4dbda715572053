"""How far a prediction can be trusted: calibrated prediction bands and uncertainty weights.

* :func:`fit_with_band` fits a model of any kind and calibrates its prediction band on held-out
  residuals of two fits on halves of the training records (:mod:`.calibrate`); the band is
  stored in the model's provenance and saved with it (:mod:`.band`).
* :func:`predict_interval` gives the prediction of a record with its lower and upper force at a
  coverage level; :func:`coverage` measures it against the measured force.
* :func:`uncertainty_weights` fits, per frozen electrical level, a stable first-order weight
  ``W(s)`` bounding the relative model error on the held-out records (:mod:`.weight`), for
  robust LPV / H-infinity design; ``mrdamper export --format mat|json`` writes it.
"""

from mrdamper.uncertainty.band import LEVELS, Band, band_of, check_level
from mrdamper.uncertainty.calibrate import calibrate, calibration_folds, fit_with_band, with_band
from mrdamper.uncertainty.interval import Interval, coverage, predict_interval, require_band
from mrdamper.uncertainty.spectra import error_spectra
from mrdamper.uncertainty.weight import (
    Weight,
    bound_share,
    fit_weight,
    uncertainty_weights,
    weight_export_data,
)

__all__ = [
    "LEVELS",
    "Band",
    "Interval",
    "Weight",
    "band_of",
    "bound_share",
    "calibrate",
    "calibration_folds",
    "check_level",
    "coverage",
    "error_spectra",
    "fit_weight",
    "fit_with_band",
    "predict_interval",
    "require_band",
    "uncertainty_weights",
    "weight_export_data",
    "with_band",
]
