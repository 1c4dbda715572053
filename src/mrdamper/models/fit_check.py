"""Whether a fit explains its own training force: the check every fit ends with.

A fit can succeed numerically and still explain nothing: on records whose damper barely moves
(velocity noise only) the best model is a constant, with a training ESR (paper eq. 24,
``mean((F - F_pred)^2) / var(F)``) near 1, the ESR of the mean force. Such a model scores far
worse than 1 on any real record. :func:`training_fit_note` measures the free-run training ESR of
the fitted model and returns a one-line note when it is at least :data:`EXPLAINS_NOTHING_ESR`;
:meth:`mrdamper.models.base.Estimator.fit` records it in the model's provenance
(``training_fit``) and issues it as a warning, so every command that fits (``fit``, ``study``,
``select``, ``demo``) says it on standard error or in its table of fits.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from mrdamper.data import ExperimentSet
from mrdamper.errors import MrDamperError
from mrdamper.metrics import esr

__all__ = ["EXPLAINS_NOTHING_ESR", "training_esr", "training_fit_note"]

#: Training ESR [-] from which a fit is said to explain (almost) nothing of its training force
#: (1 is the ESR of the mean force).
EXPLAINS_NOTHING_ESR = 0.9


def training_esr(model: Any, records: ExperimentSet) -> float | None:
    """Mean free-run ESR [-] of ``model`` over ``records`` (None when no record can be run)."""
    values = []
    for e in records:
        try:
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore")
                values.append(float(esr(e.F, model.predict(e))))
        except (MrDamperError, ValueError, FloatingPointError):
            continue  # a diverging run or a constant force: said elsewhere
    finite = [v for v in values if np.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def training_fit_note(model: Any, records: ExperimentSet) -> tuple[float | None, str | None]:
    """The training ESR of ``model`` and, when it explains (almost) nothing, the note to give.

    Returns
    -------
    esr : float or None
        Mean free-run training ESR [-] (None when no record could be run).
    note : str or None
        One line naming the model, the ESR and the likely causes; None when the fit is usable.
    """
    value = training_esr(model, records)
    if value is None or value < EXPLAINS_NOTHING_ESR:
        return value, None
    peak = max(float(np.max(np.abs(e.v))) for e in records)
    return value, (
        f"{model.kind}: the fit explains almost nothing of its training force (training ESR "
        f"{value:.4g}, 1 is the mean force; largest |v| {peak:.3g} m/s): check that the records "
        "move the damper (velocity column and unit) and that the force responds to it; its "
        "predictions are not to be used"
    )
