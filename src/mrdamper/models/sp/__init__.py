"""Semi-phenomenological static maps SP-1 ... SP-4 (Guo et al. variants): the family.

* :mod:`~mrdamper.models.sp.model`: the fitted models and the estimators;
* :mod:`~mrdamper.models.sp.fit`: the identification (linear least squares, then the nonlinear
  refinement);
* :mod:`~mrdamper.models.sp.kernels`: the compiled maps, their Jacobians and the static-map
  per-sample step (shared with Bingham).

The family's names are also importable from :mod:`mrdamper.models.semiphenomenological`.
"""

from __future__ import annotations

from mrdamper.models.sp.model import *
