"""The values the fit template and the families pass (training data, identification result) and
the result of a free-run simulation.

Re-exported by :mod:`mrdamper.models.base` (the fit template, :class:`~mrdamper.models.Estimator`,
builds and reads them).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.metrics import Scores, score_arrays

__all__ = ["Identified", "SimulationResult", "TrainingData"]


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Free-run prediction of one record, with its scores.

    Attributes
    ----------
    experiment : Experiment
        The record simulated.
    F_pred : ndarray
        Predicted force [N].
    model_kind : str
        Kind of the model that produced it.
    elapsed : float
        Wall-clock simulation time [s].
    """

    experiment: Experiment
    F_pred: np.ndarray
    model_kind: str
    elapsed: float = 0.0

    @property
    def scores(self) -> Scores:
        """ESR, SSSE, NRMSE and fit of ``F_pred`` against the measured force."""
        return score_arrays(self.experiment.F, self.F_pred)

    def to_frame(self) -> pd.DataFrame:
        """Channels of the record plus ``F_pred`` [N]."""
        df = self.experiment.to_frame()
        df["F_pred"] = self.F_pred
        return df

    def plot(self, ax: Any = None) -> Any:
        """Plot measured and predicted force against time; returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 3))
        e = self.experiment
        ax.plot(e.t, e.F, lw=0.8, label="measured")
        ax.plot(e.t, self.F_pred, lw=0.8, label=f"{self.model_kind} (ESR {self.scores.esr:.3g})")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("F [N]")
        ax.legend(loc="best")
        return ax


@dataclass(frozen=True, eq=False)
class TrainingData:
    """Training records as :meth:`~mrdamper.models.Estimator.fit` hands them to a family's
    identification step.

    Attributes
    ----------
    records : ExperimentSet
        The training records (validated: at least one, each with motion).
    input : {"i", "voltage"}
        Electrical input channel of the estimator.
    electrical : tuple of ndarray
        That channel of every record, contiguous float64 [A] or [V] (read-only views).
    input_range : (float, float)
        Range of the electrical input over every sample of every record [A] or [V]: the model's
        identified range.
    level : float or None
        The one level of the input when it is constant over every record (see
        :func:`single_level`); the family then reduces its laws in the input to constants.
    """

    records: ExperimentSet
    input: ElectricalSource
    electrical: tuple[np.ndarray, ...]
    input_range: tuple[float, float]
    level: float | None

    @property
    def single(self) -> bool:
        """True when the electrical input takes one level over all the training data."""
        return self.level is not None


@dataclass(frozen=True, eq=False)
class Identified:
    """What a family's identification step returns: the model's own parameters and provenance.

    The common fields (``input``, ``input_range``, ``range_policy``, timings, the single-level
    note) are added by :meth:`~mrdamper.models.Estimator.fit`.

    Attributes
    ----------
    parameters : mapping
        Keyword arguments of the family's fitted-model class (its own fields only).
    provenance : mapping
        Facts about the identification (solver, costs, records, notes); no wall-clock times.
    """

    parameters: Mapping[str, Any]
    provenance: Mapping[str, Any] = field(default_factory=dict)
