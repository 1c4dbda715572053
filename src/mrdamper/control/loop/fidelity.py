"""Closed-loop fidelity: what a model predicts in the loop against what the damper achieves.

:func:`closed_loop_fidelity` runs every controller on every ISO 8608 road and speed twice with the
controller and inverse of ``model``: *predicted*, with the model itself as the damper, and
*achieved*, with ``plant`` as the damper (:func:`~mrdamper.control.loop.closed_loop.
simulate_closed_loop`), and tabulates :data:`METRICS` for both with
``error_pct = 100 (predicted - achieved) / achieved``.

Every run is checked (:func:`checked_run`): the plant step is halved and the run repeated; when a
metric moves by more than ``tol`` (0.5 %) the step is halved again, up to ``max_substeps`` plant
steps per road sample, beyond which the run is refused with the figure. A run whose loop diverges
keeps NaN rows and a note too (``diverged: ...``); the other runs go on. Each run also reports
the share of its body-acceleration power above the wheel-hop band (:func:`oscillation`; a
sampled-loop oscillation concentrates it there) and, from the envelope the model carries
(:mod:`mrdamper.models.envelope`), how far the loop's motion leaves the model's training data.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import pandas as pd

from mrdamper.control.damper import DamperModel, SampledModel
from mrdamper.control.loop._loop import default_rate, input_unit
from mrdamper.control.loop.closed_loop import check_pair, resolve_plant, simulate_closed_loop
from mrdamper.control.loop.quarter_car import (
    CONTROLLERS,
    Controller,
    QuarterCar,
    QuarterCarResult,
    iso_road,
)
from mrdamper.errors import DataValidationError, MrDamperError, SimulationDivergedError
from mrdamper.models.base import FittedModel
from mrdamper.models.envelope import ENVELOPE_TOLERANCE, envelope_of, excursions
from mrdamper.models.levels import check_levels

__all__ = [
    "MAX_SUBSTEPS",
    "METRICS",
    "FidelityResult",
    "NotConvergedError",
    "check_sides",
    "checked_run",
    "closed_loop_fidelity",
    "discrete_rate",
    "failed_runs",
    "grouped_notes",
    "input_unit",
    "loop_metrics",
    "oscillation",
    "oscillation_note",
]

#: Metric name -> unit (``mean_current`` is in the model's input unit: [A], or [V]).
METRICS: dict[str, str] = {
    "rms_acc": "m/s²",
    "a_w": "m/s²",
    "rms_tyre_load": "N",
    "rms_travel": "m",
    "rms_tracking": "N",
    "mean_current": "A",
}


#: Finest plant step of the halving check [plant steps per road sample]. On the default car 16
#: refused 5 of the 37 points of P-15's gain sweep (``docs/results.md``, "Every gain of the
#: sweep"); the check stops at the first step that converges, so converged runs cost no more.
MAX_SUBSTEPS = 64


#: Smallest magnitude a metric is compared against in the halving check (below it, absolute).
_FLOOR = {
    "rms_acc": 1e-3,
    "a_w": 1e-3,
    "rms_tyre_load": 1.0,
    "rms_travel": 1e-5,
    "rms_tracking": 1.0,
    "mean_current": 1e-2,
}

#: Acceleration power above this multiple of the wheel-hop frequency counts as high-frequency
#: (about 35 Hz on the default car).
HF_FACTOR = 3.0
#: A run whose high-frequency share exceeds this is reported as a sampled-loop oscillation. On
#: ISO 8608 roads A-D the true damper's loops put at most 2.2 % of the body-acceleration power
#: there (every controller); the default LPV model fitted on Table II at 1 kHz in passive hard up
#: to 8 % (8-81 % while the loop held its force over each sample).
HF_SHARE = 0.05
#: A discrete-time model's oscillation peaked above this share of its rate is a sampled-loop one.
NYQUIST_SHARE = 0.25
#: Below that, a one-sample delay lagging by at least this much [deg] at the peak counts as a cause.
DELAY_LAG_DEG = 30.0


def loop_metrics(r: QuarterCarResult) -> dict[str, float]:
    """:data:`METRICS` of one run (``rms_tracking`` NaN for a passive controller)."""
    m = r.metrics()
    track = r.F - r.F_desired
    ok = np.isfinite(track)
    return {
        "rms_acc": m["rms_acc"],
        "a_w": m["rms_acc_wk"],
        "rms_tyre_load": m["rms_tyre_load"],
        "rms_travel": m["rms_travel"],
        "rms_tracking": float(np.sqrt(np.mean(track[ok] ** 2))) if ok.any() else float("nan"),
        "mean_current": float(np.mean(r.i)),
    }


def oscillation(r: QuarterCarResult) -> tuple[float, float]:
    """Share of the body-acceleration power above ``HF_FACTOR`` times the wheel-hop frequency
    [-] and the frequency of the largest peak there [Hz] (Welch PSD, 1 s segments)."""
    from scipy.signal import welch

    f, p = welch(r.a_s, fs=r.fs, nperseg=min(r.a_s.size, int(r.fs)))
    total = float(np.sum(p))
    hf = f > HF_FACTOR * r.car.wheel_hop_frequency()
    if total <= 0 or not hf.any():
        return 0.0, float("nan")
    return float(np.sum(p[hf]) / total), float(f[hf][np.argmax(p[hf])])


#: Where the remedy for a loop beyond the training envelope is described.
REMEDY = (
    "on the virtual rig `mrdamper rig doe --extension control`; docs/control.md, "
    "'A model meant for a loop'"
)

#: How :func:`_envelope_note`'s dimensions read in a note.
_EXCURSION_NAMES = {
    "velocity": "velocity",
    "stroke": "stroke",
    "switching": "switching-while-moving velocity",
    "frequency": "frequency content",
}


#: The switching dimension when the training records never switch the input while moving.
_NEW_SWITCHING = "the input switches while the damper moves, which no training record does"


def _excursion_text(exc: dict[str, float]) -> str:
    """The dimensions the loop leaves (ratio to the training envelope above 1 +
    :data:`~mrdamper.models.envelope.ENVELOPE_TOLERANCE`, as for a record), largest first, e.g.
    ``"stroke x1.3, velocity x1.1"``; switching while moving, when the training records never
    do, in words, last."""
    out = sorted(
        ((v, k) for k, v in exc.items() if v > 1.0 + ENVELOPE_TOLERANCE and np.isfinite(v)),
        reverse=True,
    )
    text = [f"{_EXCURSION_NAMES.get(k, k)} x{v:.2g}" for v, k in out]
    if exc.get("switching") == np.inf:
        text.append(_NEW_SWITCHING)
    return ", ".join(text)


def discrete_rate(model: DamperModel) -> float | None:
    """The rate [Hz] of a discrete-time model (an LPV, LTI or NARX step, whose ``dt`` is set), None
    for a continuous-time one: the ``model_fs`` of :func:`oscillation_note`."""
    dt = getattr(cast(FittedModel, model).step(), "dt", None)
    return None if dt is None else float(cast(SampledModel, model).fs)


class NotConvergedError(MrDamperError):
    """The halving check refused a run: the plant step is not converged (the message gives the
    figure and the metric)."""


def oscillation_note(
    share: float, peak: float, car: QuarterCar, model_fs: float | None = None
) -> str:
    """The one-line description of a high-frequency loop oscillation (:func:`oscillation`'s
    ``share`` [-] and ``peak`` [Hz] on ``car``).

    For a discrete-time damper of rate ``model_fs`` [Hz] the note says what the model's rate has
    to do with it: a peak above :data:`NYQUIST_SHARE` of the rate is the sampled loop's (a higher
    rate is the remedy); below it the note gives the phase lag of the model's one-sample delay at
    the peak (``360 peak / model_fs`` degrees): from :data:`DELAY_LAG_DEG` on, a higher rate
    shortens a delay that matters there, below it the oscillation is the model's own dynamics in
    the loop, and records of the loop's motions (:mod:`mrdamper.control.loop.doe_extension`) are
    what
    can change it.
    """
    what = (
        f"{100 * share:.0f} % of the body acceleration power above "
        f"{HF_FACTOR * car.wheel_hop_frequency():.0f} Hz, peak at {peak:.1f} Hz"
    )
    if model_fs is None:
        return f"high-frequency loop oscillation: {what}"
    if peak > NYQUIST_SHARE * model_fs:
        return (
            f"sampled-loop oscillation: {what}, near the model's Nyquist frequency "
            f"({model_fs / 2:g} Hz): identify the model at a higher rate (LPV setting model_fs)"
        )
    lag = 360.0 * peak / model_fs
    remedy = (
        "a higher model rate (LPV setting model_fs) shortens that delay"
        if lag >= DELAY_LAG_DEG
        else "a higher rate barely changes it"
    )
    return (
        f"loop oscillation: {what}, where the model's one-sample delay lags by {lag:.0f} deg: "
        f"{remedy}; training records of the loop's motions ({REMEDY}) give the model the "
        "motions it meets here"
    )


def checked_run(
    run: Callable[[int], QuarterCarResult],
    *,
    tol: float = 0.005,
    max_substeps: int = MAX_SUBSTEPS,
) -> tuple[QuarterCarResult, int, float]:
    """Run with 1, 2, 4, ... plant steps per road sample until halving the step moves no metric
    by more than ``tol`` (relative).

    A run that diverges at a step is repeated at half that step (a stiff damper coupled to the car
    over too long a step is how a loop that is stable diverges); the check then starts from the
    first step that ran.

    Returns
    -------
    result : QuarterCarResult
        The run at the accepted step.
    substeps : int
        Plant steps per road sample of that run.
    change : float
        Largest relative change of a metric when its step is halved [-].

    Raises
    ------
    NotConvergedError
        Not converged at ``max_substeps`` (the message gives the figure and the metric).
    SimulationDivergedError
        Diverged at every step down to ``max_substeps / 2`` plant steps per road sample.
    """
    s = 1
    while True:
        try:
            a = run(s)
            break
        except SimulationDivergedError as exc:
            if 2 * s >= max_substeps:
                what = str(exc).split(": ", 2)[-1]
                raise SimulationDivergedError(
                    exc.model,
                    exc.sample,
                    f"{what}, at every plant step down to 1/{s} of the road's: the loop itself "
                    "diverges, not its integration",
                ) from exc
            s *= 2
    ma = loop_metrics(a)
    while True:
        b = run(2 * s)
        mb = loop_metrics(b)
        changes = {
            k: abs(ma[k] - mb[k]) / max(abs(mb[k]), _FLOOR[k]) for k in ma if np.isfinite(mb[k])
        }
        worst = max(changes, key=changes.__getitem__)
        change = changes[worst]
        if change <= tol:
            return a, s, change
        if 2 * s >= max_substeps:
            raise NotConvergedError(
                f"substeps: the plant step is not converged: halving it at {2 * s} steps per "
                f"road sample still moves {worst} by {100 * change:.2g} % (> {100 * tol:g} %)"
            )
        s, a, ma = 2 * s, b, mb


@dataclass(frozen=True, eq=False)
class FidelityResult:
    """Predicted against achieved metrics.

    Attributes
    ----------
    model_kind, plant_kind : str
    rows : list of dict
        One per controller x road x speed x metric (:meth:`table`).
    runs : list of dict
        One per controller x road x speed x side: substeps, halving change, high-frequency share
        and peak, envelope excursions.
    notes : list of str
        One-line warnings (sampled-loop oscillation, envelope left).
    """

    model_kind: str
    plant_kind: str
    input_unit: str
    rows: list[dict[str, Any]]
    runs: list[dict[str, Any]]
    notes: list[str] = field(default_factory=list)

    def table(self) -> pd.DataFrame:
        """Columns ``controller, road, speed_m_s, metric, predicted, achieved, error_pct``."""
        return pd.DataFrame(
            self.rows,
            columns=[
                "controller",
                "road",
                "speed_m_s",
                "metric",
                "predicted",
                "achieved",
                "error_pct",
            ],
        )

    def runs_frame(self) -> pd.DataFrame:
        """The per-run diagnostics."""
        return pd.DataFrame(self.runs)

    def unit(self, metric: str) -> str:
        """Unit of ``metric``."""
        return self.input_unit if metric == "mean_current" else METRICS[metric]


def _envelope_note(model: DamperModel, r: QuarterCarResult) -> dict[str, float] | None:
    trained = dict(getattr(model, "provenance", {}) or {}).get("envelope")
    if not trained:
        return None
    x = r.travel * r.car.motion_ratio
    v = (r.v_s - r.v_u) * r.car.motion_ratio
    return excursions(trained, envelope_of([x], [v], [r.i], dt=[1.0 / r.fs]))


def failed_runs(res: FidelityResult) -> int:
    """Number of runs of ``res`` that diverged or were refused (:func:`check_sides`)."""
    return check_sides(res.runs, lambda r: r.get("refused"), res.model_kind, res.plant_kind)


def check_sides(
    rows: Sequence[Mapping[str, Any]],
    reason: Callable[[Mapping[str, Any]], str | None],
    model_kind: str,
    plant_kind: str | None,
) -> int:
    """Number of ``rows`` (runs with a ``side``) that failed, by ``reason(row)`` (None: ran).

    Raises
    ------
    DataValidationError
        Every run of one side failed: the model (``"model"``, predicted side) or the plant
        (``"plant"``, achieved side) cannot drive the quarter car at all (unstable, or its step
        fails); one line with the first run's reason.
    """
    failed = 0
    for side, who, kind in (("predicted", "model", model_kind), ("achieved", "plant", plant_kind)):
        why = [reason(r) for r in rows if r.get("side") == side]
        bad = [w for w in why if w]
        failed += len(bad)
        if why and len(bad) == len(why):
            raise DataValidationError(
                who,
                f"every loop with the {kind} {who} as damper failed ({len(bad)} runs; first: "
                f"{bad[0]}); it cannot drive the quarter car (is it stable over its input range?)",
            )
    return failed


def closed_loop_fidelity(
    model: DamperModel,
    plant: Any,
    *,
    road_classes: Sequence[str] = ("C",),
    speeds: Sequence[float] = (20.0,),
    controllers: Sequence[Controller | str] = CONTROLLERS,
    duration: float = 20.0,
    seed: int = 0,
    car: QuarterCar | None = None,
    reg: float | None = None,
    rate: float | None = None,
    tol: float = 0.005,
    max_substeps: int = MAX_SUBSTEPS,
) -> FidelityResult:
    """Predicted (``model`` as damper) against achieved (``plant`` as damper) loop metrics.

    Parameters
    ----------
    model : FittedModel
        Controller model.
    plant : FittedModel or str
        The damper (:func:`~mrdamper.control.loop.closed_loop.resolve_plant`).
    road_classes : sequence of str
        ISO 8608 classes.
    speeds : sequence of float
        Vehicle speeds [m/s] (>= 0).
    controllers : sequence
        Controllers (names or :class:`Controller`).
    duration : float
        Road length [s].
    seed : int
        Road phases.
    car : QuarterCar, optional
        Car.
    reg, rate : float, optional
        Inverse regularisation [N per input unit] and input rate bound [input unit/s].
    tol : float
        Halving tolerance [-] of :func:`checked_run`.
    max_substeps : int
        Finest plant step [steps per road sample].
    """
    plant_m = resolve_plant(plant)
    check_pair(model, plant_m)
    same = "every controller gives the same numbers"  # one level trained: no authority
    check_levels(model, same)
    check_levels(plant_m, same, field="plant")
    car = QuarterCar() if car is None else car
    for sp in speeds:
        if not (np.isfinite(sp) and sp > 0):
            raise DataValidationError("speed", f"expected a vehicle speed > 0 [m/s], got {sp!r}")
    ctrls = [Controller(c) if isinstance(c, str) else c for c in controllers]
    unit = input_unit(model)
    rows: list[dict[str, Any]] = []
    runs: list[dict[str, Any]] = []
    fs = default_rate(model)
    model_fs = discrete_rate(model)
    for cls in road_classes:
        for sp in speeds:
            road = iso_road(cls, speed=float(sp), duration=duration, fs=fs, seed=seed)
            for c in ctrls:
                out = {}
                for side, p in (("predicted", None), ("achieved", plant_m)):

                    def run(
                        s: int, p: Any = p, c: Controller = c, road: Any = road
                    ) -> QuarterCarResult:
                        return simulate_closed_loop(
                            model, road, c, car, plant=p, substeps=s, reg=reg, rate=rate
                        )

                    info: dict[str, Any] = {
                        "controller": c.kind,
                        "road": cls,
                        "speed_m_s": float(sp),
                        "side": side,
                    }
                    try:
                        r, s, change = checked_run(run, tol=tol, max_substeps=max_substeps)
                    except (NotConvergedError, SimulationDivergedError) as exc_refused:
                        # this run only: the others go on (a loop that diverges is a finding)
                        what = (
                            "refused" if isinstance(exc_refused, NotConvergedError) else "diverged"
                        )
                        runs.append({**info, "refused": f"{what}: {exc_refused}"})
                        out[side] = dict.fromkeys(METRICS, float("nan"))
                        continue
                    share, f_hf = oscillation(r)
                    exc = _envelope_note(model, r)
                    info.update(
                        {
                            "substeps": s,
                            "halving_change_pct": 100 * change,
                            "hf_share": share,
                            "hf_peak_hz": f_hf,
                        }
                    )
                    if exc is not None:
                        info.update({f"excursion_{k}": v for k, v in exc.items()})
                    runs.append(info)
                    out[side] = loop_metrics(r)
                for metric in METRICS:
                    pr, ac = out["predicted"][metric], out["achieved"][metric]
                    err = 100.0 * (pr - ac) / ac if ac != 0 else float("nan")  # NaN if refused
                    rows.append(
                        {
                            "controller": c.kind,
                            "road": cls,
                            "speed_m_s": float(sp),
                            "metric": metric,
                            "predicted": pr,
                            "achieved": ac,
                            "error_pct": err,
                        }
                    )
    n_loops = len(ctrls) * len(road_classes) * len(speeds)
    notes = grouped_notes(model, runs, n_loops, car, model_fs)
    return FidelityResult(model.kind, plant_m.kind, unit, rows, runs, notes)


#: Runs named in full in a grouped note; the others are counted (all are in ``runs_frame``).
_NAMED_RUNS = 4


def _where(run: dict[str, Any]) -> str:
    return f"{run['controller']} ISO {run['road']} @ {run['speed_m_s']:g} m/s {run['side']}"


def _named(runs: list[dict[str, Any]]) -> str:
    """``"hard ISO A @ 20 m/s predicted, ... and 3 more"``."""
    shown = ", ".join(_where(r) for r in runs[:_NAMED_RUNS])
    more = len(runs) - _NAMED_RUNS
    return shown + (f" and {more} more" if more > 0 else "")


def grouped_notes(
    model: DamperModel,
    runs: list[dict[str, Any]],
    n_loops: int,
    car: QuarterCar,
    model_fs: float | None,
) -> list[str]:
    """One line per finding over every run (refused, diverged, oscillating, beyond the training
    envelope), naming the runs; each run's figures stay in :meth:`FidelityResult.runs_frame`.

    Parameters
    ----------
    model : FittedModel
        The controller's model.
    runs : list of dict
        :attr:`FidelityResult.runs` (of one or several calls, e.g. one per controller).
    n_loops : int
        Controller x road x speed loops the runs cover.
    car : QuarterCar
        The car (the oscillation's band).
    model_fs : float or None
        :func:`discrete_rate` of ``model``.

    Returns
    -------
    list of str
    """
    notes: list[str] = []
    for what in ("refused", "diverged"):
        hit = [r for r in runs if str(r.get("refused", "")).startswith(what)]
        if hit:
            why = str(hit[0]["refused"]).removeprefix(f"{what}: ").removeprefix("substeps: ")
            notes.append(
                f"{len(hit)} run(s) {what}, their metrics left empty ({_named(hit)}); the "
                f"first: {why}"
            )
    osc = [r for r in runs if r.get("hf_share", 0.0) > HF_SHARE]
    if osc:
        worst = max(osc, key=lambda r: float(r["hf_share"]))
        fs_m = model_fs if worst["side"] == "predicted" else None
        what = oscillation_note(worst["hf_share"], worst["hf_peak_hz"], car, fs_m)
        notes.append(
            f"{len(osc)} run(s) oscillate ({_named(osc)}); the strongest, {_where(worst)}: {what}"
        )
    if not dict(getattr(model, "provenance", {}) or {}).get("envelope"):
        notes.append(
            f"the {model.kind} model carries no training envelope (saved before it was recorded):"
            " refit it to see how far the loop leaves its training data"
        )
    largest: dict[str, float] = {}
    n_left = 0  # loops (achieved side) that leave the model's training envelope
    for r in runs:
        exc = {
            k.removeprefix("excursion_"): float(v)
            for k, v in r.items()
            if k.startswith("excursion_")
        }
        if r["side"] == "achieved" and _excursion_text(exc):
            n_left += 1
            for k, v in exc.items():
                largest[k] = max(largest.get(k, 0.0), v)
    if n_left:
        notes.append(
            f"{n_left} of {n_loops} loops leave the {model.kind} model's training envelope (at "
            f"most: {_excursion_text(largest)}), where its predictions extrapolate: add records "
            f"of the loop's own motions to its training set ({REMEDY})"
        )
    return notes
