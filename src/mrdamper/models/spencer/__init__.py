"""Spencer et al. (1997) modified Bouc-Wen model: the family.

The family's parts, one module each:

* :mod:`~mrdamper.models.spencer.model`: the fitted model, the estimator and the published
  parameter set (:func:`spencer1997`);
* :mod:`~mrdamper.models.spencer.fit`: the identification on plain settings (it does not import
  the estimator);
* :mod:`~mrdamper.models.spencer.kernels`: RK4 with forward sensitivities, the sub-step rule and
  the per-sample step (``SpencerForm``).
"""

from __future__ import annotations

from mrdamper.models.spencer.model import *
