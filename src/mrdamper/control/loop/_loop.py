"""What every quarter-car loop kernel needs, prepared once (private).

:func:`loop_setup` turns a damper model, a road, a controller and a car into the plain values the
compiled loops take (the fused static-map / LPV kernel of :mod:`._quarter_car_kernels` and the
generic-plant kernel of :mod:`._closed_loop_kernels`): the inverse's arrays, the input limits,
the control sample and plant step, the regularisation weight, the controller code and gains, the
car scaled by the motion ratio and the road at the plant rate. :func:`loop_result` builds the
:class:`~mrdamper.control.loop.quarter_car.QuarterCarResult` from what a kernel returns;
:func:`controller_form` gives the controller and the model's inverse as the kernels read them
(:mod:`mrdamper.control.inverse._forms`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from mrdamper.control.damper import DamperModel
from mrdamper.control.inverse._forms import ControllerForm, frozen, inverse_form
from mrdamper.control.inverse._inverse_setup import lpv_inverse_fields
from mrdamper.control.inverse.current import (
    default_reg,
    horizon_samples,
    model_input_limits,
    static_map_arrays,
)
from mrdamper.control.loop.car import Controller, QuarterCar, QuarterCarResult, Road, positive
from mrdamper.control.loop.controllers import law_of
from mrdamper.errors import DataValidationError
from mrdamper.models.lpv import TransferFunctionModel

__all__ = [
    "LoopSetup",
    "controller_form",
    "damper_arrays",
    "default_rate",
    "divergence_hint",
    "input_limits",
    "input_unit",
    "limits_note",
    "loop_result",
    "loop_setup",
    "positive",
    "rated_range",
]


def damper_arrays(model: DamperModel | None) -> dict[str, Any]:
    """The model as kernel arrays (static map or LPV); unsupported kinds raise TypeError."""
    from mrdamper.models.protocols import scheduled_form

    empty2 = np.zeros((1, 1))
    out: dict[str, Any] = {
        "is_lpv": False,
        "comp": np.zeros(0, np.int64),
        "power": np.zeros(0, np.int64),
        "theta": np.zeros(0),
        "f0": 0.0,
        "alpha": empty2,
        "beta": empty2,
        "offset": 0.0,
        "lag": -1.0,
        "mode": 0,
        "gm": np.zeros((3, 1)),
        "gc": np.zeros((3, 1)),
        "mu_high": np.zeros(2),
        "mu_low": np.zeros(2),
        "blend": 0.0,
        "stroke": 0.0,
        "stiffness": 0.0,
    }
    if model is None:  # no inverse arrays (a controller that steps the model instead)
        return out
    if getattr(model, "kind", None) == "linear" and hasattr(model, "c"):
        out.update(
            comp=np.array([3], np.int64), power=np.array([0], np.int64), theta=np.array([model.c])
        )
        return out
    if scheduled_form(model) is not None:
        out.update(lpv_inverse_fields(cast(TransferFunctionModel, model)))
        return out
    comp, power, theta, f0 = static_map_arrays(model)
    out.update(comp=comp, power=power, theta=theta, f0=f0)
    return out


@dataclass(frozen=True, eq=False)
class LoopSetup:
    """Plain values of one quarter-car run (see the module docstring).

    ``n_sub`` plant steps of ``h`` [s] per control sample ``dt_c`` [s]; ``zr`` the road at the
    plant rate scaled by the motion ratio ``mr`` (``z_in`` unscaled); ``lo, hi`` input limits;
    ``lam`` regularisation weight [N per input unit]; ``step_rate`` largest input change per
    control sample; ``n_h`` lead horizon of a lagged LPV inverse [samples].
    """

    arrays: dict[str, Any]
    ctrl: Controller
    car: QuarterCar
    road: Road
    lo: float
    hi: float
    n_sub: int
    h: float
    dt_c: float
    n_h: int
    lam: float
    step_rate: float
    code: int
    gains: np.ndarray
    car_arr: np.ndarray
    zr: np.ndarray
    z_in: np.ndarray
    n_ctrl: int
    mr: float


def loop_setup(
    model: DamperModel,
    road: Road,
    ctrl: Controller,
    car: QuarterCar,
    *,
    reg: float | None,
    v_ref: float,
    rate: float | None,
    i_range: tuple[float, float] | None,
    substeps: int,
    arrays: dict[str, Any] | None = None,
    authority: float | None = None,
    sample: float | None = None,
) -> LoopSetup:
    """Prepare one run (``model`` is the controller's model; see :func:`simulate_quarter_car`).

    ``arrays`` overrides :func:`damper_arrays` (a model without inverse arrays); ``authority``
    [N per input unit] then sets the default regularisation weight (:func:`default_reg`);
    ``sample`` [s] is the control sample of a controller that steps a discrete-time model (its
    sample time, an integer number of road samples).
    """
    own = arrays is None  # the model's own inverse arrays (not a model stepped instead)
    arrays = damper_arrays(model) if arrays is None else arrays
    lo, hi = input_limits(model) if i_range is None else (float(i_range[0]), float(i_range[1]))
    if not hi >= lo:
        raise DataValidationError("i_range", f"expected low <= high, got {(lo, hi)}")
    eta = getattr(model, "eta", None)
    if arrays["is_lpv"]:
        fs = cast(TransferFunctionModel, model).fs
        n_sub = _samples_per_sample(road.fs, fs, "an LPV damper")
        if eta is not None:
            arrays["lag"] = float(np.exp(-eta / fs))
        n_h = horizon_samples(eta, 1.0 / fs)
    else:
        n_h = 1
        n_sub = 1
        if sample is not None:  # a stepped discrete-time model: control at its own rate
            n_sub = _samples_per_sample(road.fs, 1.0 / sample, f"the {model.kind} model")
        # a static map with a drive lag, at the road rate (a stepped model's lag is in its step)
        if own and eta is not None:
            arrays["lag"] = float(np.exp(-eta / road.fs))
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise DataValidationError("substeps", f"expected an int >= 1, got {substeps!r}")
    dt_c = 1.0 / road.fs * n_sub  # control sample [s]
    n_sub *= int(substeps)
    h = 1.0 / (road.fs * substeps)
    law = law_of(ctrl.kind)
    if getattr(model, "kind", None) == "linear" or law.passive:
        lam = 0.0
    elif reg is None:
        lam = (
            default_reg(model, positive("v_ref", v_ref, "m/s"), dt_c, authority=authority)
            if hi > lo
            else 0.0
        )
    else:
        lam = positive("reg", reg, "N per input unit", allow_zero=True)
    step_rate = np.inf if rate is None else positive("rate", rate, "input unit/s") * dt_c
    i_const = law.constant_input(lo, hi)
    mr = car.motion_ratio
    # the damper sees mr * (relative motion) and acts with mr * F: scale the plant instead of the
    # model
    car_arr = np.array([car.m_s, car.m_u, car.k_s, car.k_t, car.c_t], dtype=np.float64)
    gains = np.array([ctrl.c_sky / mr**2, ctrl.c_ground / mr**2, ctrl.alpha, i_const])
    zr = np.ascontiguousarray(road.z, dtype=np.float64)
    if substeps > 1:  # the road is linear between its samples
        zr = np.interp(np.arange((zr.size - 1) * substeps + 1) / substeps, np.arange(zr.size), zr)
    z_in = zr
    n_ctrl = (zr.size - 1) // n_sub
    if n_ctrl < 2:
        raise DataValidationError("road", f"too short: {zr.size} samples")
    if mr != 1.0:
        car_arr = np.array(
            [car.m_s / mr**2, car.m_u / mr**2, car.k_s / mr**2, car.k_t / mr**2, car.c_t / mr**2]
        )
        zr = zr * mr
    return LoopSetup(
        arrays=arrays,
        ctrl=ctrl,
        car=car,
        road=road,
        lo=lo,
        hi=hi,
        n_sub=n_sub,
        h=h,
        dt_c=dt_c,
        n_h=n_h,
        lam=lam,
        step_rate=step_rate,
        code=law.code,
        gains=gains,
        car_arr=car_arr,
        zr=np.ascontiguousarray(zr[: n_ctrl * n_sub + 1]),
        z_in=z_in,
        n_ctrl=n_ctrl,
        mr=mr,
    )


def _samples_per_sample(road_fs: float, model_fs: float, what: str) -> int:
    """Road samples per model sample (refused when the road's rate [Hz] is not an integer
    multiple of the model's)."""
    ratio = road_fs / model_fs
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise DataValidationError(
            "road",
            f"road sampled at {road_fs:g} Hz; {what} at {model_fs:g} Hz needs an integer multiple",
        )
    return n


def controller_form(s: LoopSetup, n_grid: int) -> ControllerForm:
    """The controller of the run ``s`` as the compiled loops read it, with the damper model's
    inverse (``n_grid`` intervals of its search grid)."""
    inv = inverse_form(lam=s.lam, n_grid=int(n_grid), horizon=int(s.n_h), **s.arrays)
    return ControllerForm(
        int(s.code),
        frozen(s.gains),
        float(s.lo),
        float(s.hi),
        float(s.step_rate),
        s.n_sub * s.h,
        inv,
    )


def loop_result(
    s: LoopSetup,
    model_kind: str,
    X: np.ndarray,
    F: np.ndarray,
    Fd: np.ndarray,
    cmd: np.ndarray,
    sat: np.ndarray,
) -> QuarterCarResult:
    """The run as a :class:`QuarterCarResult`; ``F`` per plant step or per control sample (then
    held), ``Fd``, ``cmd`` and ``sat`` per control sample."""
    n = s.n_ctrl * s.n_sub
    rep = np.repeat
    mr = s.mr
    return QuarterCarResult(
        road=s.road.name,
        controller=s.ctrl.kind,
        model_kind=model_kind,
        fs=1.0 / s.h,
        t=np.arange(n) * s.h,
        z_r=s.z_in[:n].copy(),
        z_s=X[:, 0] / mr,
        v_s=X[:, 1] / mr,
        z_u=X[:, 2] / mr,
        v_u=X[:, 3] / mr,
        a_s=X[:, 4] / mr,
        F=(F if F.size == n else rep(F, s.n_sub)) * mr,
        F_desired=rep(Fd, s.n_sub) * mr,
        i=rep(cmd, s.n_sub),
        saturated=rep(sat, s.n_sub),
        car=s.car,
    )


def rated_range(model: DamperModel) -> tuple[float, float] | None:
    """The rated input range of the damper behind ``model``'s training records [A] or [V]: the
    input range of the shipped reference damper the virtual rig made them with (provenance
    ``training_damper``), else None (not known)."""
    from mrdamper.rig.reference import REFERENCE_DAMPERS, reference_damper

    name = dict(getattr(model, "provenance", None) or {}).get("training_damper")
    if name not in REFERENCE_DAMPERS:
        return None
    lo, hi = reference_damper(str(name)).input_range
    return float(lo), float(hi)


def input_limits(model: DamperModel) -> tuple[float, float]:
    """A controller's default input limits: the model's
    (:func:`~mrdamper.control.inverse.current.model_input_limits`) within the rated range of its
    damper when known (:func:`rated_range`; the identified range of a measured current can pass
    it: 1.0086 A for a rated 0-1 A driver)."""
    lo, hi = model_input_limits(model)
    rated = rated_range(model)
    if rated is not None and max(lo, rated[0]) <= min(hi, rated[1]):
        lo, hi = max(lo, rated[0]), min(hi, rated[1])
    return lo, hi


def limits_note(model: DamperModel) -> str:
    """One line on the controllers' input limits when the rated range narrows the identified
    one (``""`` otherwise)."""
    lo, hi = input_limits(model)
    mlo, mhi = model_input_limits(model)
    if (lo, hi) == (mlo, mhi):
        return ""
    u = input_unit(model)
    name = dict(getattr(model, "provenance", None) or {}).get("training_damper")
    return (
        f"inputs within [{lo:g}, {hi:g}] {u}, the rated range of the {name} damper the training "
        f"records were made with (identified on [{mlo:.5g}, {mhi:.5g}] {u}); --i-range widens it"
    )


def input_unit(model: DamperModel) -> str:
    """The unit of ``model``'s electrical input: ``"V"`` for a voltage, else ``"A"``."""
    return "V" if getattr(model, "input", "i") == "voltage" else "A"


def divergence_hint(damper: Any) -> str:
    """What a diverged loop's message adds about its damper: for a static map whose force falls
    with velocity somewhere on its input range (a free SP fit past its records), the slope and
    the remedy; otherwise nothing."""
    floor = getattr(damper, "velocity_slope_floor", None)
    if floor is None:
        return ""
    slope, at = floor()
    if slope >= 0:
        return ""
    return (
        f"; the {damper.kind} damper's force falls with velocity (dF/dv down to {slope:.4g} N s/m "
        f"at {at:.4g} {input_unit(damper)}): fit it again with the setting monotone "
        "(the default since 0.2)"
    )


def default_rate(model: DamperModel, plant_step: float = 1e-3) -> float:
    """Plant rate [Hz]: ``1 / plant_step`` for a static damper; for an LPV damper the smallest
    integer multiple of its model rate whose step is at most ``plant_step``."""
    fs_model = getattr(model, "fs", None)
    if getattr(model, "kind", "") == "lpv" and fs_model:
        return float(fs_model) * max(1, math.ceil(1.0 / (plant_step * float(fs_model)) - 1e-9))
    return 1.0 / plant_step
