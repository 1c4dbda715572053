"""Controller comparison on the quarter car: every controller on every road, one table, figures.

:func:`compare_controllers` runs :func:`~mrdamper.control.closed_loop.simulate_closed_loop` for
each road (ISO 8608 classes at one speed, plus a bump) and each controller, and returns a
:class:`ControllerComparison` with the metrics table (absolute values and ratios to the passive
soft damper on the same road) and figures: time histories, the body-acceleration PSD (Welch) and
the road-to-body-acceleration transmissibility estimated as ``|P_{r a}| / P_{r r}`` (H1 estimator).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.closed_loop import simulate_closed_loop
from mrdamper.control.quarter_car import (
    CONTROLLERS,
    Controller,
    QuarterCar,
    QuarterCarResult,
    Road,
    bump_road,
    iso_road,
)
from mrdamper.errors import DataValidationError

__all__ = ["ControllerComparison", "compare_controllers", "default_rate"]

_ISO = ("A", "B", "C", "D", "E", "F", "G", "H")


def default_rate(model: Any, plant_step: float = 1e-3) -> float:
    """Plant rate [Hz]: ``1 / plant_step`` for a static damper; for an LPV damper the smallest
    integer multiple of its model rate whose step is at most ``plant_step``."""
    fs_model = getattr(model, "fs", None)
    if getattr(model, "kind", "") == "lpv" and fs_model:
        return float(fs_model) * max(1, math.ceil(1.0 / (plant_step * float(fs_model)) - 1e-9))
    return 1.0 / plant_step


@dataclass(frozen=True, eq=False)
class ControllerComparison:
    """Runs of several controllers over several roads.

    Attributes
    ----------
    results : dict
        ``(road name, controller kind) -> QuarterCarResult``.
    roads : list of str
        Road names in run order.
    controllers : list of str
    """

    results: dict[tuple[str, str], QuarterCarResult]
    roads: list[str]
    controllers: list[str]

    def table(self) -> pd.DataFrame:
        """Metrics per road and controller (:meth:`QuarterCarResult.metrics`), with
        ``acc_wk_vs_soft``, ``tyre_load_vs_soft`` and ``travel_vs_soft``: ratios to the passive soft
        damper on the same road (NaN when ``soft`` was not run)."""
        rows = [self.results[(r, c)].metrics() for r in self.roads for c in self.controllers]
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
        return df

    def to_frame(self) -> pd.DataFrame:
        """Same as :meth:`table`."""
        return self.table()

    def plot_time(self, road: str | None = None, t_range: tuple[float, float] | None = None) -> Any:
        """Body acceleration, suspension travel, dynamic tyre load and input against time.

        Returns
        -------
        Figure
        """
        import matplotlib.pyplot as plt

        road = self.roads[0] if road is None else road
        fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True)
        for c in self.controllers:
            r = self.results[(road, c)]
            sel = slice(None) if t_range is None else (r.t >= t_range[0]) & (r.t <= t_range[1])
            axes[0].plot(r.t[sel], r.a_s[sel], lw=0.7, label=c)
            axes[1].plot(r.t[sel], 1e3 * r.travel[sel], lw=0.7)
            axes[2].plot(r.t[sel], r.tyre_load[sel], lw=0.7)
            axes[3].plot(r.t[sel], r.i[sel], lw=0.7)
        lim = 1e3 * self.results[(road, self.controllers[0])].car.travel_limit
        for y in (-lim, lim):
            axes[1].axhline(y, color="0.5", ls="--", lw=0.6)
        axes[0].set_ylabel("body acc. [m/s²]")
        axes[1].set_ylabel("travel [mm]")
        axes[2].set_ylabel("dyn. tyre load [N]")
        axes[3].set_ylabel("input")
        axes[3].set_xlabel("t [s]")
        axes[0].legend(loc="upper right", ncol=len(self.controllers), fontsize=7)
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
        for c in self.controllers:
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


def _check_authority(model: Any) -> None:
    """Refuse a model identified at one electrical level: its force does not depend on the
    input, so every controller would give the same numbers (no control authority)."""
    from mrdamper.models.levels import check_levels

    check_levels(model, "every controller gives the same numbers")


def compare_controllers(
    model: Any,
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
        Damper model (see :func:`~mrdamper.control.quarter_car.simulate_quarter_car`).
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
        Passed to :func:`~mrdamper.control.quarter_car.simulate_quarter_car` (``reg``, ``rate``,
        ...).
    """
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
    results = {}
    for road in roads:
        for c in ctrls:
            results[(road.name, c.kind)] = simulate_closed_loop(model, road, c, car, **sim_kw)
    return ControllerComparison(
        results=results, roads=[r.name for r in roads], controllers=[c.kind for c in ctrls]
    )
