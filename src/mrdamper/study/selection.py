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
in the ``clipped`` column).

Beyond the training envelope (``beyond=True``, default): every kind is also scored on the folds of
:func:`mrdamper.models.envelope_folds.envelope_folds` (the largest amplitude, the highest frequency
or velocity, and the lowest frequency held out; for one record, a later block whose range exceeds
the earlier one's), and
(``stress=True``, default) fitted once on all the records and stress-tested
(:func:`mrdamper.study.stress.stress_test`: motions beyond the envelope must stay bounded,
dissipative and free of divergence; new motions inside it must be free of bursts).

The recommendation is the kind with the lowest ``rank_esr`` among those that fitted and simulated
on every fold (inside and beyond the envelope) and passed the stress test, and that are not
interpolation-only (:attr:`mrdamper.kinds.KindSpec.interpolation_only`: NARX) when the selection
validates beyond the envelope (beyond-envelope folds or the stress test); ``rank_esr`` is the mean
of the in-envelope mean ESR and the beyond-envelope mean ESR (the in-envelope mean alone when there
is no beyond-envelope fold). Kinds within :data:`TIE` (5 %) of the lowest ``rank_esr`` tie (the
difference is within what the folds can tell apart); among them the one with the lowest worst
left-out record (``worst_esr``) is recommended when that record is more than 5 % better than the
first-ranked kind's (the one that fails least badly on a condition it was not trained on),
otherwise the first-ranked kind. The ``status`` column says
why a kind is not recommended; the reason states the envelope the recommendation was validated in.

The fits run on worker processes, with successive halving (a kind far above the leader after its
first two fits runs no further fit) and an optional time budget
(:mod:`mrdamper.study._select_run`); a kind stopped early is not recommended, and its status says
why.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError
from mrdamper.metrics import MIN_SCORED_SAMPLES

__all__ = [
    "HALVING",
    "SCORE_COLUMNS",
    "SelectionResult",
    "cross_validate",
    "selection_folds",
    "selection_from_scores",
]

#: Columns of :attr:`SelectionResult.scores` (``beyond``: the fold leaves the training envelope;
#: optional in :func:`selection_from_scores`, False when absent).
SCORE_COLUMNS: tuple[str, ...] = ("model", "fold", "record", "esr", "clipped", "error", "beyond")
_REQUIRED: tuple[str, ...] = SCORE_COLUMNS[:-1]
#: Kinds within this fraction of the lowest ``rank_esr`` tie; the lowest ``worst_esr`` decides [-].
TIE = 0.05
#: Successive-halving factor of :func:`cross_validate` [-]: a kind whose first fits estimate a
#: ``rank_esr`` more than this many times the leader's runs no further fit.
HALVING = 3.0

#: Why an interpolation-only kind (:attr:`mrdamper.kinds.KindSpec.interpolation_only`) is not
#: recommended when the selection validates beyond the training envelope.
INTERPOLATION_ONLY = (
    "interpolation-only (a black-box model: nothing in its structure carries it beyond the "
    "training envelope)"
)

FoldKind = Literal["auto", "condition", "record", "time"]
#: The fold schemes, typed (for the callers that check a name against them).
FOLD_KINDS: tuple[FoldKind, ...] = ("auto", "condition", "record", "time")


@dataclass(frozen=True)
class SelectionResult:
    """Cross-validation table and recommendation.

    Attributes
    ----------
    table : DataFrame
        One row per model kind: ``mean_esr``, ``median_esr``, ``worst_esr`` (over left-out
        records inside the envelope), ``folds_ok``, ``folds_failed``, ``beyond_esr`` (mean over
        the beyond-envelope folds; NaN without them), ``beyond_failed``, ``rank_esr`` (the
        ranking index, see the module docstring), ``stress`` (``"ok"``, the first failure, or
        ``"-"`` when not run), ``clipped`` (left-out records clipped to the training range),
        ``fit_s`` (mean fit time [s]), ``error`` (first failure) and ``status``
        (``"recommended"``, ``"eligible"`` or why not); sorted by ``rank_esr``, kinds that cannot
        be recommended last.
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
    n_beyond : int
        Number of beyond-envelope folds.
    stress : dict
        Kind -> :class:`~mrdamper.study.stress.StressResult` (empty when not run).
    envelope : str
        The envelope of the records, in words (what the recommendation was validated in).
    """

    table: pd.DataFrame
    scores: pd.DataFrame
    split: str
    n_folds: int
    recommended: str | None
    reason: str
    notes: list[str] = field(default_factory=list)
    n_beyond: int = 0
    stress: dict[str, Any] = field(default_factory=dict)
    envelope: str = ""

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


def _model_rate_note(
    kinds: Sequence[str], rates: Sequence[float], settings: Mapping[str, Mapping[str, Any]]
) -> str | None:
    """One line saying at which rate each discrete kind runs (by the rule of
    :func:`mrdamper.models.rates.rate_rule`), when the records have several rates or a kind runs
    above them; None otherwise."""
    from mrdamper.models.rates import rate_rule
    from mrdamper.models.registry import get_estimator

    groups: dict[float, list[str]] = {}
    floors: list[str] = []
    for kind in kinds:
        est = get_estimator(kind, **settings.get(kind, {}))
        if "model_fs" in est.settings_names():
            floor = type(est).min_model_fs
            fs = rate_rule(rates, getattr(est, "model_fs", None), floor)
            groups.setdefault(fs, []).append(kind)
            if floor is not None:
                floors.append(f"{kind} at least {floor:g} Hz")
    if not groups or (len(rates) == 1 and set(groups) == {float(rates[0])}):
        return None
    runs = "; ".join(f"{', '.join(ks)} at {fs:g} Hz" for fs, ks in sorted(groups.items()))
    rule = f" ({', '.join(floors)})" if floors else ""
    return (
        f"records have rates {[float(r) for r in rates]} Hz: discrete models run at the lowest "
        f"record rate{rule} unless model_fs is set: {runs}"
    )


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


def _check_run(workers: Any, halving: Any, time_budget: Any) -> None:
    """Refuse run settings that cannot work, in one line naming the setting."""
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise DataValidationError("workers", f"expected a positive integer, got {workers!r}")
    for name, value, low in (("halving", halving, 1.0), ("time_budget", time_budget, 0.0)):
        if value is None:
            continue
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if not ok or not np.isfinite(value) or value <= low:
            raise DataValidationError(name, f"expected a number above {low:g}, got {value!r}")


def cross_validate(
    data: Experiment | Iterable[Experiment],
    *,
    models: Sequence[str] | None = None,
    folds: FoldKind = "auto",
    n_folds: int = 5,
    input: ElectricalSource = "i",
    settings: Mapping[str, Mapping[str, Any]] | None = None,
    beyond: bool = True,
    stress: bool = True,
    seed: int = 0,
    workers: int | None = None,
    halving: float | None = HALVING,
    time_budget: float | None = None,
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
    beyond : bool
        Also score every kind on the folds that leave the training envelope.
    stress : bool
        Also fit every kind on all the records and stress-test it.
    seed : int
        Seed of the stress test's random motion.
    workers : int, optional
        Worker processes the fits run on (default: the cores this process may use); 1 runs them
        in this process. The result does not depend on it.
    halving : float or None
        Successive halving (:mod:`mrdamper.study._select_run`): a kind whose first two fits
        estimate a ``rank_esr`` more than ``halving`` times the leader's runs no further fit
        (default :data:`HALVING`); None fits every kind on every fold.
    time_budget : float, optional
        No fit starts after this many seconds [s]; the kinds left with fits not run are listed
        as not compared. None (default): no limit.

    Returns
    -------
    SelectionResult

    Raises
    ------
    DataValidationError
        An unknown kind or setting, ``workers`` not a positive integer, ``halving`` not a number
        above 1 or ``time_budget`` not a positive number.

    Notes
    -----
    Reports the stage ``"cross-validation: fits"`` (fits done of the kinds times the folds, plus
    one fit on all the records per kind when ``stress``) to :mod:`mrdamper.progress`, and each
    kind, when its last fit is in, as a finished step (:func:`mrdamper.progress.finished`). With
    one worker each fit's own stages come prefixed with the kind and fold.
    """
    _check_run(workers, halving, time_budget)
    from mrdamper.kinds import spec
    from mrdamper.models.envelope_folds import envelope_folds
    from mrdamper.models.registry import available_models
    from mrdamper.study._select_run import Plan, run_plan

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
    extra_parts = envelope_folds(exps) if beyond else []
    notes: list[str] = []
    rate_note = _model_rate_note(kinds, sorted({e.fs for e in exps}), extra)
    if rate_note:
        notes.append(rate_note)
    if beyond and not extra_parts:
        notes.append(
            "no fold leaves the training envelope (the records share one range, or the later "
            "part of the record stays within the earlier one's): validated inside it only"
        )
    validates_beyond = bool(extra_parts) or stress
    plan = Plan(
        kinds=kinds,
        options={k: {"input": input, **extra.get(k, {})} for k in kinds},
        folds=[(*p, False) for p in parts] + [(*p, True) for p in extra_parts],
        records=exps,
        stress=stress,
        seed=seed,
        recommendable={
            k: not (validates_beyond and getattr(spec(k), "interpolation_only", False))
            for k in kinds
        },
    )
    run = run_plan(plan, workers=workers, halving=halving, time_budget=time_budget)
    scores = pd.DataFrame(run.rows, columns=list(SCORE_COLUMNS))
    return selection_from_scores(
        scores,
        kinds,
        run.fit_times,
        split,
        len(parts),
        [*notes, *run.notes],
        stress=run.stress,
        envelope=_envelope_text(exps, input),
        stopped=run.stopped,
    )


def _envelope_text(exps: ExperimentSet, source: ElectricalSource) -> str:
    """The records' envelope in words (velocity, displacement, frequency band, input)."""
    from mrdamper.models.envelope import envelope_of

    try:
        elec = [np.asarray(e.electrical(source)) for e in exps]
    except Exception:  # noqa: BLE001 - a missing channel fails every fit anyway
        return ""
    env = envelope_of([e.x for e in exps], [e.v for e in exps], elec, dt=[e.dt for e in exps])
    unit = "A" if source == "i" else "V"
    lo, hi = env["x_range"]
    return (
        f"|v| <= {env['v_max']:.3g} m/s, x in [{lo * 1e3:.3g}, {hi * 1e3:.3g}] mm, frequency "
        f"band <= {env['f_band']:.3g} Hz, {source} in [{env['e_range'][0]:.3g}, "
        f"{env['e_range'][1]:.3g}] {unit}"
    )


def selection_from_scores(
    scores: pd.DataFrame,
    kinds: Sequence[str],
    fit_times: Mapping[str, Sequence[float]],
    split: str,
    n_folds: int,
    notes: Sequence[str] = (),
    *,
    stress: Mapping[str, Any] | None = None,
    envelope: str = "",
    stopped: Mapping[str, str] | None = None,
) -> SelectionResult:
    """The selection table and recommendation from held-out scores, by the rule of
    :func:`cross_validate` (module docstring).

    :func:`cross_validate` calls it on its own folds; a study calls it on the scores of its
    protocol's folds (:attr:`mrdamper.study.StudyResult.selection`).

    Parameters
    ----------
    scores : DataFrame
        One row per (model, fold, left-out record) with the columns :data:`SCORE_COLUMNS`:
        ``esr`` (NaN when it failed), ``clipped`` (bool: the record left the model's range),
        ``error`` (empty when ok; a non-empty error fails the model's fold), ``beyond``
        (optional: the fold leaves the training envelope).
    kinds : sequence of str
        Models in table order before sorting (every one gets a row).
    fit_times : mapping
        Model -> fit times of its successful fits [s].
    split : str
        Fold kind, for the reason text.
    n_folds : int
        Number of folds inside the envelope.
    notes : sequence of str
        Notes carried into the result.
    stress : mapping, optional
        Model -> :class:`~mrdamper.study.stress.StressResult` (models without one: ``"-"``).
    envelope : str
        The records' envelope in words, for the reason.
    stopped : mapping, optional
        Model -> why it ran only some of its fits (successive halving, a time budget): such a
        model is not recommended, and its status says why.

    Returns
    -------
    SelectionResult
    """
    missing = [c for c in _REQUIRED if c not in scores.columns]
    if missing:
        raise DataValidationError("scores", f"missing column(s) {missing}")
    scores = scores.copy()
    if "beyond" not in scores.columns:
        scores["beyond"] = False
    scores["beyond"] = scores["beyond"].eq(True)
    times = {k: list(fit_times.get(k, ())) for k in kinds}
    stress = dict(stress or {})
    n_beyond = int(scores.loc[scores["beyond"], "fold"].nunique())
    table = _summarise(
        scores, list(kinds), times, stress, dict(stopped or {}), beyond=bool(n_beyond or stress)
    )
    recommended, reason = _recommend(table, split, n_folds, n_beyond, envelope)
    if recommended is not None:
        table.loc[recommended, "status"] = "recommended"
    return SelectionResult(
        table,
        scores,
        split,
        n_folds,
        recommended,
        reason,
        list(notes),
        n_beyond,
        stress,
        envelope,
    )


def _summarise(
    scores: pd.DataFrame,
    kinds: list[str],
    fit_times: Mapping[str, Sequence[float]],
    stress: Mapping[str, Any],
    stopped: Mapping[str, str],
    *,
    beyond: bool,
) -> pd.DataFrame:
    from mrdamper.kinds import spec

    out = []
    for k in kinds:
        every = scores[scores["model"] == k]
        s = every[~every["beyond"]]
        b = every[every["beyond"]]
        failed_folds = s.loc[s["error"] != "", "fold"].nunique()
        b_failed = b.loc[b["error"] != "", "fold"].nunique()
        errs = every.loc[every["error"] != "", "error"]
        esr = s["esr"].dropna()
        mean = float(esr.mean()) if failed_folds == 0 and len(esr) else np.nan
        b_esr = float(b["esr"].mean()) if len(b) and b_failed == 0 else np.nan
        rank = mean if b.empty else (0.5 * (mean + b_esr) if np.isfinite(b_esr) else np.nan)
        st = stress.get(k)
        st_text = "-" if st is None else str(st.reason)
        if st is None and k in stopped:
            st_text = "not run"
        status = "eligible"
        if k in stopped and not (failed_folds or b_failed):
            status = f"not recommended: {stopped[k]}"
        elif failed_folds:
            status = f"not recommended: failed {failed_folds} fold(s)"
        elif b_failed:
            status = "not recommended: failed beyond the training envelope"
        elif st is not None and not st.passed:
            status = f"not recommended: stress test: {st.reason}"
        elif not np.isfinite(rank):
            status = "not recommended: no score"
        elif beyond and getattr(spec(k), "interpolation_only", False):
            status = f"not recommended: {INTERPOLATION_ONLY}"
        out.append(
            {
                "model": k,
                "mean_esr": mean,
                "median_esr": float(esr.median()) if len(esr) else np.nan,
                "worst_esr": float(esr.max()) if len(esr) else np.nan,
                "folds_ok": int(s["fold"].nunique() - failed_folds),
                "folds_failed": int(failed_folds),
                "beyond_esr": b_esr,
                "beyond_failed": int(b_failed),
                "rank_esr": rank,
                "stress": st_text[:160],
                "clipped": int(s["clipped"].sum()),
                "fit_s": float(np.mean(fit_times[k])) if fit_times[k] else np.nan,
                "error": str(errs.iloc[0])[:120] if len(errs) else "",
                "status": status,
            }
        )
    t = pd.DataFrame(out).set_index("model")
    t["_ok"] = t["status"] == "eligible"
    t = t.sort_values(["_ok", "rank_esr", "median_esr"], ascending=[False, True, True])
    return t.drop(columns="_ok")


def _recommend(
    table: pd.DataFrame, split: str, n: int, n_beyond: int, envelope: str
) -> tuple[str | None, str]:
    ok = table[table["status"] == "eligible"]
    folds = f"{n} {split} fold{'s' if n != 1 else ''}"
    if n_beyond:
        folds += f" and {n_beyond} beyond-envelope fold{'s' if n_beyond != 1 else ''}"
    if ok.empty:
        return None, f"no model kind fitted, simulated and passed every check on {folds}"
    tied = ok[ok["rank_esr"] <= (1.0 + TIE) * ok["rank_esr"].iloc[0]]
    best = str(ok.index[0])
    if tied["worst_esr"].notna().any():
        safest = str(tied["worst_esr"].idxmin())
        if tied.loc[safest, "worst_esr"] < (1.0 - TIE) * tied.loc[best, "worst_esr"]:
            best = safest
    first = ok.loc[best]
    what = (
        "mean free-run ESR (inside and beyond the training envelope, averaged)"
        if n_beyond
        else "mean free-run ESR on the left-out data"
    )
    beyond = f"; beyond {first['beyond_esr']:.3g}" if n_beyond else ""
    if len(tied) > 1:
        rivals = tied.drop(index=best)
        lead = (
            f"{best} ties with {', '.join(rivals.index)} on the {what} (within {TIE:.0%} of the "
            f"lowest, {ok['rank_esr'].iloc[0]:.3g}, which these folds cannot tell apart)"
        )
        if best != str(ok.index[0]):
            lead += (
                f" and has the lowest worst left-out record, {first['worst_esr']:.3g} against "
                + ", ".join(f"{r['worst_esr']:.3g} ({k})" for k, r in rivals.iterrows())
            )
        else:
            lead += (
                ", has the lowest mean free-run ESR of them and a worst left-out record no "
                f"more than {TIE:.0%} above theirs"
            )
        reason = (
            f"{lead}: {first['rank_esr']:.3g} over {folds} (inside {first['mean_esr']:.3g}{beyond})"
        )
    else:
        reason = (
            f"{best} has the lowest {what}, {first['rank_esr']:.3g} over {folds} (inside "
            f"{first['mean_esr']:.3g}, worst left-out record {first['worst_esr']:.3g}{beyond})"
        )
        if len(ok) > 1:
            reason += f"; next: {ok.index[1]} {ok['rank_esr'].iloc[1]:.3g}"
    failing = table.index[table["status"].str.startswith("not recommended")].tolist()
    if failing:
        reason += f"; not recommended: {', '.join(failing)} (see status)"
    if envelope:
        reason += f". Validated within {envelope}"
        if n_beyond or first["stress"] == "ok":
            reason += (
                " and beyond it ("
                + ", ".join(
                    (["held-out folds beyond the training part"] if n_beyond else [])
                    + (
                        ["stress motions to amplitude x1.5, frequency x2"]
                        if first["stress"] == "ok"
                        else []
                    )
                )
                + ")"
            )
    return best, reason
