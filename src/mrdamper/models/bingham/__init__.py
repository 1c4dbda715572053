"""Bingham plastic reference model: the family.

* :mod:`~mrdamper.models.bingham.model`: the fitted model and the estimator;
* :mod:`~mrdamper.models.bingham.fit`: the identification (no compiled kernel: its per-sample
  step is the static-map step of :mod:`mrdamper.models.sp.kernels`).
"""

from __future__ import annotations

from mrdamper.models.bingham.model import BinghamEstimator, BinghamModel

__all__ = ["BinghamEstimator", "BinghamModel"]
