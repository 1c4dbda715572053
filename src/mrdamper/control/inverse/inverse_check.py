"""How well an inverse model recovers the electrical input of a measured record.

On a record whose electrical input is known (constant-current sine tests, a measured command
voltage) the inverse is asked for the input that reproduces the record's measured force. Two
figures judge it:

* the median ``|input error|`` over the samples where ``|v|`` exceeds ``v_fraction`` (20 %) of its
  peak: near zero velocity the force barely depends on the input, so the input is not observable
  there and is left out;
* the force the forward model produces with the inverse's input, scored against the measured force
  (SSSE, eq. 23), divided by the forward model's own SSSE with the measured input. A ratio below 1
  means the inverse's input explains the measured force better than the true input does (it also
  absorbs model error); a ratio far above 1 means the inverse chatters or drifts.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.inverse.current import inverse_current
from mrdamper.data import Experiment
from mrdamper.data.experiment import require_experiment
from mrdamper.errors import DataValidationError
from mrdamper.metrics import ssse
from mrdamper.models.base import FittedModel

__all__ = ["InverseCheck", "check_inverse", "check_inverse_frame"]


@dataclass(frozen=True)
class InverseCheck:
    """Figures of one inverse run on one record.

    Attributes
    ----------
    record, model_kind, input : str
        Record name, inverted model kind, electrical input name (``"i"`` or ``"voltage"``).
    median_input_error : float
        Median ``|input - measured input|`` over the samples with ``|v| > v_fraction max|v|`` [A]
        or [V].
    ssse_model : float
        SSSE of the forward model with the measured input [N].
    ssse_inverse : float
        SSSE of the forward model with the inverse's input [N].
    ssse_ratio : float
        ``ssse_inverse / ssse_model`` [-].
    saturated_fraction : float
        Fraction of samples whose desired force is out of the damper's reach [-].
    """

    record: str
    model_kind: str
    input: str
    median_input_error: float
    ssse_model: float
    ssse_inverse: float
    ssse_ratio: float
    saturated_fraction: float

    def passes(self, max_input_error: float = 0.1, max_ssse_ratio: float = 1.5) -> bool:
        """True when both figures meet the given limits."""
        return bool(
            self.median_input_error <= max_input_error and self.ssse_ratio <= max_ssse_ratio
        )


def check_inverse(
    model: FittedModel, experiment: Experiment, *, v_fraction: float = 0.2, **inverse_kw: Any
) -> InverseCheck:
    """Invert ``model`` on the record's measured force and score the result (see module docstring).

    Parameters
    ----------
    model : FittedModel
        A model :func:`~mrdamper.control.inverse_current` supports.
    experiment : Experiment
        Record with the model's electrical input channel.
    v_fraction : float
        Velocity threshold as a fraction of the record's peak ``|v|`` [-].
    **inverse_kw
        Passed to :func:`~mrdamper.control.inverse_current`.
    """
    require_experiment(experiment)
    if not (0.0 <= v_fraction < 1.0):
        raise DataValidationError("v_fraction", f"expected 0 <= v_fraction < 1, got {v_fraction!r}")
    measured = np.asarray(experiment.electrical(model.input), dtype=float)
    res = inverse_current(model, experiment, experiment.F, **inverse_kw)
    speed = np.abs(np.asarray(experiment.v))
    sel = speed > v_fraction * float(speed.max())
    if not sel.any():
        raise DataValidationError(
            "experiment", f"{experiment.name!r}: no sample moves; nothing to check"
        )
    err = float(np.median(np.abs(res.i[sel] - measured[sel])))
    clip = model.with_range_policy("clip")
    own = ssse(experiment.F, clip.predict(experiment))
    inv = ssse(experiment.F, res.F_achieved)
    return InverseCheck(
        record=experiment.name,
        model_kind=model.kind,
        input=model.input,
        median_input_error=err,
        ssse_model=own,
        ssse_inverse=inv,
        ssse_ratio=inv / own if own > 0 else np.inf,
        saturated_fraction=res.saturated_fraction,
    )


def check_inverse_frame(checks: list[InverseCheck]) -> pd.DataFrame:
    """One row per :class:`InverseCheck` (columns are its attributes).

    Parameters
    ----------
    checks : list of InverseCheck
        Results of :func:`check_inverse` (one per record).
    """
    return pd.DataFrame([asdict(c) for c in checks])
