"""P-15, Wang's phenomenological model with current-dependent coefficients: the family.

* :mod:`~mrdamper.models.p15.model`: the fitted model (stable by construction) and the
  estimator;
* :mod:`~mrdamper.models.p15.fit`: the paper's equation-error fit and the output-error fit;
* :mod:`~mrdamper.models.p15.kernels`: L-stable SDIRK2 with discrete sensitivities and the
  per-sample step (``P15Form``).

The family's modules are also importable as :mod:`mrdamper.models.phenomenological`.
"""

from __future__ import annotations

from mrdamper.models.p15.model import P15Estimator, P15Model

__all__ = ["P15Estimator", "P15Model"]
