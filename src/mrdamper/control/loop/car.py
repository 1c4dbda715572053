"""The quarter car, its road and its controllers as values (see
:mod:`mrdamper.control.loop.quarter_car`
for the equations and the simulation), and the result of a run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.loop.comfort import weighted_rms
from mrdamper.control.loop.controllers import LAWS, law_of
from mrdamper.errors import DataValidationError

__all__ = [
    "CONTROLLERS",
    "Controller",
    "LinearDamper",
    "QuarterCar",
    "QuarterCarResult",
    "Road",
    "bump_road",
    "iso_road",
    "loop_inputs",
    "positive",
]


def positive(name: str, value: Any, unit: str, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (or >= 0), else a one-line error naming ``name``."""
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise DataValidationError(name, f"expected a number [{unit}], got {value!r}") from None
    ok = math.isfinite(f) and (f >= 0 if allow_zero else f > 0)
    if isinstance(value, bool) or not ok:
        raise DataValidationError(
            name, f"expected a finite value {'>=' if allow_zero else '>'} 0 [{unit}], got {value!r}"
        )
    return f


#: The controllers of the default comparison (the registry :mod:`.controllers`, in its order).
CONTROLLERS = tuple(LAWS)


@dataclass(frozen=True)
class QuarterCar:
    """Quarter-car parameters (defaults: one corner of a mid-size passenger car).

    Attributes
    ----------
    m_s : float
        Sprung mass [kg] (default 300: a quarter of a 1200 kg body).
    m_u : float
        Unsprung mass [kg] (40: wheel, tyre, hub, brake, part of the links).
    k_s : float
        Suspension spring rate at the wheel [N/m] (20 000: body mode ``sqrt(k_s/m_s)/2pi`` =
        1.3 Hz).
    k_t : float
        Tyre vertical stiffness [N/m] (200 000: wheel-hop mode about 12 Hz).
    c_t : float
        Tyre damping [N s/m] (0).
    travel_limit : float
        Suspension travel available either side of static equilibrium [m] (0.08).
    motion_ratio : float
        Damper travel per wheel travel [-] (1: damper at the wheel). The damper sees
        ``motion_ratio`` times the wheel-to-body motion and acts with ``motion_ratio`` times its
        force at the wheel.
    """

    m_s: float = 300.0
    m_u: float = 40.0
    k_s: float = 20_000.0
    k_t: float = 200_000.0
    c_t: float = 0.0
    travel_limit: float = 0.08
    motion_ratio: float = 1.0

    def __post_init__(self) -> None:
        units = {
            "m_s": "kg",
            "m_u": "kg",
            "k_s": "N/m",
            "k_t": "N/m",
            "travel_limit": "m",
            "motion_ratio": "-",
        }
        for name, unit in units.items():
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        object.__setattr__(self, "c_t", positive("c_t", self.c_t, "N s/m", allow_zero=True))

    def body_frequency(self) -> float:
        """Undamped body mode on the spring and tyre in series [Hz]."""
        k = self.k_s * self.k_t / (self.k_s + self.k_t)
        return math.sqrt(k / self.m_s) / (2 * math.pi)

    def wheel_hop_frequency(self) -> float:
        """Undamped wheel-hop mode with the body held [Hz]."""
        return math.sqrt((self.k_s + self.k_t) / self.m_u) / (2 * math.pi)


@dataclass(frozen=True)
class LinearDamper:
    """Ideal linear damper ``F = c v`` (reference plant, no electrical input).

    Attributes
    ----------
    c : float
        Damping coefficient [N s/m].
    """

    c: float
    kind: str = field(default="linear", init=False)
    input: str = field(default="i", init=False)
    input_range: tuple[float, float] = field(default=(0.0, 1.0), init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "c", positive("c", self.c, "N s/m", allow_zero=True))


@dataclass(frozen=True)
class Controller:
    """A damper controller.

    Attributes
    ----------
    kind : str
        A registered controller (:mod:`mrdamper.control.loop.controllers`; by default ``soft`` /
        ``hard``: constant lowest / highest input. ``skyhook``: desired force ``c_sky z_s'`` when
        ``z_s' v > 0``, else 0. ``groundhook``: ``-c_ground z_u'`` when ``-z_u' v > 0``, else 0.
        ``hybrid``: ``alpha`` skyhook + ``(1 - alpha)`` groundhook).
    c_sky, c_ground : float
        Gains [N s/m] (default 3000 each, about 0.6 of the body's critical damping with the
        defaults).
    alpha : float
        Hybrid weight [-].
    """

    kind: str
    c_sky: float = 3000.0
    c_ground: float = 3000.0
    alpha: float = 0.5

    def __post_init__(self) -> None:
        law_of(self.kind)  # one line naming the registered controllers otherwise
        positive("c_sky", self.c_sky, "N s/m", allow_zero=True)
        positive("c_ground", self.c_ground, "N s/m", allow_zero=True)
        if not (0.0 <= float(self.alpha) <= 1.0):
            raise DataValidationError("alpha", f"expected 0 <= alpha <= 1, got {self.alpha!r}")


@dataclass(frozen=True, eq=False)
class Road:
    """Road displacement under the tyre.

    Attributes
    ----------
    name : str
    fs : float
        Sampling rate [Hz].
    z : ndarray
        Road height [m].
    """

    name: str
    fs: float
    z: np.ndarray

    @property
    def t(self) -> np.ndarray:
        """Time [s]."""
        return np.arange(self.z.size) / self.fs


def loop_inputs(
    road: Any, controller: Controller | str, car: QuarterCar | None
) -> tuple[QuarterCar, Controller]:
    """The car (the default :class:`QuarterCar` for None) and the controller (a name in
    :data:`CONTROLLERS` or a :class:`Controller`) of a loop run over ``road``, checked.

    Raises
    ------
    DataValidationError
        For a controller that is neither, or a road that is not a :class:`Road`.
    """
    car = QuarterCar() if car is None else car
    ctrl = Controller(controller) if isinstance(controller, str) else controller
    if not isinstance(ctrl, Controller):
        raise DataValidationError(
            "controller", f"expected a Controller or a name in {CONTROLLERS}, got {controller!r}"
        )
    if not isinstance(road, Road):
        raise DataValidationError("road", f"expected a Road, got {type(road).__name__}")
    return car, ctrl


def iso_road(
    road_class: str,
    *,
    speed: float = 20.0,
    duration: float = 20.0,
    fs: float = 1000.0,
    seed: int = 0,
    min_frequency: float = 0.3,
    max_frequency: float = 30.0,
) -> Road:
    """ISO 8608 road of class ``road_class`` driven at ``speed`` [m/s] (physical amplitude).

    Uses :func:`mrdamper.signals.road_profile` with ``fill=None`` (no scaling) and a 0.5 s fade in
    and out; the band ``[min_frequency, max_frequency]`` [Hz] bounds the synthesis.

    Parameters
    ----------
    road_class : str
        ISO 8608 class ``"A"`` .. ``"H"``.
    speed : float
        Vehicle speed [m/s].
    duration : float
        Length of the road signal [s].
    fs : float
        Sampling rate [Hz].
    seed : int
        Seed of the random phases.
    min_frequency, max_frequency : float
        Temporal frequency band of the synthesis [Hz].
    """
    from mrdamper.signals.road import road_profile

    z = road_profile(
        fs,
        duration,
        seed=seed,
        road_class=road_class,
        speed=speed,
        max_frequency=max_frequency,
        min_frequency=min_frequency,
        stroke=1e3,
        fill=None,
        taper=0.5,
    )
    return Road(name=f"ISO {str(road_class).upper()} @ {speed:g} m/s", fs=float(fs), z=z)


def bump_road(
    *,
    height: float = 0.05,
    length: float = 2.0,
    speed: float = 20.0,
    duration: float = 3.0,
    fs: float = 1000.0,
    start: float = 0.5,
) -> Road:
    """One ``(1 - cos)`` bump of ``height`` [m] and ``length`` [m] reached after ``start`` [s].

    Parameters
    ----------
    height : float
        Bump height [m].
    length : float
        Bump length along the road [m].
    speed : float
        Vehicle speed [m/s].
    duration : float
        Length of the road signal [s].
    fs : float
        Sampling rate [Hz].
    start : float
        Time at which the wheel reaches the bump [s].
    """
    h = positive("height", height, "m")
    L = positive("length", length, "m")
    V = positive("speed", speed, "m/s")
    fs = positive("fs", fs, "Hz")
    n = round(positive("duration", duration, "s") * fs) + 1
    s = V * (np.arange(n) / fs - start)  # distance past the bump's start [m]
    z = np.where((s >= 0) & (s <= L), 0.5 * h * (1 - np.cos(2 * np.pi * np.clip(s, 0, L) / L)), 0.0)
    return Road(name=f"bump {100 * h:g} cm x {L:g} m @ {V:g} m/s", fs=float(fs), z=z)


@dataclass(frozen=True, eq=False)
class QuarterCarResult:
    """One quarter-car run (signals at the plant rate, inputs held per control sample).

    Attributes
    ----------
    road, controller, model_kind : str
    fs : float
        Plant rate [Hz].
    t, z_r, z_s, v_s, z_u, v_u, a_s : ndarray
        Time [s], road [m], body displacement [m] / velocity [m/s], wheel [m] / [m/s], body
        acceleration [m/s^2].
    F, F_desired : ndarray
        Damper force at the wheel (preload removed) and desired force [N] (NaN when passive).
    i : ndarray
        Electrical input (command) [A] or [V].
    saturated : ndarray of bool
        Desired force out of reach.
    car : QuarterCar
    """

    road: str
    controller: str
    model_kind: str
    fs: float
    t: np.ndarray
    z_r: np.ndarray
    z_s: np.ndarray
    v_s: np.ndarray
    z_u: np.ndarray
    v_u: np.ndarray
    a_s: np.ndarray
    F: np.ndarray
    F_desired: np.ndarray
    i: np.ndarray
    saturated: np.ndarray
    car: QuarterCar

    @property
    def travel(self) -> np.ndarray:
        """Suspension travel ``z_s - z_u`` [m] (positive: extension)."""
        return np.asarray(self.z_s - self.z_u)

    @property
    def tyre_load(self) -> np.ndarray:
        """Dynamic tyre load [N] (positive: more load than static)."""
        vr = np.gradient(self.z_r, 1.0 / self.fs)
        return np.asarray(-(self.car.k_t * (self.z_u - self.z_r) + self.car.c_t * (self.v_u - vr)))

    def metrics(self) -> dict[str, Any]:
        """RMS and peak figures of the run.

        Keys: ``rms_acc`` and ``rms_acc_wk`` (ISO 2631 Wk weighted) [m/s^2], ``peak_acc`` [m/s^2],
        ``rms_tyre_load`` [N], ``rms_tyre_load_rel`` (over the static wheel load) [-],
        ``rms_travel``, ``max_travel`` [m], ``travel_over_limit`` (fraction of time beyond the
        limit) [-], ``mean_input`` [A|V], ``saturated`` (fraction) [-].
        """
        static = (self.car.m_s + self.car.m_u) * 9.81
        tl = self.tyre_load
        tr = self.travel
        return {
            "road": self.road,
            "controller": self.controller,
            "rms_acc": float(np.sqrt(np.mean(self.a_s**2))),
            "rms_acc_wk": weighted_rms(self.a_s, self.fs),
            "peak_acc": float(np.max(np.abs(self.a_s))),
            "rms_tyre_load": float(np.sqrt(np.mean(tl**2))),
            "rms_tyre_load_rel": float(np.sqrt(np.mean(tl**2)) / static),
            "rms_travel": float(np.sqrt(np.mean(tr**2))),
            "max_travel": float(np.max(np.abs(tr))),
            "travel_over_limit": float(np.mean(np.abs(tr) > self.car.travel_limit)),
            "mean_input": float(np.mean(self.i)),
            "saturated": float(np.mean(self.saturated)),
        }

    def to_frame(self) -> pd.DataFrame:
        """Signals as columns ``t, z_r, z_s, v_s, z_u, v_u, a_s, F, F_desired, i, saturated``."""
        return pd.DataFrame(
            {
                k: getattr(self, k)
                for k in (
                    "t",
                    "z_r",
                    "z_s",
                    "v_s",
                    "z_u",
                    "v_u",
                    "a_s",
                    "F",
                    "F_desired",
                    "i",
                    "saturated",
                )
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """Body acceleration with the input on a twin axis; returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 3))
        ax.plot(self.t, self.a_s, lw=0.7, label=f"{self.controller}")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("body acceleration [m/s²]")
        ax.legend(loc="upper right")
        return ax
