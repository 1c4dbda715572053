"""Gain fronts: comfort against road holding for every controller gain, tuned on the model.

:func:`gain_fronts` drives the quarter car over one ISO 8608 road with

* the **passive front**: the damper held at constant inputs across its range (``soft`` is the
  lowest, ``hard`` the highest), :data:`PASSIVE_LEVELS`;
* each semi-active controller at every gain of its grid (:data:`GAIN_GRIDS`: skyhook ``c_sky``,
  groundhook ``c_ground``, hybrid ``alpha`` x a common gain ``c_sky = c_ground``),

each run with the model as the damper (*predicted*) and, when a plant is given, with the plant
(*achieved*), every run checked by halving the plant step
(:func:`~mrdamper.control.loop.fidelity.checked_run`). Metrics: ISO 2631 weighted RMS body
acceleration ``a_w`` [m/s²] (comfort), RMS dynamic tyre load [N] (road holding), RMS suspension
travel [m] and mean input [A or V].

**Gain over passive at equal travel.** A semi-active point is compared with the passive front at
the same RMS travel: the passive metric is interpolated linearly in travel between the two
passive levels that bracket it (NaN when its travel is outside the passive front's range: more
travel than the soft damper, or less than the hard one). ``aw_gain_pct = 100 (1 - a_w / a_w,
passive)`` and likewise ``tyre_gain_pct``; positive is better than passive.

**Tuning rule** (on the model only, :meth:`FrontsResult.chosen`): each controller's gain is the
one with the largest predicted gain over the model's passive front at equal travel in its own
objective: ``a_w`` for skyhook, tyre load for groundhook and the mean of the two for hybrid.
The same gain is then run on the plant and compared with the plant's own passive front.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.damper import DamperModel
from mrdamper.control.loop._loop import input_limits
from mrdamper.control.loop.closed_loop import check_pair, resolve_plant, simulate_closed_loop
from mrdamper.control.loop.controllers import LAWS
from mrdamper.control.loop.fidelity import MAX_SUBSTEPS, checked_run, loop_metrics
from mrdamper.control.loop.quarter_car import Controller, QuarterCar, QuarterCarResult, iso_road
from mrdamper.control.loop.quarter_car_study import default_rate
from mrdamper.errors import DataValidationError, MrDamperError

__all__ = [
    "FRONT_COLUMNS",
    "GAIN_GRIDS",
    "OBJECTIVES",
    "PASSIVE_LEVELS",
    "FrontsResult",
    "gain_fronts",
    "gap_size",
]

#: Constant inputs of the passive front, as fractions of the input range [-].
PASSIVE_LEVELS: tuple[float, ...] = (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)
#: Gains swept per semi-active controller [N s/m] (hybrid: ``alpha`` [-] x gain): each
#: registered controller's ``front_gains`` (:mod:`mrdamper.control.loop.controllers`).
GAIN_GRIDS: dict[str, tuple[float, ...]] = {
    name: law.front_gains for name, law in LAWS.items() if law.objectives
}
#: Hybrid weights of skyhook swept [-].
HYBRID_ALPHAS: tuple[float, ...] = (0.25, 0.5, 0.75)
#: The metric(s) each controller is tuned for (each controller's ``objectives``).
OBJECTIVES: dict[str, tuple[str, ...]] = {
    name: law.objectives for name, law in LAWS.items() if law.objectives
}
#: Columns of :meth:`FrontsResult.table`.
FRONT_COLUMNS: tuple[str, ...] = (
    "road",
    "speed_m_s",
    "side",
    "controller",
    "level",
    "c_sky",
    "c_ground",
    "alpha",
    "a_w",
    "rms_tyre_load",
    "rms_travel",
    "mean_current",
    "aw_gain_pct",
    "tyre_gain_pct",
    "pareto",
    "status",
)
_METRICS = ("a_w", "rms_tyre_load", "rms_travel", "mean_current")


def gap_size(row: Any, unit: str) -> str:
    """How wide one gap of :meth:`FrontsResult.widest_gaps` is: ``"+29.0 %"``, or for the mean
    input its difference in ``unit`` (``"+0.012 A"``)."""
    if row["metric"] == "mean_current":
        return f"{row['difference']:+.3g} {unit}"
    return f"{row['error_pct']:+.1f} %"


def _points(
    grids: Mapping[str, Sequence[float]], alphas: Sequence[float], levels: Sequence[float]
) -> list[tuple[str, float, Controller]]:
    """``(label, level, controller)`` of every point: passive levels first, then the gains."""
    out = [("passive", float(f), Controller("soft")) for f in levels]
    for kind, gains in grids.items():
        if kind not in OBJECTIVES:
            raise DataValidationError(
                "grids", f"expected semi-active controllers {tuple(OBJECTIVES)}, got {kind!r}"
            )
        law = LAWS[kind]
        for g in gains:
            out += [(kind, np.nan, Controller(kind, **kw)) for kw in law.sweep(g, tuple(alphas))]
    return out


def _gains(label: str, ctrl: Controller) -> dict[str, float]:
    """The gain columns of a row: the gains the point's controller reads, NaN for the others."""
    reads = () if label == "passive" else LAWS[label].gains
    return {
        g: float(getattr(ctrl, g)) if g in reads else np.nan for g in ("c_sky", "c_ground", "alpha")
    }


def _pareto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Points not dominated in ``(a, b)`` (both lower is better; NaN never on the front)."""
    ok = np.isfinite(a) & np.isfinite(b)
    front = np.zeros(a.size, dtype=bool)
    for k in np.flatnonzero(ok):
        dominated = (a[ok] <= a[k]) & (b[ok] <= b[k]) & ((a[ok] < a[k]) | (b[ok] < b[k]))
        front[k] = not dominated.any()
    return front


def _at_travel(passive: pd.DataFrame, travel: np.ndarray, metric: str) -> np.ndarray:
    """The passive front's ``metric`` interpolated at ``travel`` [m] (NaN outside its range)."""
    p = passive[np.isfinite(passive["rms_travel"]) & np.isfinite(passive[metric])]
    p = p.sort_values("rms_travel")
    if len(p) < 2:
        return np.full(travel.size, np.nan)
    xs, ys = p["rms_travel"].to_numpy(), p[metric].to_numpy()
    return np.asarray(np.interp(travel, xs, ys, left=np.nan, right=np.nan), dtype=float)


@dataclass(frozen=True, eq=False)
class FrontsResult:
    """Every point of the gain sweep, predicted and achieved.

    Attributes
    ----------
    model_kind : str
        Kind of the controller model.
    plant_kind : str or None
        Kind of the plant (None: predicted only).
    rows : list of dict
        One per road x side x point (:data:`FRONT_COLUMNS`).
    """

    model_kind: str
    plant_kind: str | None
    rows: list[dict[str, Any]]

    def table(self) -> pd.DataFrame:
        """The sweep (:data:`FRONT_COLUMNS`), with the gains over passive at equal travel and
        the Pareto flag (comfort ``a_w`` against road holding, per road and side)."""
        df = pd.DataFrame(self.rows, columns=[c for c in FRONT_COLUMNS if c in self.rows[0]])
        aw = np.full(len(df), np.nan)
        ty = np.full(len(df), np.nan)
        par = np.zeros(len(df), dtype=bool)
        for _, g in df.groupby(["road", "speed_m_s", "side"], sort=False):
            idx = g.index.to_numpy()
            passive = g[g["controller"] == "passive"]
            tr = g["rms_travel"].to_numpy()
            aw[idx] = 100.0 * (1.0 - g["a_w"].to_numpy() / _at_travel(passive, tr, "a_w"))
            ty[idx] = 100.0 * (
                1.0 - g["rms_tyre_load"].to_numpy() / _at_travel(passive, tr, "rms_tyre_load")
            )
            par[idx] = _pareto(g["a_w"].to_numpy(), g["rms_tyre_load"].to_numpy())
        semi = (df["controller"] != "passive").to_numpy()
        df["aw_gain_pct"] = np.where(semi, aw, np.nan)
        df["tyre_gain_pct"] = np.where(semi, ty, np.nan)
        df["pareto"] = par
        return df[list(FRONT_COLUMNS)]

    def chosen(self) -> pd.DataFrame:
        """The gain of each controller chosen on the model (module docstring) with its predicted
        and, when a plant ran, achieved metrics and gains over passive at equal travel.

        Columns: ``road, speed_m_s, controller, c_sky, c_ground, alpha, objective`` then, per
        side, ``a_w, rms_tyre_load, rms_travel, aw_gain_pct, tyre_gain_pct`` suffixed
        ``_predicted`` / ``_achieved``, and the same three metrics of passive soft (``soft_*``).
        """
        df = self.table()
        keys = ["road", "speed_m_s", "controller", "c_sky", "c_ground", "alpha"]
        cols = ["a_w", "rms_tyre_load", "rms_travel", "aw_gain_pct", "tyre_gain_pct"]
        rows = []
        for (road, sp), g in df.groupby(["road", "speed_m_s"], sort=False):
            pred = g[g["side"] == "predicted"]
            ach = g[g["side"] == "achieved"]
            for kind, objective in OBJECTIVES.items():
                cand = pred[(pred["controller"] == kind) & (pred["status"] == "ok")]
                score = cand[[f"{_GAIN[m]}" for m in objective]].mean(axis=1, skipna=False)
                if cand.empty or not np.isfinite(score).any():
                    continue
                best = cand.loc[score.idxmax()]
                row: dict[str, Any] = {k: best[k] for k in keys}
                row["objective"] = " + ".join(objective)
                for side, part in (("predicted", pred), ("achieved", ach)):
                    match = part[part["controller"] == kind]
                    for k in keys[3:]:
                        match = match[np.isclose(match[k], best[k], equal_nan=True)]
                    for c in cols:
                        row[f"{c}_{side}"] = match[c].iloc[0] if len(match) else np.nan
                    soft = part[(part["controller"] == "passive") & (part["level"] == 0.0)]
                    for c in cols[:3]:
                        row[f"soft_{c}_{side}"] = soft[c].iloc[0] if len(soft) else np.nan
                rows.append(row)
        return pd.DataFrame(rows)

    def fidelity(self) -> pd.DataFrame:
        """Predicted against achieved at every point of the sweep (empty without a plant).

        Returns
        -------
        DataFrame
            One row per road x speed x point x metric (``a_w`` [m/s²], ``rms_tyre_load`` [N],
            ``rms_travel`` [m], ``mean_current`` [A or V]) with the columns ``road, speed_m_s,
            controller, level, c_sky, c_ground, alpha, metric, predicted, achieved, difference,
            error_pct``; ``difference = predicted - achieved`` (the metric's unit) and
            ``error_pct = 100 (predicted - achieved) / achieved`` (NaN where either run was
            refused or the achieved value is 0).
        """
        keys = ["road", "speed_m_s", "controller", "level", "c_sky", "c_ground", "alpha"]
        columns = [*keys, "metric", "predicted", "achieved", "difference", "error_pct"]
        df = pd.DataFrame(self.rows)
        if self.plant_kind is None or df.empty:
            return pd.DataFrame(columns=columns)
        pred = df[df["side"] == "predicted"].reset_index(drop=True)
        ach = df[df["side"] == "achieved"].reset_index(drop=True)
        # Both sides run the same points in the same order (gain_fronts).
        same = pred[keys].fillna(-1.0).to_numpy(dtype=object) == ach[keys].fillna(-1.0).to_numpy(
            dtype=object
        )
        if len(pred) != len(ach) or not same.all():
            raise ValueError("the predicted and achieved sweeps do not run the same points")
        parts = []
        for metric in _METRICS:
            p = pred[metric].to_numpy(dtype=float)
            a = ach[metric].to_numpy(dtype=float)
            with np.errstate(divide="ignore", invalid="ignore"):
                err = np.where(a != 0.0, 100.0 * (p - a) / a, np.nan)
            parts.append(
                pred[keys].assign(
                    metric=metric, predicted=p, achieved=a, difference=p - a, error_pct=err
                )
            )
        return pd.concat(parts, ignore_index=True)[columns]

    def widest_gaps(self) -> pd.DataFrame:
        """Per metric, the point of the sweep where the model's prediction is furthest from the
        plant's (rows of :meth:`fidelity`); empty without a plant.

        ``a_w``, tyre load and travel: the largest ``|error_pct|``. Mean input: the largest
        ``|difference|`` [A or V], since at the soft gains the mean input is near 0 and its ratio
        says nothing.
        """
        fid = self.fidelity().dropna(subset=["difference"])
        if fid.empty:
            return fid
        size = (
            fid["error_pct"].abs().where(fid["metric"] != "mean_current", fid["difference"].abs())
        )
        idx = size.groupby(fid["metric"], sort=False).idxmax().dropna()
        return fid.loc[idx.to_numpy()].reset_index(drop=True)

    def plot(self) -> Any:
        """Comfort against road holding (left) and against travel (right), predicted (open
        markers) and achieved (filled), the passive front as a line (dashed predicted, solid
        achieved) with soft and hard marked, the chosen gains circled; one row per road.

        Returns
        -------
        Figure
        """
        import matplotlib.pyplot as plt

        df = self.table()
        chosen = self.chosen()
        groups = list(df.groupby(["road", "speed_m_s"], sort=False))
        fig, axes = plt.subplots(len(groups), 2, figsize=(7.0, 3.2 * len(groups)), squeeze=False)
        colours = {"passive": "0.3"} | {n: law.colour for n, law in LAWS.items() if law.objectives}
        for k, ((road, sp), g) in enumerate(groups):
            row = axes[k]
            for side, ls, fill in (("predicted", "--", "none"), ("achieved", "-", None)):
                part = g[(g["side"] == side) & (g["status"] == "ok")]
                for ctrl, c in colours.items():
                    pts = part[part["controller"] == ctrl]
                    if pts.empty:
                        continue
                    pts = pts.sort_values("rms_travel")
                    for ax, x in ((row[0], "rms_tyre_load"), (row[1], "rms_travel")):
                        scale = 1e3 if x == "rms_travel" else 1.0
                        ax.plot(
                            scale * pts[x], pts["a_w"], ls=ls if ctrl == "passive" else "none",
                            marker="o", ms=3, lw=0.8, color=c, mfc=fill if fill else c,
                            label=f"{ctrl} ({side})",
                        )  # fmt: skip
                for lvl, name in ((0.0, "soft"), (1.0, "hard")):
                    p = part[(part["controller"] == "passive") & (part["level"] == lvl)]
                    for ax, x in ((row[0], "rms_tyre_load"), (row[1], "rms_travel")):
                        if len(p):
                            scale = 1e3 if x == "rms_travel" else 1.0
                            ax.annotate(
                                name, (scale * p[x].iloc[0], p["a_w"].iloc[0]), fontsize=7,
                                xytext=(3, 3), textcoords="offset points",
                            )  # fmt: skip
                ch = chosen[(chosen["road"] == road) & (chosen["speed_m_s"] == sp)]
                for ax, x in ((row[0], "rms_tyre_load"), (row[1], "rms_travel")):
                    scale = 1e3 if x == "rms_travel" else 1.0
                    ax.plot(
                        scale * ch[f"{x}_{side}"], ch[f"a_w_{side}"], ls="none", marker="o",
                        ms=9, mfc="none", mec="k", mew=0.8,
                    )  # fmt: skip
            row[0].set_xlabel("RMS dynamic tyre load [N]")
            row[1].set_xlabel("RMS suspension travel [mm]")
            for ax in row:
                ax.set_ylabel("a_w [m/s²]")
                ax.set_title(f"ISO {road} @ {sp:g} m/s", fontsize=8)
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=7, frameon=False)
        plant = f", plant {self.plant_kind}" if self.plant_kind else ""
        fig.suptitle(f"{self.model_kind} controller{plant}: circled = gain chosen on the model",
                     fontsize=8)  # fmt: skip
        fig.tight_layout(rect=(0, 0.1 if len(groups) == 1 else 0.05, 1, 0.97))
        return fig


_GAIN = {"a_w": "aw_gain_pct", "rms_tyre_load": "tyre_gain_pct"}


def _run_point(
    model: DamperModel,
    plant: Any,
    road: Any,
    ctrl: Controller,
    car: QuarterCar,
    level: float,
    lo: float,
    hi: float,
    check: bool,
    tol: float,
    max_substeps: int,
) -> dict[str, Any]:
    i_range = (lo + level * (hi - lo), hi) if np.isfinite(level) else None

    def run(s: int) -> QuarterCarResult:
        return simulate_closed_loop(
            model, road, ctrl, car, plant=plant, substeps=s, i_range=i_range
        )

    try:
        r = checked_run(run, tol=tol, max_substeps=max_substeps) if check else run(1)
    except MrDamperError as exc:
        return {**dict.fromkeys(_METRICS, np.nan), "status": str(exc)}
    m = loop_metrics(r[0] if isinstance(r, tuple) else r)
    return {**{k: m[k] for k in _METRICS}, "status": "ok"}


def gain_fronts(
    model: DamperModel,
    plant: Any = None,
    *,
    road_classes: Sequence[str] = ("C",),
    speeds: Sequence[float] = (20.0,),
    duration: float = 20.0,
    seed: int = 0,
    car: QuarterCar | None = None,
    grids: Mapping[str, Sequence[float]] | None = None,
    alphas: Sequence[float] = HYBRID_ALPHAS,
    levels: Sequence[float] = PASSIVE_LEVELS,
    check: bool = True,
    tol: float = 0.005,
    max_substeps: int = MAX_SUBSTEPS,
) -> FrontsResult:
    """Sweep the passive levels and every semi-active controller's gains (module docstring).

    Parameters
    ----------
    model : FittedModel
        Controller model (invertible: a static map, LPV or continuous-time model).
    plant : FittedModel or str, optional
        The damper of the achieved runs (:func:`~mrdamper.control.loop.closed_loop.resolve_plant`);
        None: predicted only.
    road_classes : sequence of str
        ISO 8608 classes.
    speeds : sequence of float
        Vehicle speeds [m/s].
    duration : float
        Road length [s].
    seed : int
        Road phases (the same road for every point).
    car : QuarterCar, optional
        Car (default :class:`QuarterCar()`).
    grids : mapping, optional
        Controller -> gains [N s/m] (default :data:`GAIN_GRIDS`).
    alphas : sequence of float
        Hybrid weights of skyhook [-].
    levels : sequence of float
        Passive inputs as fractions of the input range [-] (0 = soft, 1 = hard; both needed
        for the front's ends).
    check : bool
        Check every run by halving the plant step (a refused run keeps its row with the
        reason in ``status``).
    tol : float
        Halving tolerance [-].
    max_substeps : int
        Finest plant step of the halving check [steps per road sample].

    Returns
    -------
    FrontsResult
    """
    plant_m = None if plant is None else resolve_plant(plant)
    if plant_m is not None:
        check_pair(model, plant_m)
    car = QuarterCar() if car is None else car
    for f in levels:
        if not (0.0 <= float(f) <= 1.0):
            raise DataValidationError("levels", f"expected fractions in [0, 1], got {f!r}")
    lo, hi = input_limits(model)  # within the rated range of the damper, when known
    points = _points(GAIN_GRIDS if grids is None else grids, alphas, levels)
    fs = default_rate(model)
    rows: list[dict[str, Any]] = []
    sides = [("predicted", None)] + ([] if plant_m is None else [("achieved", plant_m)])
    for cls in road_classes:
        for sp in speeds:
            road = iso_road(str(cls), speed=float(sp), duration=duration, fs=fs, seed=seed)
            for side, p in sides:
                for label, level, ctrl in points:
                    out = _run_point(
                        model, p, road, ctrl, car, level, lo, hi, check, tol, max_substeps
                    )
                    rows.append(
                        {
                            "road": str(cls),
                            "speed_m_s": float(sp),
                            "side": side,
                            "controller": label,
                            "level": level,
                            **_gains(label, ctrl),
                            **out,
                        }
                    )
    return FrontsResult(
        str(getattr(model, "kind", "damper")),
        None if plant_m is None else str(plant_m.kind),
        rows,
    )
