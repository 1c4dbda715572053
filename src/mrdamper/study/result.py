"""The outcome of a study: a value holding tables, fitted models and the figure records.

A :class:`StudyResult` draws nothing and writes nothing: its figures are
:func:`mrdamper.study.figures.make_figures`, its report :func:`mrdamper.study.report.render_report`
and its folder :func:`mrdamper.study.writer.write_study`. Those modules import this one, never
the reverse.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from mrdamper.data import Experiment
from mrdamper.models import FittedModel
from mrdamper.study.analysis_step import AnalysisOutcome
from mrdamper.study.control_step import ControlRelevance
from mrdamper.study.protocol import ModelSpec, Protocol
from mrdamper.study.selection import SelectionResult
from mrdamper.study.tables import headline, headlines, summarize

__all__ = ["Showcase", "StudyResult"]


@dataclass(frozen=True, eq=False)
class Showcase:
    """One record with every model's free-run prediction, for the time-domain figures.

    Attributes
    ----------
    fold : str
        Fold whose models made the predictions.
    record : Experiment
        The record (scored in that fold).
    predictions : dict
        Model label -> predicted force [N] (ndarray) or the error text when it failed.
    kinds : dict
        Model label -> registry kind.
    """

    fold: str
    record: Experiment
    predictions: Mapping[str, NDArray[np.float64] | str]
    kinds: Mapping[str, str] = field(default_factory=dict)

    def ok(self) -> dict[str, NDArray[np.float64]]:
        """Only the successful predictions."""
        return {k: v for k, v in self.predictions.items() if not isinstance(v, str)}


@dataclass(frozen=True, eq=False)
class StudyResult:
    """Everything a study produced.

    Attributes
    ----------
    protocol : Protocol
        The protocol run (with the models actually used in ``specs``).
    specs : tuple of ModelSpec
        Models run, in display order.
    results : DataFrame
        One row per fold x model x scored record (see ``docs/study.md`` for the columns).
    fits : DataFrame
        One row per fold x model: fit status, time, training size, error.
    roles : DataFrame
        Which record had which role (analysis, train, score) in which fold.
    models : dict
        ``(fold, label) -> FittedModel`` for every successful fit.
    analyses : dict
        ``fold -> AnalysisOutcome`` of the force-velocity analysis.
    showcase, hysteresis : Showcase or None
        Records and predictions drawn in Figs. 6, 9, 10 and Fig. 4.
    info : dict
        Seed, executor, wall time, platform.
    selection : SelectionResult or None
        The model-selection table and recommendation of ``mrdamper select``, computed from this
        study's held-out scores (scored records that trained nothing in their fold), with the
        rule of :func:`~mrdamper.study.selection.cross_validate`.
    control : ControlRelevance or None
        Every model in the quarter-car loop (:mod:`mrdamper.study.control_step`), None when the
        step was switched off.
    """

    protocol: Protocol
    specs: tuple[ModelSpec, ...]
    results: pd.DataFrame
    fits: pd.DataFrame
    roles: pd.DataFrame
    models: Mapping[tuple[str, str], FittedModel]
    analyses: Mapping[str, AnalysisOutcome]
    showcase: Showcase | None = None
    hysteresis: Showcase | None = None
    info: Mapping[str, Any] = field(default_factory=dict)
    selection: SelectionResult | None = None
    control: ControlRelevance | None = None

    @property
    def labels(self) -> list[str]:
        """Model labels in display order."""
        return [s.label for s in self.specs]

    @property
    def summary(self) -> pd.DataFrame:
        """Per-model statistics (see :func:`~mrdamper.study.tables.summarize`)."""
        return summarize(self.results, self.labels)

    def headline(self, model: str = "lpv") -> dict[str, Any]:
        """``model`` against the best of the paper's classical models (P-15, SP-1..SP-4)."""
        return headline(self.summary, model)

    def headlines(self) -> list[dict[str, Any]]:
        """The paper's LPV (static input) against the paper's classical models when the study ran
        it, then the default LPV (:func:`~mrdamper.study.tables.headlines`)."""
        return headlines(self.summary)

    def to_frame(self) -> pd.DataFrame:
        """The per-record results table."""
        return self.results

    def overlap(self) -> pd.DataFrame:
        """Scored records that also trained a model or the analysis in the same fold.

        Empty when none.
        """
        r = self.roles
        sc = r[r["role"] == "score"][["fold", "record"]]
        tr = r[r["role"] != "score"][["fold", "record", "role"]]
        return sc.merge(tr, on=["fold", "record"], how="inner")

    def plot(self, index: str = "esr", ax: Any = None) -> Any:
        """Box plot of an index per model (Figs. 7 and 8); returns the Axes.

        A thin call of :func:`mrdamper.plotting.plot_index_boxes` on :attr:`results`; the report's
        figures are :func:`mrdamper.study.figures.make_figures`.

        Parameters
        ----------
        index : str
            Column of :attr:`results` to plot (``"esr"``, ``"ssse"``, ``"nrmse"``, ``"fit_pct"``).
        ax : matplotlib Axes, optional
            Axes to draw on (a new figure when None).
        """
        from mrdamper.plotting import plot_index_boxes

        return plot_index_boxes(self.results, index=index, order=self.labels, ax=ax)
