"""Numba kernel of the quarter-car simulation with the identified damper in the loop.

Plain arrays only (see :mod:`mrdamper.control.loop.quarter_car` for the equations and choices).

State ``[z_s, v_s, z_u, v_u]`` (deviations from static equilibrium [m, m/s]); the plant is
integrated by the classical fixed-step Runge-Kutta method (RK4) with ``n_sub`` steps of ``h`` per
control sample. The road displacement is linear between its samples (given at the plant rate).

The damper is used through a per-sample step interface:

* static map (SP family, Bingham, linear): force ``sp_force1(x, v, i) - f0`` evaluated at every
  Runge-Kutta stage with the current held over the control sample (with a drive lag, ``rho[k]``,
  the lagged command at the sample instant, is held);
* LPV model: the force of control sample ``k`` is a polynomial in ``rho[k]`` fixed by the past
  (``lpv_coefficients``), and ``u[k]`` is built from the damper velocity at the sample instant;
  the model has no direct feedthrough, so the force of sample ``k + 1`` (``rho`` held) is known
  too, and the force is linear in time between the two (:func:`_between`); a parallel stiffness
  ``k_x`` adds ``k_x x`` with the travel of the sample instant, held over the sample as the
  motion is held for every discrete plant's step.

Controllers (desired damper force ``Fd``, damper velocity ``v_rel = v_s - v_u``, the force acting
on the body is ``-F``): 0 passive (constant input ``i_const``), 1 skyhook
``Fd = c_sky v_s`` when ``v_s v_rel > 0`` else 0, 2 groundhook ``Fd = -c_gnd v_u`` when
``-v_u v_rel > 0`` else 0, 3 hybrid ``Fd = alpha sky + (1 - alpha) ground``. The input realising
``Fd`` comes from the regularised inverse step of the same damper model.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.control.inverse._forms import ControllerForm, InverseForm
from mrdamper.control.inverse._inverse_kernels import (
    horizon_step,
    inverse_input,
    past_buffers,
    reg_solve_poly,
    reg_solve_static,
)
from mrdamper.models.kernels import (
    allowed_interval,
    dahl_step,
    held_input,
    lag_command,
    lpv_coefficients,
    sp_force1,
)
from mrdamper.models.kernels import poly as _poly

__all__ = ["control_sample", "simulate"]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

CTRL_PASSIVE, CTRL_SKYHOOK, CTRL_GROUNDHOOK, CTRL_HYBRID = 0, 1, 2, 3


@njit(cache=True)
def _deriv(  # pragma: no cover - numba
    zs: float,
    vs: float,
    zu: float,
    vu: float,
    zr: float,
    vr: float,
    F: float,
    m_s: float,
    m_u: float,
    k_s: float,
    k_t: float,
    c_t: float,
    out: FloatArray,
) -> None:
    fs = k_s * (zs - zu)
    out[0] = vs
    out[1] = (-fs - F) / m_s
    out[2] = vu
    out[3] = (fs + F - k_t * (zu - zr) - c_t * (vu - vr)) / m_u


@njit(cache=True)
def _between(f0: float, f1: float, s: int, c: float, n_sub: int) -> float:  # pragma: no cover
    """Force of a discrete-time damper between its samples ``f0`` and ``f1`` [N]: linear in
    time, at Runge-Kutta node ``c`` of plant step ``s`` of the ``n_sub`` in a sample."""
    return f0 + (f1 - f0) * (s + c) / n_sub


@njit(cache=True)
def _stage(  # pragma: no cover - numba
    q: FloatArray,
    zr: float,
    vr: float,
    c: float,
    s: int,
    n_sub: int,
    F0: float,
    F1: float,
    r: float,
    inv: InverseForm,
    car: FloatArray,
    out: FloatArray,
) -> float:
    """One Runge-Kutta stage of the plant at the state ``q`` and node ``c`` of plant step ``s``.

    The damper force (rest force removed) [N] is the LPV force between its samples ``F0`` and
    ``F1`` (:func:`_between`) or the static map at the input ``r`` and the motion of ``q``;
    ``out`` receives the state derivative (road at ``zr`` [m], ``vr`` [m/s]). Returns the force.
    """
    if inv.is_lpv:
        Fh = _between(F0, F1, s, c, n_sub)
    else:
        Fh = sp_force1(q[0] - q[2], q[1] - q[3], r, inv.comp, inv.power, inv.theta, inv.f0) - inv.f0
    _deriv(q[0], q[1], q[2], q[3], zr, vr, Fh, car[0], car[1], car[2], car[3], car[4], out)
    return Fh


@njit(cache=True)
def _desired(  # pragma: no cover - numba
    ctrl: int, vs: float, vu: float, c_sky: float, c_gnd: float, alpha: float
) -> float:
    vrel = vs - vu
    sky = c_sky * vs if vs * vrel > 0.0 else 0.0
    gnd = -c_gnd * vu if -vu * vrel > 0.0 else 0.0
    if ctrl == CTRL_SKYHOOK:
        return sky
    if ctrl == CTRL_GROUNDHOOK:
        return gnd
    return alpha * sky + (1.0 - alpha) * gnd


@njit(cache=True)
def invert_model(  # pragma: no cover - numba
    form: ControllerForm,
    k: int,
    x_d: float,
    v_d: float,
    target: float,
    a: float,
    b: float,
    prev: float,
    hold: float,
    cf: FloatArray,
    y: FloatArray,
    u: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    z_d: float,
) -> tuple[float, bool]:
    """The damper model's regularised inverse at control sample ``k`` (the quarter car's own).

    ``target`` is the desired force with the model's rest force (LPV offset, static map ``f0``)
    [N]; an LPV model's stiffness force ``k_x x_d`` is taken out of it here. ``[a, b]`` are the
    admissible inputs, ``prev`` the previous input and ``hold`` the input the regularisation
    pulls towards; ``cf`` the LPV polynomial of the sample (:func:`control_sample` computes it),
    ``y, u`` the LPV past outputs and inputs, ``yb, ub`` scratch, ``z_d`` the Dahl
    state. Returns ``(r, reachable)``.
    """
    inv = form.inverse
    if inv.is_lpv:
        t_poly = target - inv.stiffness * x_d
        if inv.lag >= 0.0 and k >= 2 and inv.horizon > 1:
            valid = past_buffers(y, u, k, yb, ub)
            return horizon_step(inv, cf, yb, ub, valid, a, b, prev, hold, v_d, t_poly, z_d)
        return reg_solve_poly(cf, t_poly, a, b, hold, inv.lam2, inv.n_grid)
    return reg_solve_static(
        x_d, v_d, inv.comp, inv.power, inv.theta, inv.f0, target, a, b, hold, inv.lam2, inv.n_grid
    )


#: The inverse :func:`control_sample` calls; a compiled variant binds another (an exported C
#: inverse: :mod:`mrdamper.control.export.c_inverse`).
INVERT = invert_model


@njit(cache=True)
def control_sample(  # pragma: no cover - numba
    k: int,
    zs: float,
    vs: float,
    zu: float,
    vu: float,
    form: ControllerForm,
    y: FloatArray,
    u: FloatArray,
    cf: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    rho: FloatArray,
    mem: FloatArray,
) -> tuple[float, bool, float, float]:
    """The controller and the damper model's inverse at control sample ``k``.

    ``form`` is the controller (:class:`~mrdamper.control.inverse._forms.ControllerForm`, with the
    damper
    model's inverse). The car state ``zs, vs, zu, vu`` is the one at the sample instant. ``mem``
    carries the
    controller's memory ``[previous input, previous command, Dahl state, previous damper
    velocity]`` (start: the first two the initial input, the others 0); ``y, u`` (LPV past outputs
    and inputs) and ``rho`` are written at index ``k``; ``cf, yb, ub`` are scratch. The model's
    own force is its prediction for the chosen input (LPV: the polynomial at ``rho[k]``, fixed by
    the past; static map: the map at the sample's motion).

    Returns
    -------
    r : float
        Scheduling value chosen (the input, or the input through the drive lag).
    ok : bool
        The desired force is within reach.
    target : float
        Desired force [N] (NaN when passive).
    F_model : float
        The model's force for ``r`` (preload removed) [N].
    """
    inv = form.inverse
    ctrl, lo, hi, rate_step, dt_c = form.ctrl, form.lo, form.hi, form.rate_step, form.dt_c
    alpha, beta, offset, lag, f0 = inv.alpha, inv.beta, inv.offset, inv.lag, inv.f0
    c_sky, c_gnd, alpha_h, i_const = form.gains[0], form.gains[1], form.gains[2], form.gains[3]
    prev, w_prev, z_d, v_prev = mem[0], mem[1], mem[2], mem[3]
    x_d = zs - zu
    v_d = vs - vu
    if inv.blend != 0.0 and k >= 1:
        z_d = dahl_step(z_d, v_prev, v_d, dt_c, inv.stroke)
    v_prev = v_d
    # --- input for this sample
    a, b = allowed_interval(k, lo, hi, lag, rho[k - 1], prev, rate_step)
    if ctrl == CTRL_PASSIVE:
        target = np.nan
    else:
        target = _desired(ctrl, vs, vu, c_sky, c_gnd, alpha_h)
    if inv.is_lpv:
        lpv_coefficients(cf, y, u, k, alpha, beta, offset)
    if ctrl == CTRL_PASSIVE:
        r = min(max(i_const, a), b)
        ok = True
    else:
        hold = held_input(k, lag, prev, w_prev, a, b)
        rest = offset if inv.is_lpv else f0  # the model's force at rest, added to the target
        r, ok = INVERT(form, k, x_d, v_d, target + rest, a, b, prev, hold, cf, y, u, yb, ub, z_d)
    w_prev = lag_command(k, lag, r, prev, lo, hi, w_prev)
    if inv.is_lpv:
        Fk = _poly(cf, r)
        y[k] = Fk - offset
        u[k] = inverse_input(inv, v_d, r, z_d)
        F_model = Fk - offset + inv.stiffness * x_d
    else:
        F_model = sp_force1(x_d, v_d, r, inv.comp, inv.power, inv.theta, f0) - f0
    rho[k] = r
    mem[0], mem[1], mem[2], mem[3] = r, w_prev, z_d, v_prev
    return r, ok, target, F_model


# Cached on disk (compiling takes seconds). Caveat: numba does not invalidate this cache when a
# function it calls in another module (the inverse kernels) changes; after editing those, delete
# this module's cache files (__pycache__/_quarter_car_kernels*.nb*), or a stale copy shadows them.
@njit(cache=True)
def simulate(  # pragma: no cover - numba
    zr: FloatArray, h: float, n_sub: int, car: FloatArray, form: ControllerForm, bound: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, BoolArray, int]:
    """Run the quarter car over a road.

    Parameters
    ----------
    zr : float64[:]
        Road displacement at the plant rate [m], ``n_ctrl * n_sub + 1`` samples.
    h : float
        Plant step [s]; the control (and LPV model) sample is ``n_sub * h``.
    car : float64[:]
        ``[m_s, m_u, k_s, k_t, c_t]`` [kg, kg, N/m, N/m, N s/m].
    form : ControllerForm
        The controller and the damper model's inverse
        (:class:`~mrdamper.control.inverse._forms.ControllerForm`; its control sample ``dt_c`` is
        ``n_sub * h``): an LPV damper (``is_lpv``; with a drive lag, the inverse's lead
        ``horizon`` [samples]; with the hysteretic input, the Dahl state ``z`` of share ``blend``
        and stroke scale ``stroke`` integrated in the loop from the damper velocity at every
        control sample with the model's exact update, from rest ``z = 0``) or a static map.
    bound : float
        Largest admissible ``|state|`` (divergence check).

    Returns
    -------
    X : float64[:, :]
        ``(n_ctrl * n_sub, 5)``: ``z_s, v_s, z_u, v_u, a_s`` at the start of every plant step.
    F : float64[:]
        Damper force (preload removed) at the start of every plant step [N].
    Fd, rho : float64[:]
        Per control sample: desired force [N] (NaN for the passive controller) and the scheduling
        value (the input, or the input through the drive lag).
    sat : bool[:]
        Desired force out of reach at that sample.
    bad : int
        First diverged plant step or -1.
    """
    inv = form.inverse
    is_lpv = inv.is_lpv
    i_const = form.gains[3]
    n_ctrl = (zr.size - 1) // n_sub
    X = np.zeros((n_ctrl * n_sub, 5))
    F = np.zeros(n_ctrl)
    Fp = np.zeros(n_ctrl * n_sub)
    Fd = np.zeros(n_ctrl)
    rho = np.zeros(n_ctrl)
    sat = np.zeros(n_ctrl, dtype=np.bool_)
    n_p = inv.alpha.shape[1]
    y = np.zeros(n_ctrl)
    u = np.zeros(n_ctrl)
    cf = np.zeros(n_p)
    yb = np.zeros(inv.alpha.shape[0])
    ub = np.zeros(inv.alpha.shape[0])
    st = np.zeros(4)
    tmp = np.zeros(4)
    k1 = np.zeros(4)
    k2 = np.zeros(4)
    k3 = np.zeros(4)
    k4 = np.zeros(4)
    lo, hi = form.lo, form.hi
    prev = min(max(i_const, lo), hi) if form.ctrl == CTRL_PASSIVE else lo
    mem = np.array([prev, prev, 0.0, 0.0])  # prev, w_prev, Dahl state, previous velocity
    cf_next = np.zeros(n_p)
    F_next = 0.0
    k_x = inv.stiffness  # LPV parallel stiffness [N/m] (0 for a static map)
    for k in range(n_ctrl):
        r, ok, target, F[k] = control_sample(
            k, st[0], st[1], st[2], st[3], form, y, u, cf, yb, ub, rho, mem
        )
        Fd[k] = target
        sat[k] = not ok
        if is_lpv:  # the next sample's force, fixed by now (b_0 = 0), with rho held
            lpv_coefficients(cf_next, y, u, k + 1, inv.alpha, inv.beta, inv.offset)
            # with the motion held, as every discrete plant's step (k_x x at the sample instant)
            F_next = _poly(cf_next, r) - inv.offset + k_x * (st[0] - st[2])
        # --- plant over the control sample
        for s in range(n_sub):
            j = k * n_sub + s
            z0, z1 = zr[j], zr[j + 1]
            vr = (z1 - z0) / h
            zm = 0.5 * (z0 + z1)
            Fp[j] = _stage(st, z0, vr, 0.0, s, n_sub, F[k], F_next, r, inv, car, k1)
            X[j, 0] = st[0]
            X[j, 1] = st[1]
            X[j, 2] = st[2]
            X[j, 3] = st[3]
            X[j, 4] = k1[1]
            for q in range(4):
                tmp[q] = st[q] + 0.5 * h * k1[q]
            _stage(tmp, zm, vr, 0.5, s, n_sub, F[k], F_next, r, inv, car, k2)
            for q in range(4):
                tmp[q] = st[q] + 0.5 * h * k2[q]
            _stage(tmp, zm, vr, 0.5, s, n_sub, F[k], F_next, r, inv, car, k3)
            for q in range(4):
                tmp[q] = st[q] + h * k3[q]
            _stage(tmp, z1, vr, 1.0, s, n_sub, F[k], F_next, r, inv, car, k4)
            for q in range(4):
                st[q] += h / 6.0 * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q])
                if not (abs(st[q]) <= bound):
                    return X, Fp, Fd, rho, sat, j
    return X, Fp, Fd, rho, sat, -1
