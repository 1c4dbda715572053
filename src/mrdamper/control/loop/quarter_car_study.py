"""Controller comparison on the quarter car: every controller on every road, one table, figures.

:func:`compare_controllers` runs :func:`~mrdamper.control.loop.closed_loop.simulate_closed_loop` for
each road (ISO 8608 classes at one speed, plus a bump) and each controller, and returns a
:class:`ControllerComparison` with the metrics table (absolute values and ratios to the passive
soft damper on the same road) and figures: time histories, the body-acceleration PSD (Welch) and
the road-to-body-acceleration transmissibility estimated as ``|P_{r a}| / P_{r r}`` (H1 estimator).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.damper import DamperModel
from mrdamper.control.loop._loop import default_rate, limits_note
from mrdamper.control.loop.closed_loop import simulate_closed_loop, stepped
from mrdamper.control.loop.quarter_car import (
    CONTROLLERS,
    Controller,
    QuarterCar,
    QuarterCarResult,
    Road,
    bump_road,
    iso_road,
)
from mrdamper.errors import DataValidationError, SimulationDivergedError

__all__ = ["ControllerComparison", "compare_controllers", "default_rate", "limits_note"]

_ISO = ("A", "B", "C", "D", "E", "F", "G", "H")
NAN = float("nan")


@dataclass(frozen=True, eq=False)
class ControllerComparison:
    """Runs of several controllers over several roads.

    Attributes
    ----------
    results : dict
        ``(road name, controller kind) -> QuarterCarResult`` of the runs that ran.
    roads : list of str
        Road names in run order.
    controllers : list of str
    steps : dict
        ``(road, controller) -> (substeps, change)``: plant steps per road sample and, for a damper
        run through its step, the largest relative change of a metric when that plant step is
        halved (:func:`~mrdamper.control.loop.fidelity.checked_run`; NaN where not checked).
    refused : dict
        ``(road, controller) -> reason`` of the runs that did not run (diverged at every plant
        step, not converged, or a controller the model cannot drive); the others are kept.
    """

    results: dict[tuple[str, str], QuarterCarResult]
    roads: list[str]
    controllers: list[str]
    steps: dict[tuple[str, str], tuple[int, float]] = field(default_factory=dict)
    refused: dict[tuple[str, str], str] = field(default_factory=dict)

    def table(self) -> pd.DataFrame:
        """Metrics per road and controller (:meth:`QuarterCarResult.metrics`), with
        ``acc_wk_vs_soft``, ``tyre_load_vs_soft`` and ``travel_vs_soft``: ratios to the passive soft
        damper on the same road (NaN when ``soft`` was not run); ``substeps`` and
        ``halving_change_pct`` (the plant step and its check, see ``steps``) and ``status``
        (``ok``, or the reason a run was refused, its metrics NaN)."""
        rows = []
        for r in self.roads:
            for c in self.controllers:
                key = (r, c)
                if key in self.results:
                    row = self.results[key].metrics()
                    sub, change = self.steps.get(key, (1, float("nan")))
                    row.update(substeps=sub, halving_change_pct=100 * change, status="ok")
                else:
                    row = {"road": r, "controller": c, "status": self.refused.get(key, "not run")}
                rows.append(row)
        df = pd.DataFrame(rows)
        for col, base in (
            ("acc_wk_vs_soft", "rms_acc_wk"),
            ("tyre_load_vs_soft", "rms_tyre_load"),
            ("travel_vs_soft", "rms_travel"),
        ):
            ref = {
                r: self.results[(r, "soft")].metrics()[base]
                if (r, "soft") in self.results
                else np.nan
                for r in self.roads
            }
            df[col] = df[base] / df["road"].map(ref)
        return df[[c for c in df.columns if c != "status"] + ["status"]]

    def to_frame(self) -> pd.DataFrame:
        """Same as :meth:`table`."""
        return self.table()

    def step_note(self) -> str:
        """The plant steps of the checked runs in one line (``""`` when none was checked): how
        many runs took each step and the largest change of a metric when it was halved."""
        checked = {k: v for k, v in self.steps.items() if np.isfinite(v[1])}
        if not checked:
            return ""
        counts: dict[float, int] = {}
        for k in checked:
            h = 1e3 / self.results[k].fs  # [ms]
            counts[h] = counts.get(h, 0) + 1
        parts = ", ".join(
            f"{h:.4g} ms on {n} run{'s' * (n > 1)}" for h, n in sorted(counts.items())
        )
        worst = max(v[1] for v in checked.values())
        return (
            f"plant step {parts}, each checked by halving it (metrics moved at most "
            f"{100 * worst:.2g} %)"
        )

    def _ran(self, road: str) -> list[str]:
        """The controllers that ran on ``road``."""
        return [c for c in self.controllers if (road, c) in self.results]

    def plot_time(self, road: str | None = None, t_range: tuple[float, float] | None = None) -> Any:
        """Body acceleration, suspension travel, dynamic tyre load and input against time.

        Returns
        -------
        Figure
        """
        import matplotlib.pyplot as plt

        road = self.roads[0] if road is None else road
        fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True)
        ran = self._ran(road)
        for c in ran:
            r = self.results[(road, c)]
            sel = slice(None) if t_range is None else (r.t >= t_range[0]) & (r.t <= t_range[1])
            axes[0].plot(r.t[sel], r.a_s[sel], lw=0.7, label=c)
            axes[1].plot(r.t[sel], 1e3 * r.travel[sel], lw=0.7)
            axes[2].plot(r.t[sel], r.tyre_load[sel], lw=0.7)
            axes[3].plot(r.t[sel], r.i[sel], lw=0.7)
        lim = 1e3 * self.results[(road, ran[0])].car.travel_limit if ran else 0.0
        for y in (-lim, lim):
            axes[1].axhline(y, color="0.5", ls="--", lw=0.6)
        axes[0].set_ylabel("body acc. [m/s²]")
        axes[1].set_ylabel("travel [mm]")
        axes[2].set_ylabel("dyn. tyre load [N]")
        axes[3].set_ylabel("input")
        axes[3].set_xlabel("t [s]")
        axes[0].legend(loc="upper right", ncol=max(1, len(ran)), fontsize=7)
        axes[0].set_title(road)
        fig.tight_layout()
        return fig

    def plot_spectra(self, road: str | None = None, nperseg: int | None = None) -> Any:
        """Body-acceleration PSD and road-to-acceleration transmissibility (Welch, H1) per
        controller.

        Returns
        -------
        Figure
        """
        import matplotlib.pyplot as plt
        from scipy import signal

        road = self.roads[0] if road is None else road
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.5))
        for c in self._ran(road):
            r = self.results[(road, c)]
            seg = nperseg or int(min(r.t.size, 4 * r.fs))
            f, p = signal.welch(r.a_s, r.fs, nperseg=seg)
            _, prr = signal.welch(r.z_r, r.fs, nperseg=seg)
            _, pra = signal.csd(r.z_r, r.a_s, r.fs, nperseg=seg)
            band = (f > 0.3) & (f <= 30.0)
            a1.loglog(f[band], p[band], lw=0.8, label=c)
            a2.loglog(f[band], np.abs(pra[band]) / prr[band], lw=0.8, label=c)
        a1.set_xlabel("f [Hz]")
        a1.set_ylabel("PSD body acc. [(m/s²)²/Hz]")
        a2.set_xlabel("f [Hz]")
        a2.set_ylabel("|a_s / z_r| [1/s²]")
        a1.legend(fontsize=7)
        a1.set_title(road, fontsize=9)
        fig.tight_layout()
        return fig


def _check_authority(model: DamperModel) -> None:
    """Refuse a model identified at one electrical level: its force does not depend on the
    input, so every controller would give the same numbers (no control authority)."""
    from mrdamper.models.levels import check_levels

    check_levels(model, "every controller gives the same numbers")


def compare_controllers(
    model: DamperModel,
    *,
    road_classes: Sequence[str] = ("A", "B", "C", "D", "E"),
    bump: bool = True,
    controllers: Sequence[str | Controller] = CONTROLLERS,
    car: QuarterCar | None = None,
    speed: float = 20.0,
    duration: float = 20.0,
    fs: float | None = None,
    seed: int = 0,
    bump_height: float = 0.05,
    bump_length: float = 2.0,
    **sim_kw: Any,
) -> ControllerComparison:
    """Run every controller on every road.

    Parameters
    ----------
    model : FittedModel or LinearDamper
        Damper model (see :func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car`).
    road_classes : sequence of str
        ISO 8608 classes to drive (each a seeded random road of ``duration`` [s]).
    bump : bool
        Also drive over one ``(1 - cos)`` bump of ``bump_height`` [m] and ``bump_length`` [m].
    controllers : sequence
        Controller names or :class:`Controller` values.
    car : QuarterCar, optional
    speed : float
        Vehicle speed [m/s].
    duration : float
        Length of each ISO road [s].
    fs : float, optional
        Plant rate [Hz] (default :func:`default_rate`).
    seed : int
        Seed of the road phases (the same road for every controller).
    bump_height, bump_length : float
        Height and length of the bump [m].
    **sim_kw
        Passed to :func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car` (``reg``,
        ``rate``,
        ...).

    Returns
    -------
    ControllerComparison
        Every run that ran; a run whose damper goes through a continuous-time step is checked by
        halving its plant step (and sub-stepped where it diverges at the road's step, see
        :func:`_checked`); a run that cannot be made (diverged at every plant step, not
        converged, or a controller the model cannot drive) is a row of ``refused`` with its
        reason.

    Raises
    ------
    SimulationDivergedError, NotConvergedError, DataValidationError
        When no run could be made (the first reason), or for bad settings.
    """
    from mrdamper.control.loop.fidelity import NotConvergedError  # fidelity imports this module

    _check_authority(model)
    fs = default_rate(model) if fs is None else float(fs)
    ctrls = [Controller(c) if isinstance(c, str) else c for c in controllers]
    if not ctrls:
        raise DataValidationError("controllers", "expected at least one controller")
    roads: list[Road] = []
    for k, rc in enumerate(road_classes):
        if str(rc).upper() not in _ISO:
            raise DataValidationError(
                "road_classes", f"expected ISO 8608 classes from {_ISO}, got {rc!r}"
            )
        roads.append(
            iso_road(str(rc).upper(), speed=speed, duration=duration, fs=fs, seed=seed + k)
        )
    if bump:
        roads.append(
            bump_road(
                height=bump_height,
                length=bump_length,
                speed=speed,
                fs=fs,
                duration=max(2.0, 1.5 + bump_length / speed),
            )
        )
    if not roads:
        raise DataValidationError(
            "road_classes", "no road to drive: give road classes or bump=True"
        )
    check = _checked(model, sim_kw)
    results: dict[tuple[str, str], QuarterCarResult] = {}
    steps: dict[tuple[str, str], tuple[int, float]] = {}
    refused: dict[tuple[str, str], str] = {}
    errors: list[Exception] = []
    for road in roads:
        for c in ctrls:
            key = (road.name, c.kind)
            try:
                results[key], *step = _run(model, road, c, car, sim_kw, check)
            except (SimulationDivergedError, NotConvergedError, DataValidationError) as exc:
                # a run the model cannot make is a row; bad settings (any other field) stop here
                if isinstance(exc, DataValidationError) and exc.field != "MODEL":
                    raise
                errors.append(exc)
                refused[key] = f"{type(exc).__name__}: {exc}"
                continue
            steps[key] = (int(step[0]), float(step[1]))
    if not results:
        raise errors[0]
    return ControllerComparison(
        results=results,
        roads=[r.name for r in roads],
        controllers=[c.kind for c in ctrls],
        steps=steps,
        refused=refused,
    )


def _run(
    model: DamperModel,
    road: Road,
    c: Controller,
    car: QuarterCar | None,
    sim_kw: dict[str, Any],
    check: bool,
) -> tuple[QuarterCarResult, int, float]:
    """One run, with its plant steps per road sample and the halving change of its metrics: with
    ``check`` the halving check (:func:`~mrdamper.control.loop.fidelity.checked_run`, which also
    sub-steps a loop that diverges at the road's step), else one run (change NaN)."""
    from mrdamper.control.loop.fidelity import checked_run

    if not check:
        return simulate_closed_loop(model, road, c, car, **sim_kw), sim_kw.get("substeps", 1), NAN

    def run(n: int) -> QuarterCarResult:
        return simulate_closed_loop(model, road, c, car, substeps=n, **sim_kw)

    return checked_run(run)


def _checked(model: DamperModel, sim_kw: dict[str, Any]) -> bool:
    """Whether the runs take the halving check: a damper run through a continuous-time step (a
    model without an inverse form, or another plant), whose plant step is the damper's
    integration step. A discrete-time damper (LPV, LTI, NARX) runs at its own sample time
    whatever the plant step, and a model that is its own damper in the fused kernel at the road's
    step; the caller's ``substeps`` are taken as given."""
    from mrdamper.control.loop.closed_loop import plant_step, resolve_plant

    plant = sim_kw.get("plant")
    if "substeps" in sim_kw or not stepped(model, plant):
        return False
    damper = model if plant is None else resolve_plant(plant)
    return plant_step(damper, 1e-3).dt is None
