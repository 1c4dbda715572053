"""LPV input-output damper model (paper eqs. 7-9, 16-22) and its LTI counterpart: the family.

Discrete transfer function of order ``n_m`` whose coefficients are polynomials of degree ``n_rho``
in the scheduling variable ``rho`` (frozen-coefficient form)::

    F[k] = y[k] + F0
    y[k] = -sum_{j=1..n_m} a_j(rho[k]) y[k-j] + sum_{j=1..n_m} b_j(rho[k]) u[k-j]     (b0 = 0)

The family's parts, one module each:

* :mod:`~mrdamper.models.lpv.model`: the fitted models and the signal pipeline;
* :mod:`~mrdamper.models.lpv.estimator`: the estimators and order selection;
* :mod:`~mrdamper.models.lpv.fit`: least squares and the output-error refinement;
* :mod:`~mrdamper.models.lpv.kernels`: the compiled regression, simulation and sensitivity kernels;
* :mod:`~mrdamper.models.lpv.step`: the per-sample step (``LPVForm``);
* :mod:`~mrdamper.models.lpv.inputs`: the LPV input (static, velocity, hysteretic).
"""

from __future__ import annotations

from mrdamper.models.lpv.estimator import LPVEstimator, LTIEstimator, select_order
from mrdamper.models.lpv.model import LPVModel, LTIModel, TransferFunctionModel, model_signals

__all__ = [
    "LPVEstimator",
    "LPVModel",
    "LTIEstimator",
    "LTIModel",
    "TransferFunctionModel",
    "model_signals",
    "select_order",
]
