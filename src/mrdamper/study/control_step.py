"""The study's control-relevance step: every fitted model in the quarter-car loop.

After the fits, :func:`control_relevance` drives the quarter car (:mod:`mrdamper.control`) with
each model of the first fold as the controller's model:

* **truth known** (every record from the virtual rig, one named reference damper): each
  controller runs with the model as the damper (*predicted*) and with the rig's reference damper
  (*achieved*), :func:`~mrdamper.control.loop.fidelity.closed_loop_fidelity`; with ``fronts`` the
  gain fronts of each invertible model are also swept on a coarse grid
  (:func:`~mrdamper.control.loop.fronts.gain_fronts`; single runs at the road's step, not checked by
  halving, and only for the models with a closed-form inverse, static maps and LPV, to keep the
  step short);
* **measured data** (no truth in the loop): each model runs predicted only, every run checked by
  halving the plant step, and each metric is compared with the median of the models on the same
  controller and road (``vs_median_pct = 100 (metric - median) / median``).

A controller a model cannot run (no inverse, a refused or diverged run) keeps its row with the
one-line reason. The roads are short by default (3 s of ISO 8608 class C at 20 m/s) so that a
quick study stays quick; :class:`ControlSettings` changes them and ``control=None`` in
:func:`~mrdamper.study.run_study` switches the step off.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.loop.car import CONTROLLERS, Controller, QuarterCar
from mrdamper.control.loop.fidelity import (
    METRICS,
    checked_run,
    closed_loop_fidelity,
    discrete_rate,
    grouped_notes,
    input_unit,
    loop_metrics,
)
from mrdamper.control.loop.fronts import FrontsResult, gain_fronts
from mrdamper.control.loop.stroke_cells import envelope_left
from mrdamper.errors import DataValidationError, interrupt_in_chain
from mrdamper.models.protocols import InvertibleModel

__all__ = [
    "CONTROL_COLUMNS",
    "STUDY_LEVELS",
    "ControlRelevance",
    "ControlSettings",
    "control_relevance",
    "model_in_loop",
    "plot_fronts",
    "truth_damper",
]

#: Columns of :attr:`ControlRelevance.table`.
CONTROL_COLUMNS: tuple[str, ...] = (
    "model",
    "kind",
    "controller",
    "road",
    "speed_m_s",
    "metric",
    "unit",
    "predicted",
    "achieved",
    "error_pct",
    "vs_median_pct",
    "envelope_left",
    "reason",
)
#: The study's coarse gain grid (a few points per controller; the CLI's ``--tune`` is finer).
STUDY_GRIDS: dict[str, tuple[float, ...]] = {
    "skyhook": (1000.0, 3000.0, 8000.0),
    "groundhook": (1000.0, 3000.0, 8000.0),
    "hybrid": (3000.0,),
}
#: Passive inputs of the study's fronts, as fractions of the input range [-].
STUDY_LEVELS: tuple[float, ...] = (0.0, 0.05, 0.2, 0.5, 1.0)


#: Controllers of the control step of ``mrdamper demo --quick`` (no gain fronts either).
QUICK_CONTROLLERS = ("soft", "skyhook")


@dataclass(frozen=True)
class ControlSettings:
    """What the control-relevance step runs.

    Attributes
    ----------
    road_classes : tuple of str
        ISO 8608 classes (default ``("C",)``).
    speeds : tuple of float
        Vehicle speeds [m/s] (default ``(20.0,)``).
    duration : float
        Road length [s] (default 3; the road fades in and out over 0.5 s).
    controllers : tuple of str
        Controllers (default all five).
    fronts : bool
        With a known truth, also sweep the gain fronts (coarse grid) of each model with a
        closed-form inverse (static maps, LPV).
    plant : str, optional
        The damper of the virtual-rig records, when it is not the rig's default reference
        (``"rig:spencer1997"`` or a model file); ignored on measured data.
    """

    road_classes: tuple[str, ...] = ("C",)
    speeds: tuple[float, ...] = (20.0,)
    duration: float = 3.0
    controllers: tuple[str, ...] = CONTROLLERS
    fronts: bool = True
    plant: str | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.duration) and self.duration >= 2.0):
            raise DataValidationError(
                "duration", f"expected a road length >= 2 s, got {self.duration!r}"
            )
        for c in self.controllers:
            Controller(c)  # one-line error naming the controller

    def describe(self) -> str:
        """One line for the report."""
        speeds = ", ".join(f"{s:g}" for s in self.speeds)
        return (
            f"ISO 8608 class {', '.join(self.road_classes)} at {speeds} m/s, {self.duration:g} s "
            f"roads, controllers {', '.join(self.controllers)}"
        )


@dataclass(frozen=True, eq=False)
class ControlRelevance:
    """The loop metrics of every model.

    Attributes
    ----------
    truth : str or None
        The damper in the loop (``"rig"``, ``"rig:NAME"`` or a model file,
        :func:`truth_damper`), None when no truth is known.
    fold : str
        The fold whose models ran.
    settings : ControlSettings
    table : DataFrame
        :data:`CONTROL_COLUMNS`, one row per model x controller x road x speed x metric, or one
        row per model x controller with the reason when it could not run.
    fronts : dict
        Model label -> :class:`~mrdamper.control.loop.fronts.FrontsResult` or the reason (str).
    notes : list of str
        One-line warnings of the runs (envelope left, oscillation).
    """

    truth: str | None
    fold: str
    settings: ControlSettings
    table: pd.DataFrame
    fronts: Mapping[str, FrontsResult | str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def truth_damper(records: Iterable[Any], plant: str | None = None) -> str | None:
    """The damper behind every record when it is known, else None.

    Every record must come from the virtual rig (metadata ``source``) with one damper kind
    (metadata ``damper``). The truth is then ``plant`` when given (``"rig:NAME"`` or a model
    file, :func:`~mrdamper.control.loop.closed_loop.resolve_plant`); else the shipped reference
    damper
    the records name (metadata ``reference_damper``, written by the rig and kept in the manifest
    of ``mrdamper rig doe``): ``"rig"`` for the default one, ``"rig:NAME"`` for another; None when
    they name another damper (``"custom"``) or disagree. Records that name none (written before
    the rig named its damper) are taken to be the default reference damper's when their damper is
    a Spencer model.
    """
    from mrdamper.rig.reference import DEFAULT_REFERENCE, REFERENCE_DAMPERS, REFERENCE_KEY

    recs = list(records)
    if not recs or any(e.metadata.get("source") != "virtual rig" for e in recs):
        return None
    kinds = {str(e.metadata.get("damper", "")) for e in recs}
    if len(kinds) != 1:
        return None
    if plant is not None:
        return plant
    names = {str(e.metadata.get(REFERENCE_KEY, "")) for e in recs}
    if names == {""}:
        return "rig" if kinds == {"spencer"} else None
    if len(names) != 1 or not names <= set(REFERENCE_DAMPERS):
        return None
    (name,) = names
    return "rig" if name == DEFAULT_REFERENCE else f"rig:{name}"


def _reason(exc: BaseException) -> str:
    if interrupt_in_chain(exc):
        raise KeyboardInterrupt from exc
    text = str(exc).strip().splitlines()  # the message only: no class name in the report
    return text[0] if text else f"failed without a message ({type(exc).__name__})"


def _failed_row(label: str, kind: str, ctrl: str, reason: str) -> dict[str, Any]:
    return {"model": label, "kind": kind, "controller": ctrl, "reason": reason}


def _predicted_rows(
    label: str, model: Any, ctrl: str, s: ControlSettings, car: QuarterCar
) -> list[dict[str, Any]]:
    from mrdamper.control.loop.closed_loop import simulate_closed_loop
    from mrdamper.control.loop.quarter_car import iso_road
    from mrdamper.control.loop.quarter_car_study import default_rate

    unit = input_unit(model)
    rows = []
    for cls in s.road_classes:
        for sp in s.speeds:
            road = iso_road(cls, speed=sp, duration=s.duration, fs=default_rate(model), seed=0)

            def run(n: int, road: Any = road) -> Any:
                return simulate_closed_loop(model, road, ctrl, car, substeps=n)

            m = loop_metrics(checked_run(run)[0])
            for metric, value in m.items():
                rows.append(
                    {
                        "model": label,
                        "kind": model.kind,
                        "controller": ctrl,
                        "road": cls,
                        "speed_m_s": float(sp),
                        "metric": metric,
                        "unit": unit if metric == "mean_current" else METRICS[metric],
                        "predicted": value,
                    }
                )
    return rows


def _spread(df: pd.DataFrame) -> pd.DataFrame:
    """``vs_median_pct``: each model's predicted metric against the median of the models."""
    ok = df["metric"].notna()
    med = (
        df[ok]
        .groupby(["controller", "road", "speed_m_s", "metric"])["predicted"]
        .transform("median")
    )
    out = np.full(len(df), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        out[ok.to_numpy()] = (100.0 * (df.loc[ok, "predicted"] - med) / med).to_numpy()
    df["vs_median_pct"] = np.where(np.isfinite(out), out, np.nan)
    return df


def model_in_loop(
    label: str,
    kind: str,
    model: Any,
    truth: str | None,
    settings: ControlSettings,
    car: QuarterCar | None = None,
) -> tuple[list[dict[str, Any]], FrontsResult | str | None, list[str]]:
    """One model in the loop: its rows, its gain fronts (or why not; None when not asked) and
    its warnings. A task of the study's executor (``model`` may be a saved model's dict)."""
    from mrdamper.control.loop.closed_loop import resolve_plant
    from mrdamper.models import model_from_dict

    s = settings
    car = QuarterCar() if car is None else car
    if isinstance(model, Mapping):
        model = model_from_dict(dict(model))
    plant = None if truth is None else resolve_plant(truth)
    rows: list[dict[str, Any]] = []
    runs: list[dict[str, Any]] = []  # of every controller: their notes are grouped once
    n_loops = 0
    for ctrl in s.controllers:
        try:
            if plant is None:
                rows += _predicted_rows(label, model, ctrl, s, car)
                continue
            res = closed_loop_fidelity(
                model,
                plant,
                road_classes=s.road_classes,
                speeds=s.speeds,
                controllers=[ctrl],
                duration=s.duration,
                car=car,
            )
        except Exception as exc:  # noqa: BLE001 - the row keeps the one-line reason
            rows.append(_failed_row(label, kind, ctrl, _reason(exc)))
            continue
        refused: dict[tuple[str, float], str] = {}
        for run in res.runs:  # one controller: a road and speed name the run
            if "refused" in run:
                key = (run["road"], run["speed_m_s"])
                why = f"{run['side']} run {run['refused']}"  # "refused: ..." or "diverged: ..."
                refused[key] = f"{refused[key]}; {why}" if key in refused else why
        left = {  # the cell's loop (achieved side) beyond the model's training envelope
            (run["road"], run["speed_m_s"]): envelope_left(run)
            for run in res.runs
            if run.get("side") == "achieved"
        }
        for r in res.table().to_dict("records"):
            row = {"model": label, "kind": kind, "unit": res.unit(r["metric"]), **r}
            row["envelope_left"] = left.get((r["road"], r["speed_m_s"]), "")
            said = refused.get((r["road"], r["speed_m_s"]))
            if said is not None:  # its NaN cells say why
                row["reason"] = said
            rows.append(row)
        runs += res.runs
        n_loops += len(s.road_classes) * len(s.speeds)
    notes = [
        f"{label}: {n}"
        for n in (grouped_notes(model, runs, n_loops, car, discrete_rate(model)) if runs else [])
        if "carries no training envelope" not in n
    ]
    fronts: FrontsResult | str | None = None
    if plant is not None and s.fronts and not isinstance(model, InvertibleModel):
        fronts = (
            f"not swept in the study: the {model.kind} model has no closed-form inverse (its "
            "controllers, if any, solve through its step, several times slower); `mrdamper "
            "quartercar MODEL --plant rig --tune` sweeps it"
        )
    elif plant is not None and s.fronts:
        try:
            fronts = gain_fronts(
                model,
                plant,
                road_classes=s.road_classes[:1],
                speeds=s.speeds[:1],
                duration=s.duration,
                car=car,
                grids=STUDY_GRIDS,
                alphas=(0.5,),
                levels=STUDY_LEVELS,
                check=False,
            )
        except Exception as exc:  # noqa: BLE001 - the figure says why
            fronts = _reason(exc)
    return rows, fronts, notes


def control_relevance(
    models: Mapping[str, Any],
    labels: Sequence[str],
    kinds: Mapping[str, str],
    truth: str | None,
    fold: str,
    settings: ControlSettings | None = None,
    *,
    fit_errors: Mapping[str, str] | None = None,
    car: QuarterCar | None = None,
    submit: Callable[..., Any] | None = None,
    advance: Callable[[], None] | None = None,
) -> ControlRelevance:
    """Every model in the loop (module docstring).

    Parameters
    ----------
    models : mapping
        Label -> fitted model, or its dict (the fold's successful fits).
    labels : sequence of str
        Every model of the study, in display order (a label without a model gets a row with
        its fit error).
    kinds : mapping
        Label -> registry kind.
    truth : str or None
        The true damper (:func:`truth_damper`); None: no truth is known (measured data).
    fold : str
        The fold the models come from.
    settings : ControlSettings, optional
    fit_errors : mapping, optional
        Label -> why its fit failed.
    car : QuarterCar, optional
    submit : callable, optional
        ``submit(fn, *args)`` returning a future (a study executor's): each model runs as a task
        there; default: one after the other here.
    advance : callable, optional
        Called once per model that ran in the loop, when its result is in (a progress bar).
    """
    s = ControlSettings() if settings is None else settings
    pending: dict[str, Any] = {}
    for label, model in models.items():  # in the mapping's order (the costliest first)
        args = (label, kinds.get(label, "?"), model, truth, s, car)
        pending[label] = submit(model_in_loop, *args) if submit else model_in_loop(*args)
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    fronts: dict[str, FrontsResult | str] = {}
    for label in labels:
        if label not in pending:
            why = f"fit failed: {(fit_errors or {}).get(label) or 'no fitted model'}"
            rows += [_failed_row(label, kinds.get(label, "?"), c, why) for c in s.controllers]
            if truth is not None and s.fronts:
                fronts[label] = why
            continue
        out = pending[label]
        try:
            got, fr, n = out.result() if submit else out
        except Exception as exc:  # noqa: BLE001 - a worker's failure keeps the model's rows
            why = f"worker error: {_reason(exc)}"
            got, fr, n = (
                [_failed_row(label, kinds.get(label, "?"), c, why) for c in s.controllers],
                why,
                [],
            )
        rows += got
        notes += n
        if advance is not None:
            advance()
        if fr is not None:
            fronts[label] = fr
    table = pd.DataFrame(rows, columns=list(CONTROL_COLUMNS))
    if truth is None:
        table = _spread(table)
    return ControlRelevance(truth, fold, s, table, fronts, notes)


def plot_fronts(cr: ControlRelevance) -> Any:
    """Comfort (``a_w``) against road holding (RMS tyre load) per model: the passive front
    (line) and the semi-active points, predicted (open, dashed) and achieved (filled, solid).

    Returns
    -------
    Figure or str
        The reason when there is nothing to draw.
    """
    import matplotlib.pyplot as plt

    ok = {k: v for k, v in cr.fronts.items() if isinstance(v, FrontsResult)}
    if not ok:
        return "no gain fronts: " + (
            "no truth in the loop (measured data)" if cr.truth is None else "no model ran"
        )
    n = len(ok)
    cols = min(3, n)
    nrow = -(-n // cols)
    fig, axes = plt.subplots(nrow, cols, figsize=(7.0, 2.4 * nrow + 0.5), squeeze=False)
    colours = {"passive": "0.3", "skyhook": "C0", "groundhook": "C2", "hybrid": "C3"}
    for ax, (label, fr) in zip(axes.flat, ok.items()):
        df = fr.table()
        for side, ls, filled in (("predicted", "--", False), ("achieved", "-", True)):
            part = df[(df["side"] == side) & (df["status"] == "ok")]
            for ctrl, c in colours.items():
                pts = part[part["controller"] == ctrl].sort_values("rms_travel")
                if pts.empty:
                    continue
                ax.plot(
                    pts["rms_tyre_load"], pts["a_w"], ls=ls if ctrl == "passive" else "none",
                    marker="o", ms=3, lw=0.8, color=c, mfc=c if filled else "none",
                    label=f"{ctrl} ({side})",
                )  # fmt: skip
        ax.set_title(label, fontsize=8)
        ax.set_xlabel("RMS tyre load [N]")
        ax.set_ylabel("a_w [m/s²]")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=4, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.12 if nrow == 1 else 0.06, 1, 1))
    return fig
