"""The hysteretic input's open settings (``stroke`` [m], ``blend`` [-]) chosen on the records.

When a hysteretic LPV / LTI estimator leaves ``stroke`` or ``blend`` None, :func:`fit_choosing`
(the estimator's settings-choice hook of the fit template) fits the model for every candidate of
the grid :data:`~mrdamper.models.lpv.inputs.STROKES` x :data:`~mrdamper.models.lpv.inputs.BLENDS`
with at most :data:`CHOICE_NFEV` output-error iterations, scores each in free run (mean ESR,
eq. 24) and returns the estimator with the best candidate, which the template then fits on every
training record with the full budget. Where the candidates are fitted and scored is the
estimator's ``choose_on``:

``"beyond"`` (default)
    Held-out records inside and beyond the training envelope: the folds of ``"held-out"`` (whole
    records only) plus one fold that holds out the records of the highest frequency band (the
    ``"highest frequency held out"`` fold of
    :func:`mrdamper.models.envelope_folds.envelope_folds`, every current of the highest-frequency
    condition; :func:`beyond_split`), fitted on the others; a candidate's score is the mean over
    all these folds. The input's pre-yield shape decides how the model extrapolates in frequency
    and stroke, so it is chosen where the model meets records it was not fitted on, some of them
    beyond the others' band. The band's fold is left out when it would hold out more than
    :data:`MAX_BEYOND_SHARE` of the records (two sine conditions: the candidates would be fitted
    on one); with neither folds of records nor that fold (one record, three records of three
    excitations, two conditions per level), the choice is made on the training records.
``"training"``
    The candidates are fitted and scored on the training records themselves.
``"held-out"``
    Inner folds of the training records (:func:`inner_splits`): the candidates are fitted on each
    fold's inner-training part and scored on its held-out part; a candidate's score is the mean
    over the folds. The records are grouped by electrical level (their metadata ``current``, else
    the constant level of the electrical input, else one group of records with a varying input);
    in each level with at least :data:`HOLD_EVERY` records, fold ``r`` holds out the records
    ``j`` (in the order given) with ``j % HOLD_EVERY == r``, so each such record is held out once
    and every level keeps at least two records in every inner-training part (the zone laws and
    ``n_rho`` see every level). When a fold would hold out fewer than :data:`MIN_HELD_OUT` records
    (e.g. a single record, or three records of three different excitations: one held-out record
    would be a third of the variety and a noisy score), one split holding out the last
    :data:`HELD_OUT_FRACTION` of every record (in time) is used instead. Records given to the fit
    as ``choice_records`` replace the folds: the candidates are fitted on every training record
    and scored on those.

The beyond-envelope choice costs :data:`HOLD_EVERY` + 1 sets of candidate fits, the held-out
choice :data:`HOLD_EVERY` sets, the training choice one. Measured on the shared data
(``docs/results.md``), the beyond-envelope choice against the training choice: the virtual-rig
chirp 1-15 Hz 0.0204 -> 0.0065 and its road 0.0051 -> 0.0025 (full-length benchmark), Quiroz
trained up to 3 Hz and scored at 5 Hz 0.0178 -> 0.0163, the Quiroz leave-one-condition-out folds
0.01767 -> 0.01768, Labcontrol, the Quiroz cross set, Dyke and the demo unchanged. The folds of
records alone (``"held-out"``) miss the 5 Hz gain; the band's fold alone missed the full-length
chirp (0.0188: its scores were within 5 % of one another).

With ``stiffness="auto"`` (the default) and records given to the fit (``choice_records``), the
best candidate is fitted once more with the parallel stiffness identified
(:func:`mrdamper.models.lpv.fit.identify`), and the given records keep it where it predicts them
better; every grid candidate is fitted without it. Given records are the user's statement of
where the model will be used (e.g. held-out loop records: in a quarter car the stiffness acts in
the body band, where the skyhook loop's current is decided); on the inner or beyond-envelope
folds the stiffness is left out (0), because there it trades off against the pre-yield blend
(``docs/results.md``, "Parallel stiffness").

With ``eta="identify"`` on a measured current the candidates are fitted without a lag; the lag is
then identified with the chosen settings held (:func:`mrdamper.models.lag.fit_with_lag`, where no
lag is itself a candidate). For a voltage command every candidate identifies its own drive lag.

On long campaigns (a part above :data:`CHOICE_THRESHOLD` samples) the candidates are fitted and
scored on evenly spread 20 s windows of that part (:data:`CHOICE_BUDGET` samples in all;
:func:`mrdamper.models._scale.plan_windows`); the chosen candidate is then fitted on every record.
The grid, every candidate's score, and which records or blocks were held out are in the model's
provenance (``hysteretic_choice``, ``hysteretic_held_out``, ``hysteretic_note``).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable, Sequence
from typing import Any, NamedTuple

import numpy as np

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _scale
from mrdamper.models.base import Choice
from mrdamper.models.envelope_folds import envelope_folds
from mrdamper.models.lag import LAG_SETTINGS, settings_chosen_without_lag
from mrdamper.models.levels import single_level
from mrdamper.models.lpv import inputs as _inputs
from mrdamper.progress import report, section

__all__ = [
    "BEYOND_FOLD",
    "CHOICE_BUDGET",
    "CHOICE_NFEV",
    "CHOICE_THRESHOLD",
    "HELD_OUT_FRACTION",
    "HOLD_EVERY",
    "MAX_BEYOND_SHARE",
    "MIN_HELD_OUT",
    "InnerSplit",
    "beyond_split",
    "fit_choosing",
    "inner_splits",
]

#: Every HOLD_EVERY-th record of each electrical level is held out [-].
HOLD_EVERY = 3
#: Fewest whole records held out; with fewer, the records' ends are held out instead.
MIN_HELD_OUT = 2
#: Share of every record (its end, in time) held out when records are not [-].
HELD_OUT_FRACTION = 0.3
#: Samples of a part above which the candidates are compared on windows of its records, and the
#: samples those windows hold (20 s windows).
CHOICE_THRESHOLD = 250_000
CHOICE_BUDGET = 120_000
#: Output-error iteration budget of each candidate's fit (the chosen one is refitted in full).
CHOICE_NFEV = 10


class InnerSplit(NamedTuple):
    """Records the candidates are fitted on and records they are scored on.

    Attributes
    ----------
    fit, held_out : ExperimentSet
        Inner-training part and held-out part.
    fit_weights, held_out_weights : list of float or None
        Per-record weights [-] of each part (None: all 1).
    how : {"beyond", "records", "time", "given", "training"}
        The records beyond the others' envelope held out, whole records held out per level, the
        end of every record held out, records given by the caller, or no split (the training
        records score themselves).
    """

    fit: ExperimentSet
    held_out: ExperimentSet
    fit_weights: list[float] | None
    held_out_weights: list[float] | None
    how: str
    #: What the beyond-envelope split held out, in words ("" for the others).
    label: str = ""

    def record(self) -> dict[str, Any]:
        """The split as the provenance keeps it (what was held out and how)."""
        how = {
            "records": (
                f"records {HOLD_EVERY}, {2 * HOLD_EVERY}, ... of each electrical level "
                "(in the order given)"
            ),
            "time": f"the last {HELD_OUT_FRACTION:.0%} of every record",
            "given": "records given to the fit (choice_records)",
            "training": "none: scored on the training records",
            "beyond": f"beyond the envelope of the others: {self.label}",
        }[self.how]
        return {
            "how": how,
            "held_out": list(self.held_out.names),
            "inner_training": list(self.fit.names),
        }


def _level_key(e: Experiment, source: ElectricalSource) -> tuple[str, float]:
    """The electrical level a record belongs to (its metadata current, else its constant input)."""
    if "current" in e.metadata:
        return ("current", float(e.metadata["current"]))
    level = single_level(np.asarray(e.electrical(source)))
    return ("varying", 0.0) if level is None else ("level", float(f"{level:.6g}"))


def _pick(values: Sequence[float] | None, index: Iterable[int]) -> list[float] | None:
    return None if values is None else [float(values[k]) for k in index]


def inner_splits(
    exps: ExperimentSet, source: ElectricalSource, record_weights: Sequence[float] | None = None
) -> tuple[InnerSplit, ...]:
    """The inner folds of the training records that score the candidates (module docstring).

    Parameters
    ----------
    exps : ExperimentSet
        Training records.
    source : {"i", "voltage"}
        Electrical input channel (groups records with a constant input by its level).
    record_weights : sequence of float, optional
        One weight per record [-], carried into both parts.

    Returns
    -------
    tuple of InnerSplit
        :data:`HOLD_EVERY` folds of whole records (``how="records"``; fold ``r`` holds out the
        records ``j`` with ``j % HOLD_EVERY == r`` of every level with at least
        :data:`HOLD_EVERY` records, so each such record is held out once) or, when a fold would
        hold out fewer than :data:`MIN_HELD_OUT` records, one split holding out the last
        :data:`HELD_OUT_FRACTION` of every record (``how="time"``).
    """
    groups: dict[tuple[str, float], list[int]] = {}
    for k, e in enumerate(exps):
        groups.setdefault(_level_key(e, source), []).append(k)
    folds = [
        sorted(
            k
            for ks in groups.values()
            if len(ks) >= HOLD_EVERY
            for j, k in enumerate(ks)
            if j % HOLD_EVERY == r
        )
        for r in range(HOLD_EVERY)
    ]
    if all(len(held) >= MIN_HELD_OUT for held in folds):
        out = []
        for held in folds:
            kept = [k for k in range(len(exps)) if k not in set(held)]
            out.append(
                InnerSplit(
                    ExperimentSet([exps[k] for k in kept], name="inner training"),
                    ExperimentSet([exps[k] for k in held], name="held out"),
                    _pick(record_weights, kept),
                    _pick(record_weights, held),
                    "records",
                )
            )
        return tuple(out)
    cuts = [round((1.0 - HELD_OUT_FRACTION) * e.n) for e in exps]
    every = range(len(exps))
    return (
        InnerSplit(
            ExperimentSet(
                [e.slice(0, c, name=f"{e.name}[0:{c}]") for e, c in zip(exps, cuts)],
                name="inner training",
            ),
            ExperimentSet(
                [e.slice(c, e.n, name=f"{e.name}[{c}:{e.n}]") for e, c in zip(exps, cuts)],
                name="held out",
            ),
            _pick(record_weights, every),
            _pick(record_weights, every),
            "time",
        ),
    )


#: Largest share of the training records the beyond-envelope split may hold out [-]; above it
#: the candidates would be fitted on too little (e.g. one of two sine conditions) and the training
#: choice is used.
MAX_BEYOND_SHARE = 1.0 / 3.0
#: Label of the :func:`~mrdamper.models.envelope_folds.envelope_folds` fold the beyond-envelope
#: choice scores on.
BEYOND_FOLD = "beyond: highest frequency"


def beyond_split(
    exps: ExperimentSet,
    record_weights: Sequence[float] | None = None,
    source: ElectricalSource = "i",
) -> InnerSplit | None:
    """The beyond-envelope split of the training records (module docstring), or None.

    Parameters
    ----------
    exps : ExperimentSet
        Training records.
    record_weights : sequence of float, optional
        One weight per record [-].
    source : {"i", "voltage"}
        Electrical input channel (the held-out band must leave every level in the fit part).

    Returns
    -------
    InnerSplit or None
        ``how="beyond"``: the records of the highest frequency band held out; None for one
        record, records without such a band, or a band of more than :data:`MAX_BEYOND_SHARE` of
        the records.
    """
    if len(exps) < 2:
        return None
    for label, fit, held in envelope_folds(exps):
        if not label.startswith(BEYOND_FOLD):
            continue
        if len(held) > MAX_BEYOND_SHARE * len(exps):
            return None  # too little left to fit the candidates on
        if {_level_key(e, source) for e in fit} != {_level_key(e, source) for e in exps}:
            return None  # the band holds every record of a level: the zone laws would miss it
        index = {e.name: k for k, e in enumerate(exps)}
        w_fit = _pick(record_weights, [index[e.name] for e in fit])
        w_held = _pick(record_weights, [index[e.name] for e in held])
        return InnerSplit(
            ExperimentSet(list(fit), name="inner training"),
            ExperimentSet(list(held), name="held out"),
            w_fit,
            w_held,
            "beyond",
            label.removeprefix("beyond: "),
        )
    return None


def _choice_split(
    est: Any,
    exps: ExperimentSet,
    record_weights: Sequence[float] | None,
    choice_records: Experiment | Iterable[Experiment] | None,
) -> tuple[InnerSplit, ...]:
    """The folds of the estimator's ``choose_on`` (and the fit's ``choice_records``)."""
    if est.choose_on == "beyond" and choice_records is None:
        inside = inner_splits(exps, est.input, record_weights)
        folds = tuple(f for f in inside if f.how == "records")
        beyond = beyond_split(exps, record_weights, est.input)
        if folds or beyond is not None:
            return folds + (() if beyond is None else (beyond,))
    if est.choose_on == "training" or (est.choose_on == "beyond" and choice_records is None):
        if choice_records is not None:
            raise DataValidationError(
                "choice_records",
                "applies to choose_on='held-out' or 'beyond' only; got choose_on='training'",
            )
        w = _pick(record_weights, range(len(exps)))
        return (InnerSplit(exps, exps, w, w, "training"),)
    if choice_records is not None:
        given = as_experiment_set(choice_records, name="choice records")
        if len(given) == 0:
            raise DataValidationError("choice_records", "expected at least one record, got none")
        return (InnerSplit(exps, given, _pick(record_weights, range(len(exps))), None, "given"),)
    return inner_splits(exps, est.input, record_weights)


def _windowed(
    exps: ExperimentSet, weights: list[float] | None
) -> tuple[ExperimentSet, list[float] | None, dict[str, Any] | None]:
    """Evenly spread windows of a part above :data:`CHOICE_THRESHOLD` samples (else the part)."""
    plan = _scale.plan_windows(
        [e.n for e in exps],
        min(e.fs for e in exps),
        threshold=CHOICE_THRESHOLD,
        budget=CHOICE_BUDGET,
    )
    if plan is None:
        return exps, weights, None
    wins = ExperimentSet(
        [exps[r].slice(a, b, name=f"{exps[r].name}[{a}:{b}]") for r, a, b in plan], name="windows"
    )
    info = {"windows": len(plan), "samples_used": int(sum(b - a for _, a, b in plan))}
    return wins, _pick(weights, [r for r, _, _ in plan]), info


def _candidates(est: Any) -> list[tuple[float, float]]:
    strokes = _inputs.STROKES if est.stroke is None else (float(est.stroke),)
    blends = _inputs.BLENDS if est.blend is None else (float(est.blend),)
    return [(x_y, lam) for x_y in strokes for lam in blends]


def fit_choosing(
    est: Any,
    exps: ExperimentSet,
    record_weights: Sequence[float] | None,
    choice_records: Experiment | Iterable[Experiment] | None = None,
) -> Choice:
    """Fit every grid candidate of ``stroke`` / ``blend`` and choose the lowest mean free-run ESR
    on the held-out part of the estimator's split (module docstring).

    Parameters
    ----------
    est : LPVEstimator
        Estimator with ``stroke`` or ``blend`` None; its ``choose_on`` says where candidates are
        scored.
    exps : ExperimentSet
        Training records.
    record_weights : sequence of float, optional
        Per-record weights [-] of the fits and of the mean ESR.
    choice_records : Experiment or iterable of Experiment, optional
        Records that score the candidates instead of the inner split (``choose_on="held-out"`` or
        ``"beyond"``).

    Returns
    -------
    Choice
        The estimator with the chosen ``stroke`` and ``blend`` (the fit template fits it on every
        training record) and the provenance of the choice.

    Raises
    ------
    IdentificationError
        When no candidate could be fitted (the first failure is named).
    DataValidationError
        ``choice_records`` with ``choose_on="training"``, or empty.
    """
    folds = [_Fold(split) for split in _choice_split(est, exps, record_weights, choice_records)]
    how = folds[0].split.how
    key = "train_esr" if how == "training" else "held_out_esr"
    nfev = min(est.max_nfev, CHOICE_NFEV)
    rows: list[dict[str, Any]] = []
    best: tuple[float, float, float] | None = None
    first_error = ""
    cands = _candidates(est)
    # a measured current's lag is identified after this choice, with its result held
    held: dict[str, Any] = {"eta": None} if settings_chosen_without_lag(est) else {}
    if est.stiffness == "auto":
        held["stiffness"] = 0.0
    for k, (x_y, lam) in enumerate(cands, start=1):
        cand = dataclasses.replace(est, stroke=x_y, blend=lam, max_nfev=nfev, **held)
        report("hysteretic input: candidate", k - 1, len(cands))
        fold_esr, error = _scored(cand, folds, f"hysteretic candidate {k} of {len(cands)}")
        if fold_esr is None:
            first_error = first_error or f"stroke={x_y:g} m, blend={lam:g}: {error}"
            rows.append({"stroke": x_y, "blend": lam, key: None, "error": error})
            continue
        score = float(np.mean(fold_esr))
        row = {"stroke": x_y, "blend": lam, key: score, "error": error}
        if len(folds) > 1:
            row["fold_esr"] = fold_esr
        rows.append(row)
        if best is None or score < best[0]:
            best = (score, x_y, lam)
    if best is None:
        raise IdentificationError(
            f"{est.kind}: no hysteretic-input candidate could be fitted; {first_error}"
        )
    report("hysteretic input: candidate", len(cands), len(cands))
    chosen = dataclasses.replace(est, stroke=best[1], blend=best[2])
    note = _note(best, len(rows), nfev, [f.split for f in folds])
    if est.stiffness == "auto" and how == "given":
        stiff = dataclasses.replace(chosen, max_nfev=nfev, **{**held, "stiffness": "identify"})
        fold_esr, error = _scored(stiff, folds, "hysteretic candidate with a stiffness")
        score = float("inf") if fold_esr is None else float(np.mean(fold_esr))
        rows.append(
            {
                "stroke": best[1],
                "blend": best[2],
                "stiffness": "identify",
                key: score,
                "error": error,
            }
        )
        keep = score < best[0]
        chosen = dataclasses.replace(chosen, stiffness="identify" if keep else 0.0)
        note += (
            f"; the parallel stiffness identified scores {score:.4g} against {best[0]:.4g} "
            f"without it on the given records: {'identified' if keep else 'none'}"
        )

    def provenance(prov: dict[str, Any]) -> dict[str, Any]:
        prov = {**prov, "hysteretic_choice": rows, "hysteretic_note": note}
        prov["settings"] = {
            **prov.get("settings", {}),
            "stroke": est.stroke,
            "blend": est.blend,
            "stiffness": est.stiffness,
        }
        if how != "training":
            records = [f.split.record() for f in folds]
            prov["hysteretic_held_out"] = (
                records[0]
                if len(records) == 1
                else {"how": "; ".join(dict.fromkeys(r["how"] for r in records)), "folds": records}
            )
        windows = [f.windows for f in folds if f.windows is not None]
        if windows:
            prov["hysteretic_windows"] = {
                **windows[0],
                "note": "stroke and blend chosen on evenly spread windows; the model fitted on all",
            }
        return prov

    return Choice(chosen, provenance)


def _scored(cand: Any, folds: Sequence[_Fold], label: str) -> tuple[list[float] | None, str]:
    """``cand`` fitted and scored on every fold: its free-run ESR per fold and the reasons of the
    folds whose free run diverged; None and the reason when a fit failed."""
    with warnings.catch_warnings(), section(label):
        warnings.simplefilter("ignore")  # the chosen fit speaks for itself
        try:
            scores = [fold.score(cand) for fold in folds]
        except IdentificationError as exc:
            return None, str(exc)
    return [sc for sc, _ in scores], "; ".join(e for _, e in scores if e)


class _Fold:
    """One fold of the choice: its part to fit and its part to score, windowed when long."""

    def __init__(self, split: InnerSplit) -> None:
        self.split = split
        self.fit_set, self.fit_w, fit_win = _windowed(split.fit, split.fit_weights)
        if split.how == "training":
            self.score_set, score_w, score_win = self.fit_set, self.fit_w, None
        else:
            self.score_set, score_w, score_win = _windowed(split.held_out, split.held_out_weights)
        self.w = np.ones(len(self.score_set)) if score_w is None else np.asarray(score_w, float)
        #: Zone laws of the fit part, once a candidate has fitted them (see :meth:`score`).
        self.laws: Any = None
        self.windows: dict[str, Any] | None = None
        if fit_win is not None or score_win is not None:
            self.windows = {
                **(
                    fit_win
                    or {"windows": len(self.fit_set), "samples_used": _samples(self.fit_set)}
                ),
                "scored_on": score_win,
            }

    def score(self, cand: Any) -> tuple[float, str]:
        """The candidate fitted on the fold's fit part: its mean free-run ESR on the scored part
        (inf, with the reason, when a free run diverges).

        The zone laws depend on the fit part alone, not on the stroke and blend: the first
        candidate that fits them leaves them to the fold's next candidates (given as
        ``zone_laws``), unless a drive lag is identified per candidate (the laws then follow
        each candidate's lag)."""
        shared = cand.zone_laws is None and cand.eta not in LAG_SETTINGS
        if shared and self.laws is not None:
            cand = dataclasses.replace(cand, zone_laws=self.laws)
        model = cand.fit(self.fit_set, record_weights=self.fit_w)
        if shared and self.laws is None:
            self.laws = model.zone_laws
        report(f"free-run ESR on the {self.split.held_out.name} records")
        try:
            esr = [model.with_range_policy("ignore").score(e).esr for e in self.score_set]
        except SimulationDivergedError as exc:  # e.g. an unrefined, unstable candidate
            return float("inf"), str(exc)
        return float(np.average(esr, weights=self.w)), ""


def _samples(exps: ExperimentSet) -> int:
    return int(sum(e.n for e in exps))


def _note(best: tuple[float, float, float], n: int, nfev: int, splits: Sequence[InnerSplit]) -> str:
    """One line on what was chosen, where it was scored and how."""
    score, x_y, lam = best
    split = splits[0]
    if not np.isfinite(score):
        return (
            f"every candidate diverged in free run on the {split.held_out.name} records; the first "
            f"(stroke = {x_y:g} m, blend = {lam:g}) is returned"
        )
    n_out, n_in = len(split.held_out), len(split.fit)
    band = [f for f in splits if f.how == "beyond"]
    if band and len(splits) > 1:
        return (
            f"stroke = {x_y:g} m and blend = {lam:g} chosen on {len(splits) - 1} folds of held-out "
            f"records and the records beyond the others' envelope ({band[0].label}), each fitted "
            f"on the others (lowest mean free-run ESR over the folds of {n} candidates, each "
            f"refined with at most {nfev} iterations)"
        )
    where = {
        "training": "the training records",
        "records": f"{len(splits)} folds of held-out records (each record of a level with at "
        f"least {HOLD_EVERY} records held out once; mean over the folds), fitted on the others",
        "time": f"the last {HELD_OUT_FRACTION:.0%} of the {n_out} records, fitted on the rest",
        "given": f"{n_out} given records (choice_records), fitted on the {n_in} training records",
        "beyond": f"{n_out} held-out record(s) beyond the envelope of the other {n_in} "
        f"({split.label}), fitted on those",
    }[split.how]
    return (
        f"stroke = {x_y:g} m and blend = {lam:g} chosen on {where} (lowest mean free-run ESR of "
        f"{n} candidates, each refined with at most {nfev} iterations)"
    )
