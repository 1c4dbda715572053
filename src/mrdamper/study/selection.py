"""Which model for my damper? Cross-validate every model kind on the user's records.

Folds (nothing is scored on a record, or part of a record, it was trained on):

* ``"condition"``: leave one test condition out (records grouped by metadata ``condition``, as
  the sine-record file names give it), when there are at least two conditions;
* ``"record"``: records dealt round-robin (in name order) into at most ``n_folds`` groups, each
  group left out once;
* ``"time"``: one record cut into ``n_folds`` contiguous blocks; each block is left out once and
  the rest trains (the pieces before and after it as separate records, each from rest).

``folds="auto"`` takes ``"condition"`` if it applies, else ``"record"`` for two records or more,
else ``"time"``. Every model kind is fitted with its defaults (plus ``input`` and any
``settings``) on each training part and scored in free run (ESR, eq. 24) on the part left out,
with ``range_policy="clip"`` (a left-out level outside the training range is clipped and counted
in the ``clipped`` column). The recommendation is the kind with the lowest mean ESR among those
that fitted and simulated on every fold; a runner-up within 5 % is named as a tie.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.errors import DataValidationError, OutOfRangeError
from mrdamper.metrics import MIN_SCORED_SAMPLES
from mrdamper.progress import report, section

__all__ = [
    "SCORE_COLUMNS",
    "SelectionResult",
    "cross_validate",
    "selection_folds",
    "selection_from_scores",
]

#: Columns of :attr:`SelectionResult.scores`.
SCORE_COLUMNS: tuple[str, ...] = ("model", "fold", "record", "esr", "clipped", "error")

FoldKind = Literal["auto", "condition", "record", "time"]
#: Discrete-time model kinds: they need one model rate when records have different rates.
_DISCRETE = ("lpv", "lti", "narx")


@dataclass(frozen=True)
class SelectionResult:
    """Cross-validation table and recommendation.

    Attributes
    ----------
    table : DataFrame
        One row per model kind: ``mean_esr``, ``median_esr``, ``worst_esr`` (over left-out
        records), ``folds_ok``, ``folds_failed``, ``clipped`` (left-out records clipped to the
        training range), ``fit_s`` (mean fit time [s]) and ``error`` (first failure); sorted by
        ``mean_esr`` with failing kinds last.
    scores : DataFrame
        One row per (kind, fold, left-out record): ``esr``, ``error``.
    split : str
        Fold kind used (``"condition"``, ``"record"`` or ``"time"``).
    n_folds : int
        Number of folds.
    recommended : str or None
        Recommended kind (None when no kind passed every fold).
    reason : str
        One sentence saying why.
    notes : list of str
        Settings chosen for the user (e.g. a common model rate).
    """

    table: pd.DataFrame
    scores: pd.DataFrame
    split: str
    n_folds: int
    recommended: str | None
    reason: str
    notes: list[str] = field(default_factory=list)

    def to_frame(self) -> pd.DataFrame:
        """The per-kind table."""
        return self.table.copy()

    def plot(self, ax: Any = None) -> Any:
        """Bar chart of the mean validation ESR per kind (log scale); returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6, 3))
        t = self.table.dropna(subset=["mean_esr"])
        colours = ["tab:green" if k == self.recommended else "tab:blue" for k in t.index]
        ax.bar(list(t.index), t["mean_esr"].to_numpy(), color=colours)
        ax.set_yscale("log")
        ax.set_ylabel(f"mean ESR, {self.n_folds} {self.split} folds")
        return ax


def selection_folds(
    data: Experiment | Iterable[Experiment], folds: FoldKind = "auto", n_folds: int = 5
) -> tuple[str, list[tuple[str, ExperimentSet, ExperimentSet]]]:
    """Training / left-out splits of ``data``.

    Returns ``(fold kind, [(label, train, test), ...])``.
    """
    exps = as_experiment_set(data, name="data")
    if len(exps) == 0:
        raise DataValidationError("DATA", "no records given")
    if not (isinstance(n_folds, int) and n_folds >= 2):
        raise DataValidationError("n_folds", f"expected an integer >= 2, got {n_folds!r}")
    if folds not in ("auto", "condition", "record", "time"):
        raise DataValidationError(
            "folds", f"expected auto, condition, record or time, got {folds!r}"
        )
    conditions = {e.metadata.get("condition") for e in exps}
    has_cond = None not in conditions and len(conditions) >= 2
    if folds == "auto":
        folds = "condition" if has_cond else ("record" if len(exps) >= 2 else "time")
    if folds == "condition":
        if not has_cond:
            raise DataValidationError(
                "folds",
                "'condition' needs metadata 'condition' on every record and at least two "
                "conditions",
            )
        return "condition", [
            (str(c), tr, te) for c, tr, te in exps.leave_one_group_out("condition")
        ]
    if folds == "record":
        if len(exps) < 2:
            raise DataValidationError(
                "folds", "'record' needs at least two records; use 'time' for one record"
            )
        names = sorted(exps.names)
        k = min(n_folds, len(names))
        groups = [set(names[j::k]) for j in range(k)]
        out = []
        for j, g in enumerate(groups):
            tr = ExperimentSet([e for e in exps if e.name not in g], name=exps.name)
            te = ExperimentSet([e for e in exps if e.name in g], name=exps.name)
            out.append((f"records {j + 1}/{k}", tr, te))
        return "record", out
    if len(exps) != 1:
        raise DataValidationError("folds", f"'time' splits one record; got {len(exps)} records")
    e = exps[0]
    if e.n // n_folds < MIN_SCORED_SAMPLES:
        raise DataValidationError(
            "n_folds",
            f"{n_folds} time blocks of record {e.name!r} ({e.n} samples) would hold "
            f"{e.n // n_folds} sample(s) each; scoring a block needs at least "
            f"{MIN_SCORED_SAMPLES}: use at most {max(e.n // MIN_SCORED_SAMPLES, 2)} folds",
        )
    edges = np.linspace(0, e.n, n_folds + 1).round().astype(int)
    out = []
    for j in range(n_folds):
        a, b = int(edges[j]), int(edges[j + 1])
        parts = [e.slice(0, a, name=f"{e.name}[:{a}]")] if a > 0 else []
        if b < e.n:
            parts.append(e.slice(b, None, name=f"{e.name}[{b}:]"))
        out.append(
            (
                f"block {j + 1}/{n_folds}",
                ExperimentSet(parts),
                ExperimentSet([e.slice(a, b, name=f"{e.name}[{a}:{b}]")]),
            )
        )
    return "time", out


def _check_settings(kind: str, settings: Mapping[str, Any]) -> None:
    """Refuse an unknown kind, a setting ``kind`` does not take or a value it cannot use, in one
    line naming ``kind.setting`` (so that no fold runs with settings that cannot work)."""
    from mrdamper.models.registry import get_estimator, known_kinds

    if kind not in known_kinds():
        raise DataValidationError(
            kind, f"unknown model kind {kind!r}; expected one of {known_kinds()}"
        )
    try:
        get_estimator(kind, **settings)._validate()
    except DataValidationError as exc:
        raise DataValidationError(f"{kind}.{exc.field}", str(exc).split(": ", 1)[-1]) from None


def cross_validate(
    data: Experiment | Iterable[Experiment],
    *,
    models: Sequence[str] | None = None,
    folds: FoldKind = "auto",
    n_folds: int = 5,
    input: str = "i",
    settings: Mapping[str, Mapping[str, Any]] | None = None,
) -> SelectionResult:
    """Cross-validate every model kind on ``data`` and recommend one.

    Parameters
    ----------
    data : Experiment or iterable of Experiment
        The user's records.
    models : sequence of str, optional
        Model kinds (default: every available kind).
    folds : {"auto", "condition", "record", "time"}
        How to split (see the module docstring).
    n_folds : int
        Folds for ``"record"`` (at most) and ``"time"``.
    input : {"i", "voltage"}
        Electrical input channel of every model.
    settings : mapping, optional
        Extra estimator settings per kind, e.g. ``{"lpv": {"n_m": 2}}``.

    Returns
    -------
    SelectionResult

    Notes
    -----
    Reports the stage ``"cross-validation: fits"`` (fits done of the kinds times the folds) to
    :mod:`mrdamper.progress`; each fit's own stages come prefixed with the kind and fold.
    """
    from mrdamper.models.registry import available_models, get_estimator

    kinds = list(models) if models is not None else available_models()
    extra = {k: dict(v) for k, v in (settings or {}).items()}
    for kind in [*extra, *kinds]:  # every setting checked before any fold runs
        _check_settings(kind, {"input": input, **extra.get(kind, {})})
        if kind not in kinds:
            raise DataValidationError(
                f"{kind}.{next(iter(extra[kind]), '')}",
                f"a setting of {kind!r}, which is not among the models {kinds}",
            )
    exps = as_experiment_set(data, name="data")
    split, parts = selection_folds(exps, folds, n_folds)
    notes: list[str] = []
    rates = sorted({e.fs for e in exps})
    if len(rates) > 1:
        notes.append(
            f"records have rates {rates} Hz: discrete models ({', '.join(_DISCRETE)}) run at "
            f"the lowest, {rates[0]:g} Hz"
        )
    rows: list[dict[str, Any]] = []
    fit_times: dict[str, list[float]] = {k: [] for k in kinds}
    n_fits, done = len(kinds) * len(parts), 0
    for kind in kinds:
        for label, train, test in parts:
            report("cross-validation: fits", done, n_fits)
            done += 1
            fold = f"{kind}, fold {label} ({done} of {n_fits})"
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings(), section(fold):
                    warnings.simplefilter("ignore")
                    model = get_estimator(kind, **{"input": input, **extra.get(kind, {})}).fit(
                        train
                    )
            except Exception as exc:  # noqa: BLE001 - a failing kind is a row of the table
                rows += [
                    {
                        "model": kind,
                        "fold": label,
                        "record": e.name,
                        "esr": np.nan,
                        "clipped": False,
                        "error": f"fit: {type(exc).__name__}: {exc}",
                    }
                    for e in test
                ]
                continue
            fit_times[kind].append(time.perf_counter() - t0)
            report(f"{fold}: scoring the left-out data")
            for e in test:
                clipped = _outside(model, e)
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        esr = model.with_range_policy("clip").score(e).esr
                    rows.append(
                        {
                            "model": kind,
                            "fold": label,
                            "record": e.name,
                            "esr": float(esr),
                            "clipped": clipped,
                            "error": "",
                        }
                    )
                except Exception as exc:  # noqa: BLE001 - reported
                    rows.append(
                        {
                            "model": kind,
                            "fold": label,
                            "record": e.name,
                            "esr": np.nan,
                            "clipped": clipped,
                            "error": f"simulate: {type(exc).__name__}: {exc}",
                        }
                    )
    report("cross-validation: fits", n_fits, n_fits)
    scores = pd.DataFrame(rows, columns=list(SCORE_COLUMNS))
    return selection_from_scores(scores, kinds, fit_times, split, len(parts), notes)


def selection_from_scores(
    scores: pd.DataFrame,
    kinds: Sequence[str],
    fit_times: Mapping[str, Sequence[float]],
    split: str,
    n_folds: int,
    notes: Sequence[str] = (),
) -> SelectionResult:
    """The selection table and recommendation from held-out scores, by the rule of
    :func:`cross_validate` (lowest mean ESR among the kinds that passed every fold).

    :func:`cross_validate` calls it on its own folds; a study calls it on the scores of its
    protocol's folds (:attr:`mrdamper.study.StudyResult.selection`).

    Parameters
    ----------
    scores : DataFrame
        One row per (model, fold, left-out record) with the columns :data:`SCORE_COLUMNS`:
        ``esr`` (NaN when it failed), ``clipped`` (bool: the record left the model's range),
        ``error`` (empty when ok; a non-empty error fails the model's fold).
    kinds : sequence of str
        Models in table order before sorting (every one gets a row).
    fit_times : mapping
        Model -> fit times of its successful fits [s].
    split : str
        Fold kind, for the reason text.
    n_folds : int
        Number of folds.
    notes : sequence of str
        Notes carried into the result.

    Returns
    -------
    SelectionResult
    """
    missing = [c for c in SCORE_COLUMNS if c not in scores.columns]
    if missing:
        raise DataValidationError("scores", f"missing column(s) {missing}")
    times = {k: list(fit_times.get(k, ())) for k in kinds}
    table = _summarise(scores, list(kinds), times)
    recommended, reason = _recommend(table, split, n_folds)
    return SelectionResult(table, scores.copy(), split, n_folds, recommended, reason, list(notes))


def _outside(model: Any, e: Experiment) -> bool:
    try:
        model.with_range_policy("error").electrical_input(e)
    except OutOfRangeError:
        return True
    except Exception:  # noqa: BLE001 - a missing channel shows up when scoring
        return False
    return False


def _summarise(
    scores: pd.DataFrame, kinds: list[str], fit_times: Mapping[str, Sequence[float]]
) -> pd.DataFrame:
    out = []
    for k in kinds:
        s = scores[scores["model"] == k]
        failed_folds = s.loc[s["error"] != "", "fold"].nunique()
        errs = s.loc[s["error"] != "", "error"]
        esr = s["esr"].dropna()
        out.append(
            {
                "model": k,
                "mean_esr": float(esr.mean()) if failed_folds == 0 and len(esr) else np.nan,
                "median_esr": float(esr.median()) if len(esr) else np.nan,
                "worst_esr": float(esr.max()) if len(esr) else np.nan,
                "folds_ok": int(s["fold"].nunique() - failed_folds),
                "folds_failed": int(failed_folds),
                "clipped": int(s["clipped"].sum()),
                "fit_s": float(np.mean(fit_times[k])) if fit_times[k] else np.nan,
                "error": str(errs.iloc[0])[:120] if len(errs) else "",
            }
        )
    t = pd.DataFrame(out).set_index("model")
    return t.sort_values(["mean_esr", "median_esr"], na_position="last")


def _recommend(table: pd.DataFrame, split: str, n: int) -> tuple[str | None, str]:
    ok = table.dropna(subset=["mean_esr"])
    folds = f"{n} {split} fold{'s' if n != 1 else ''}"
    if ok.empty:
        return None, f"no model kind fitted and simulated on all {folds}"
    best = str(ok.index[0])
    reason = (
        f"{best} has the lowest mean free-run ESR on the left-out data, "
        f"{ok['mean_esr'].iloc[0]:.3g} over {folds} (worst left-out record "
        f"{ok['worst_esr'].iloc[0]:.3g})"
    )
    if len(ok) > 1:
        gap = ok["mean_esr"].iloc[1] / ok["mean_esr"].iloc[0] - 1.0
        reason += f"; next: {ok.index[1]} {ok['mean_esr'].iloc[1]:.3g}"
        if gap < 0.05:
            reason += f" (only {gap:.0%} higher: a tie at this data size, either will do)"
    failing = table.index[table["folds_failed"] > 0].tolist()
    if failing:
        reason += f"; failed on some fold: {', '.join(failing)}"
    return best, reason
