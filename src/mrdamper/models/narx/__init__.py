"""Polynomial NARX black-box peer: the family.

* :mod:`~mrdamper.models.narx.model`: the fitted model, the estimator and the candidate
  structure;
* :mod:`~mrdamper.models.narx.fit`: OLS-ERR term selection and the output-error refinement;
* :mod:`~mrdamper.models.narx.kernels`: the compiled free run, its sensitivities and the
  per-sample step (``NARXForm``).
"""

from __future__ import annotations

from mrdamper.models.narx.model import NARXEstimator, NARXModel, candidate_structure

__all__ = ["NARXEstimator", "NARXModel", "candidate_structure"]
