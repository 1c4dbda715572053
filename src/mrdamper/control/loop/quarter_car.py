"""Quarter-car evaluation of semi-active control with an identified damper model in the loop.

The plant is the 2-DOF quarter car (sprung mass ``m_s`` on the suspension spring ``k_s`` and the
damper, unsprung mass ``m_u`` on the tyre ``k_t``, ``c_t``)::

    m_s z_s'' = -k_s (z_s - z_u) - F
    m_u z_u'' =  k_s (z_s - z_u) + F - k_t (z_u - z_r) - c_t (z_u' - z_r')

with displacements measured from static equilibrium and ``F`` the damper force for the damper
displacement ``x = z_s - z_u`` and velocity ``v = z_s' - z_u'`` (positive in extension). The
damper's force at rest (``f0`` of a static map, ``F0`` of an LPV model: accumulator preload and
load-cell zero) is carried by the static equilibrium and removed. The tyre stays in contact (a
linear tyre); the travel limit is reported, not enforced (no bump stop).

Numerics: fixed-step RK4 (plant step ``h``, default 1 ms or finer) in a compiled kernel
(:mod:`mrdamper.control.loop._quarter_car_kernels`), the controller and the damper's inverse run
once per
control sample, the input is held in between. A static damper map is evaluated at every
Runge-Kutta stage; an LPV damper runs at its own rate ``fs`` (control sample = model sample, several
plant steps per sample). Its force between two samples is linear in time from the present sample's
to the next one's (a first-order hold): the model has no direct feedthrough, so the next sample's
force is fixed once the present sample's motion is known, and it is taken with the present
scheduling value held. Holding the present force instead (a zero-order hold) adds half a sample of
delay to a stiff force, which rings at the model's Nyquist frequency in the loop. The run stops
with :class:`~mrdamper.errors.SimulationDivergedError` when a state leaves ``bound``.

Controllers: passive soft (lowest input), passive hard (highest input), skyhook, groundhook and
hybrid (see :class:`Controller`); the semi-active ones ask for a force and get the input from the
regularised inverse step of the same model (:func:`mrdamper.control.inverse_current`), within the
input limits and an optional rate bound. A force opposite to the damper velocity cannot be produced:
the inverse then drives the input to its lowest value as fast as the regularisation lets it.
"""

from __future__ import annotations

from dataclasses import asdict
from typing import Any, cast

import numpy as np
import pandas as pd

from mrdamper.control.damper import DamperModel
from mrdamper.control.export.c_inverse import c_inverse_form, c_kernels
from mrdamper.control.inverse.current import driver_command
from mrdamper.control.loop import _quarter_car_kernels as QK
from mrdamper.control.loop._loop import (
    LoopSetup,
    controller_form,
    divergence_hint,
    loop_result,
    loop_setup,
)
from mrdamper.control.loop.car import (
    CONTROLLERS,
    Controller,
    LinearDamper,
    QuarterCar,
    QuarterCarResult,
    Road,
    bump_road,
    iso_road,
    loop_inputs,
)
from mrdamper.errors import SimulationDivergedError
from mrdamper.models.lpv import TransferFunctionModel

__all__ = [
    "CONTROLLERS",
    "Controller",
    "LinearDamper",
    "QuarterCar",
    "QuarterCarResult",
    "Road",
    "bump_road",
    "iso_road",
    "simulate_quarter_car",
]


#: Names of the built-in controllers.
def simulate_quarter_car(
    model: DamperModel,
    road: Road,
    controller: Controller | str = "soft",
    car: QuarterCar | None = None,
    *,
    reg: float | None = None,
    v_ref: float = 0.3,
    rate: float | None = None,
    i_range: tuple[float, float] | None = None,
    n_grid: int = 16,
    bound: float = 10.0,
    substeps: int = 1,
    c_inverse: Any = None,
) -> QuarterCarResult:
    """Drive the quarter car over ``road`` with ``model`` as its damper under ``controller``.

    Parameters
    ----------
    model : FittedModel or LinearDamper
        LPV model (kind ``lpv``), static map (``sp1``..``sp4``, ``bingham``) or
        :class:`LinearDamper`.
    road : Road
        Road at the plant rate. With an LPV damper its rate must be an integer multiple of the
        model rate (the control sample is the model sample).
    controller : Controller or str
        A :class:`Controller` or one of :data:`CONTROLLERS` with default gains.
    car : QuarterCar, optional
        Plant parameters (default :class:`QuarterCar()`).
    reg : float, optional
        Regularisation weight of the inverse [N per input unit]; default
        ``default_reg(model, v_ref, dt)`` at the control sample time ``dt`` (rate independent).
    v_ref : float
        Damper velocity setting the default ``reg`` [m/s].
    rate : float, optional
        Largest input change per second [A/s] or [V/s].
    i_range : (float, float), optional
        Input limits (default: the model's ``input_range``).
    n_grid : int
        Search grid of the inverse step.
    bound : float
        Divergence bound on every state [m, m/s].
    substeps : int
        Plant steps per road sample (the road is interpolated linearly in between; the control
        sample is unchanged); 1: the plant step is the road's sampling interval.
    c_inverse : CInverse, str or Path, optional
        A compiled C export of ``model`` whose inverse replaces the loop's own at every control
        sample (:class:`~mrdamper.control.export.c_inverse.CInverse`; a path is loaded with the
        prefix
        taken from the file name). Its settings are the ones fixed at export: ``reg``, ``rate``
        and ``n_grid`` then only matter for the ``saturated`` flag and passive controllers.

    Returns
    -------
    QuarterCarResult
        Signals at the plant rate ``road.fs * substeps``.

    Raises
    ------
    SimulationDivergedError
        A state left ``bound``.
    """

    car, ctrl = loop_inputs(road, controller, car)
    s = loop_setup(
        model,
        road,
        ctrl,
        car,
        reg=reg,
        v_ref=v_ref,
        rate=rate,
        i_range=i_range,
        substeps=substeps,
    )
    kernel: Any = QK.simulate
    form: Any = controller_form(s, n_grid)
    if c_inverse is not None:
        kernel, form = c_kernels()["simulate"], c_inverse_form(model, c_inverse, form)
    X, F, Fd, rho, sat, bad = kernel(s.zr, s.h, s.n_sub, s.car_arr, form, float(bound) * s.mr)
    if bad >= 0:
        raise SimulationDivergedError(
            getattr(model, "kind", "damper"),
            int(bad),
            f"quarter-car state left +-{bound:g} at t = {bad * s.h:.4g} s{divergence_hint(model)}",
        )
    cmd = command_of(model, rho, s)
    return loop_result(s, getattr(model, "kind", "damper"), X, F, Fd, cmd, sat)


def command_of(model: DamperModel, rho: np.ndarray, s: LoopSetup) -> np.ndarray:
    """The electrical command that gives the scheduling values ``rho`` (through a drive lag)."""
    eta = getattr(model, "eta", None)
    if s.arrays["is_lpv"] and eta is not None:
        return driver_command(rho, eta, 1.0 / cast(TransferFunctionModel, model).fs, (s.lo, s.hi))
    if eta is not None:
        return driver_command(rho, eta, s.dt_c, (s.lo, s.hi))
    return rho


def car_table(car: QuarterCar) -> pd.DataFrame:
    """Parameters of ``car`` with their units and the two mode frequencies."""
    units = {
        "m_s": "kg",
        "m_u": "kg",
        "k_s": "N/m",
        "k_t": "N/m",
        "c_t": "N s/m",
        "travel_limit": "m",
        "motion_ratio": "-",
    }
    rows = [(k, v, units[k]) for k, v in asdict(car).items()]
    rows += [
        ("body_frequency", car.body_frequency(), "Hz"),
        ("wheel_hop_frequency", car.wheel_hop_frequency(), "Hz"),
    ]
    return pd.DataFrame(rows, columns=["parameter", "value", "unit"])
