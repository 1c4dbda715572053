"""Inverting a damper model through its per-sample step: the input that gives a desired force.

A model without an inverse form (Spencer, P-15, LTI, NARX) is inverted along a record by stepping
it under the inputs chosen (:func:`invert_through_step`); :func:`step_control` measures, on the
step, the lead and force authority the inverse needs. The closed loop
(:mod:`mrdamper.control.loop.closed_loop`) and the record inverse
(:mod:`mrdamper.control.inverse.current`) both
call these; this module sits below both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mrdamper.control.damper import DamperModel
from mrdamper.control.inverse._inverse_setup import model_input_limits
from mrdamper.control.loop import _closed_loop_kernels as CK
from mrdamper.control.loop.car import LinearDamper
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models.step import Step, run_step
from mrdamper.models.step_dispatch import pack

__all__ = ["StepControl", "invert_through_step", "plant_step", "step_control"]


def plant_step(model: DamperModel, h: float) -> Step:
    """The per-sample step of ``model`` for a plant step ``h`` [s] (one-line error if none)."""
    if isinstance(model, LinearDamper):
        raise DataValidationError("plant", "a LinearDamper has no per-sample step")
    method = getattr(model, "step", None)
    if method is None:
        raise DataValidationError(
            "plant", f"{type(model).__name__} is not a damper model (no per-sample step)"
        )
    step: Step = method(dt=h)
    return step


@dataclass(frozen=True)
class StepControl:
    """A controller that steps its model (see the module docstring).

    Attributes
    ----------
    step : Step
        The model's step.
    n_lead : int
        Lead of the inverse [control samples].
    authority : float
        Steady force range per input unit at the reference velocity [N per input unit].
    sample : float or None
        The control sample a discrete-time step imposes (its own sample time) [s]; None for a
        continuous-time step (the control sample is the road's).
    """

    step: Step
    n_lead: int
    authority: float
    sample: float | None = None


def step_control(model: DamperModel, dt_c: float, v_ref: float = 0.3) -> StepControl:
    """Measure, on the model's step, the lead and authority of its inverse at control sample
    ``dt_c`` [s]: the force at a steady velocity ``v_ref`` [m/s] with the input held at its low
    end, and after a step to its high end; the lead is the 63 % rise time of the difference.

    A discrete-time step (LTI, NARX: ``Step.dt`` set) is measured and inverted at its own sample
    time, which is then the control sample (``sample`` of the result; ``dt_c`` unused).
    """
    step = plant_step(model, dt_c / 10.0)
    lo, hi = model_input_limits(model)
    if step.dt is not None:
        dt_c = dt = float(step.dt)
    else:
        dt = dt_c / 10.0
    n = round(0.3 / dt) + 1
    t = np.arange(n) * dt
    v = np.full(n, float(v_ref))
    x = v * t - 0.5 * v_ref * t[-1]
    k0 = n // 3
    e_lo = np.full(n, lo)
    e_st = e_lo.copy()
    e_st[k0:] = hi
    F_lo, s1, _ = run_step(step, x, v, e_lo, dt)
    F_st, s2, _ = run_step(step, x, v, e_st, dt)
    if s1 or s2:
        raise DataValidationError("MODEL", f"kind {model.kind!r}: its step fails at {v_ref} m/s")
    d = F_st[k0:] - F_lo[k0:]
    auth = abs(d[-1]) / (hi - lo) if hi > lo else 0.0
    reached = np.nonzero(np.abs(d) >= 0.632 * abs(d[-1]))[0]
    t63 = (reached[0] if reached.size else d.size) * dt
    return StepControl(step, max(1, round(t63 / dt_c)), float(auth), step.dt)


def invert_through_step(
    model: DamperModel,
    x: np.ndarray,
    v: np.ndarray,
    F_desired: np.ndarray,
    dt: float,
    limits: tuple[float, float],
    *,
    reg: float | None = None,
    rate: float | None = None,
    n_grid: int = 4,
) -> tuple[np.ndarray, np.ndarray]:
    """The input that makes ``model`` give ``F_desired`` along a record, through its step.

    For a model without an inverse form (Spencer, P-15, LTI, NARX): the model is stepped along the
    record under the inputs chosen, and at every sample the input minimises the regularised
    error of its mean force over a lead of :func:`step_control`'s samples, with the input held
    (:func:`~mrdamper.control.loop._closed_loop_kernels._invert_record`, the loop's inverse).

    Parameters
    ----------
    model : FittedModel
        A model with a per-sample step.
    x, v, F_desired : ndarray
        Displacement [m], velocity [m/s] and desired force [N] per sample.
    dt : float
        Sampling interval [s] (a discrete-time model's own sample time).
    limits : (float, float)
        Input limits [A] or [V].
    reg, rate : float, optional
        Regularisation weight [N per input unit] (default :func:`default_reg` with the force
        authority measured on the step at the record's peak velocity) and input rate bound
        [input unit/s] (default none).
    n_grid : int
        Intervals of the per-sample search grid.

    Returns
    -------
    e : ndarray
        Input per sample.
    saturated : ndarray of bool
        The lead force missed its target by more than 5 % (+ 1 N).
    """
    from mrdamper.control.inverse._inverse_setup import default_reg, reg_settings

    lo, hi = limits
    vpk = float(np.max(np.abs(v))) if v.size else 0.0
    sc = step_control(model, dt, vpk if vpk > 0 else 0.3)
    if sc.sample is not None and not np.isclose(sc.sample, dt, rtol=1e-9, atol=0.0):
        return _at_model_rate(model, x, v, F_desired, dt, sc.sample, limits, reg, rate, n_grid)
    if reg is None:
        reg = default_reg(model, vpk, dt, authority=sc.authority) if vpk > 0 else 0.0
    lam, step_rate = reg_settings(model, v, reg, rate, lo, hi, dt)
    step = sc.step
    state = step.initial_state(float(x[0]), float(v[0]), float(lo))
    packed = pack(step)
    args = (
        np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(v, dtype=np.float64),
        np.ascontiguousarray(F_desired, dtype=np.float64),
        float(dt),
        int(sc.n_lead),
        0.0,
        float(lo),
        float(hi),
        float(lam) ** 2,
        float(step_rate * dt),
        int(n_grid),
    )
    if packed is not None:
        e, err, bad = CK.invert_record_packed(packed, state, *args)
    else:  # a family added at run time: compiled in this process
        inv = CK.compile_loop(
            step.force, step.advance, step.force, step.advance, cache=False, inverse=True
        )
        e, err, bad = inv(step.form, state, *args)
    if bad >= 0:
        raise SimulationDivergedError(model.kind, int(bad), "its step failed along the record")
    return e, err > 0.05 * np.abs(F_desired) + 1.0


def _at_model_rate(
    model: DamperModel,
    x: np.ndarray,
    v: np.ndarray,
    F_desired: np.ndarray,
    dt: float,
    sample: float,
    limits: tuple[float, float],
    reg: float | None,
    rate: float | None,
    n_grid: int,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`invert_through_step` of a record at another rate than the discrete-time model's
    ``1 / sample`` [Hz]: solved at the model rate (the record resampled as the model's prediction
    resamples it) and the input interpolated back, with a note."""
    from mrdamper._warn import warn_user
    from mrdamper.errors import Note
    from mrdamper.models.rates import to_model_rate

    fs, fs_m = 1.0 / dt, 1.0 / sample
    x_m, v_m, F_m = (to_model_rate(a, fs, fs_m) for a in (x, v, F_desired))
    if v_m.size < 2:
        raise DataValidationError(
            "t", f"record too short: {x.size} samples at {fs:g} Hz give {v_m.size} at {fs_m:g} Hz"
        )
    e_m, sat_m = invert_through_step(
        model, x_m, v_m, F_m, sample, limits, reg=reg, rate=rate, n_grid=n_grid
    )
    warn_user(
        f"{model.kind}: record sampled at {fs:g} Hz, model at {fs_m:g} Hz; the inverse is solved "
        "at the model rate and its input interpolated back onto the record's samples",
        Note,
    )
    t, t_m = np.arange(x.size) * dt, np.arange(v_m.size) * sample
    nearest = np.clip(np.rint(t * fs_m).astype(np.int64), 0, v_m.size - 1)
    return np.interp(t, t_m, e_m), sat_m[nearest]
