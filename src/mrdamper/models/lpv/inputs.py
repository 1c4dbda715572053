"""The hysteretic LPV input (``input_signal="hysteretic"``): settings, model input and the choice
of its stroke scale and pre-yield share on the training records.

The input itself is :func:`mrdamper.analysis.hysteretic.hysteretic_input`. When the estimator's
``stroke`` [m] or ``blend`` [-] is None, the model is fitted for every value of a small grid and
the one with the lowest mean free-run ESR on the training records is returned (the grid and its
scores are in ``provenance["hysteretic_choice"]``). Nothing but the training records is used.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.data import ExperimentSet
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _scale
from mrdamper.progress import report, section

__all__ = [
    "BLENDS",
    "STROKES",
    "check_model",
    "fit_choosing",
    "model_settings",
    "needs_choice",
]

#: Candidate stroke scales ``x_y`` [m] when ``stroke`` is not given.
STROKES: tuple[float, ...] = (5e-5, 1e-4, 2e-4)
#: Candidate pre-yield shares ``lambda`` [-] when ``blend`` is not given.
BLENDS: tuple[float, ...] = (0.25, 0.5)
#: Training samples above which the candidates are compared on windows of the records, and the
#: samples those windows hold (20 s windows): the comparison costs six fits.
CHOICE_THRESHOLD = 250_000
CHOICE_BUDGET = 120_000
#: Output-error iteration budget of each candidate's fit (the chosen one is refitted in full).
CHOICE_NFEV = 10


def _check_stroke(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
        raise DataValidationError("stroke", f"expected a stroke scale [m], got {value!r}")
    if not (np.isfinite(value) and value > 0):
        raise DataValidationError("stroke", f"expected a positive stroke scale [m], got {value!r}")
    return float(value)


def _check_blend(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
        raise DataValidationError("blend", f"expected a share in [0, 1], got {value!r}")
    if not (np.isfinite(value) and 0.0 <= value <= 1.0):
        raise DataValidationError("blend", f"expected a share in [0, 1], got {value!r}")
    return float(value)


def _check_others(obj: Any) -> None:
    for name in ("stroke", "blend"):
        if getattr(obj, name) is not None:
            raise DataValidationError(
                name,
                f"applies to input_signal='hysteretic' only; got {name}={getattr(obj, name)!r} "
                f"with input_signal={obj.input_signal!r}",
            )


def check_model(model: Any) -> None:
    """Validate (and store as floats) a fitted model's ``stroke`` and ``blend``."""
    if model.input_signal != "hysteretic":
        _check_others(model)
        return
    if model.stroke is None or model.blend is None:
        raise DataValidationError(
            "stroke", "input_signal='hysteretic' needs both stroke [m] and blend [-]"
        )
    if model.reading != "continuous":
        raise DataValidationError(
            "reading",
            f"the hysteretic input builds on the continuous reading, got {model.reading!r}",
        )
    object.__setattr__(model, "stroke", _check_stroke(model.stroke))
    object.__setattr__(model, "blend", _check_blend(model.blend))


def model_settings(est: Any) -> dict[str, Any]:
    """Fields of the fitted model that carry the hysteretic input's settings."""
    if est.input_signal != "hysteretic":
        return {}
    return {"stroke": est.stroke, "blend": est.blend}


def needs_choice(est: Any) -> bool:
    """Validate the estimator's ``stroke`` / ``blend``; True when one must be chosen."""
    if est.input_signal != "hysteretic":
        _check_others(est)
        return False
    if est.reading != "continuous":
        raise DataValidationError(
            "reading", f"the hysteretic input builds on the continuous reading, got {est.reading!r}"
        )
    if est.stroke is not None:
        _check_stroke(est.stroke)
    if est.blend is not None:
        _check_blend(est.blend)
    return est.stroke is None or est.blend is None


def fit_choosing(est: Any, exps: ExperimentSet, record_weights: Sequence[float] | None) -> Any:
    """Fit every grid candidate of ``stroke`` / ``blend``; keep the lowest mean training ESR.

    The criterion is the mean free-run ESR over the training records (weighted by
    ``record_weights`` when given), the quantity the default ``weighting="esr"`` minimises, of each
    candidate fitted with at most :data:`CHOICE_NFEV` output-error iterations; the chosen
    candidate is then fitted with the estimator's full budget. On
    long campaigns (more than :data:`CHOICE_THRESHOLD` samples) the candidates are fitted and
    scored on evenly spread 20 s windows of the records (:data:`CHOICE_BUDGET` samples in all), and
    the chosen candidate is then fitted on every record.

    Raises
    ------
    IdentificationError
        When no candidate could be fitted (the first failure is named).
    """
    strokes = STROKES if est.stroke is None else (float(est.stroke),)
    blends = BLENDS if est.blend is None else (float(est.blend),)
    plan = _scale.plan_windows(
        [e.n for e in exps],
        min(e.fs for e in exps),
        threshold=CHOICE_THRESHOLD,
        budget=CHOICE_BUDGET,
    )
    full, full_weights = exps, record_weights
    if plan is not None:  # long campaign: choose on windows, refit the choice on everything
        exps = ExperimentSet(
            [exps[r].slice(a, b, name=f"{exps[r].name}[{a}:{b}]") for r, a, b in plan],
            name="windows",
        )
        if record_weights is not None:
            record_weights = [float(record_weights[r]) for r, _, _ in plan]
    w = np.ones(len(exps)) if record_weights is None else np.asarray(record_weights, dtype=float)
    rows: list[dict[str, Any]] = []
    best: tuple[float, float, float] | None = None
    first_error = ""
    n_cand = len(strokes) * len(blends)
    for x_y in strokes:
        for lam in blends:
            cand = dataclasses.replace(
                est, stroke=x_y, blend=lam, max_nfev=min(est.max_nfev, CHOICE_NFEV)
            )
            k = len(rows) + 1
            report("hysteretic input: candidate", k - 1, n_cand)
            with warnings.catch_warnings(), section(f"hysteretic candidate {k} of {n_cand}"):
                warnings.simplefilter("ignore")  # the chosen fit below speaks for itself
                try:
                    model = cand.fit(exps, record_weights=record_weights)
                except IdentificationError as exc:
                    first_error = first_error or f"stroke={x_y:g} m, blend={lam:g}: {exc}"
                    rows.append({"stroke": x_y, "blend": lam, "train_esr": None, "error": str(exc)})
                    continue
                try:
                    report("free-run ESR on the training records")
                    esr = [model.with_range_policy("ignore").score(e).esr for e in exps]
                    score, err = float(np.average(esr, weights=w)), ""
                except SimulationDivergedError as exc:  # e.g. an unrefined, unstable candidate
                    score, err = float("inf"), str(exc)
            rows.append({"stroke": x_y, "blend": lam, "train_esr": score, "error": err})
            if best is None or score < best[0]:
                best = (score, x_y, lam)
    if best is None:
        raise IdentificationError(
            f"{est.kind}: no hysteretic-input candidate could be fitted; {first_error}"
        )
    report("hysteretic input: candidate", n_cand, n_cand)
    final = dataclasses.replace(est, stroke=best[1], blend=best[2])
    model = final.fit(full, record_weights=full_weights)
    prov = {**model.provenance, "hysteretic_choice": rows}
    prov["settings"] = {**prov.get("settings", {}), "stroke": est.stroke, "blend": est.blend}
    if plan is not None:
        prov["hysteretic_windows"] = {
            "windows": len(plan),
            "samples_used": int(sum(b - a for _, a, b in plan)),
            "note": "stroke and blend chosen on evenly spread windows; the model fitted on all",
        }
    prov["hysteretic_note"] = (
        f"stroke = {model.stroke:g} m and blend = {model.blend:g} chosen on the training records "
        f"(lowest mean free-run ESR of {len(rows)} candidates, each refined with at most "
        f"{min(est.max_nfev, CHOICE_NFEV)} iterations)"
        if np.isfinite(best[0])
        else f"every candidate diverged in free run on the training records; the first "
        f"(stroke = {model.stroke:g} m, blend = {model.blend:g}) is returned"
    )
    return dataclasses.replace(model, provenance=prov)
