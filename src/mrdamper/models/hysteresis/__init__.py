"""The one-state hysteresis families: tanh, Bouc-Wen, Dahl and LuGre.

They share everything but their equations' parameters:

* :mod:`~mrdamper.models.hysteresis.model`: the fitted-model and estimator base;
* :mod:`~mrdamper.models.hysteresis.fit`: the output-error fit on plain settings;
* :mod:`~mrdamper.models.hysteresis.kernels`: one RK4 interval for the free run and the
  per-sample step (``HysteresisForm``);
* one module per family, holding only its parameters, its identified unknowns and their bounds:
  :mod:`~mrdamper.models.hysteresis.tanh`, :mod:`~mrdamper.models.hysteresis.boucwen`,
  :mod:`~mrdamper.models.hysteresis.dahl`, :mod:`~mrdamper.models.hysteresis.lugre` (also
  importable as ``mrdamper.models.tanh`` and so on).
"""

from __future__ import annotations

from mrdamper.models.hysteresis.boucwen import BoucWenEstimator, BoucWenModel
from mrdamper.models.hysteresis.dahl import DahlEstimator, DahlModel
from mrdamper.models.hysteresis.lugre import LuGreEstimator, LuGreModel
from mrdamper.models.hysteresis.tanh import TanhEstimator, TanhModel

__all__ = [
    "BoucWenEstimator",
    "BoucWenModel",
    "DahlEstimator",
    "DahlModel",
    "LuGreEstimator",
    "LuGreModel",
    "TanhEstimator",
    "TanhModel",
]
