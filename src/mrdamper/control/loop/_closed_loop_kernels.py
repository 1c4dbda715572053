"""Compiled quarter car with any damper as the plant, through its per-sample step (private).

See :mod:`mrdamper.control.loop.closed_loop` for the choices. The loop is written once, in Python
(:func:`_loop`, :func:`_step_inverse`, :func:`_lead_force`), calling the plant's and the
controller model's step functions through the module names ``P_FORCE``, ``P_ADVANCE``,
``C_FORCE``, ``C_ADVANCE``; :func:`compile_loop` compiles it with those names bound to given
compiled functions (numba freezes globals at compile time, and calls them directly):

* :data:`run_loop_packed` binds them to the built-in families' dispatch
  (:func:`~mrdamper.models.step_dispatch.family_force`, ``family_advance``) and takes the
  families' packed forms: its signature holds arrays and tuples only, so it is compiled once and
  cached on disk;
* :func:`run_loop` binds a family added at run time: compiled once per combination of step
  functions and process, not cached (a kernel specialised on functions cannot be).

The car equations are :func:`~mrdamper.control.loop._quarter_car_kernels._deriv`; the controller and
inverse of a static map or LPV model are
:func:`~mrdamper.control.loop._quarter_car_kernels.control_sample`.
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.control.inverse._forms import ControllerForm
from mrdamper.control.loop._quarter_car_kernels import (
    CTRL_PASSIVE,
    _between,
    _deriv,
    _desired,
    control_sample,
)
from mrdamper.models.kernels import allowed_interval
from mrdamper.models.step_dispatch import family_advance, family_force

__all__ = ["compile_loop", "invert_record_packed", "run_loop", "run_loop_packed"]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
#: A model's form as its step functions take it: a family's NamedTuple (a family added at run
#: time) or a built-in family's packed form (:func:`~mrdamper.models.step_dispatch.pack`).
StepForm = tuple[Any, ...]

# Bound by compile_loop in each compiled variant (placeholders for the Python source).
C_FORCE: Any = None
C_ADVANCE: Any = None
P_FORCE: Any = None
P_ADVANCE: Any = None
LEAD_FORCE: Any = None
STEP_INVERSE: Any = None


def _lead_force(  # pragma: no cover - numba
    form: StepForm,
    state: FloatArray,
    scratch: FloatArray,
    x: float,
    v: float,
    e: float,
    dt: float,
    n_lead: int,
    offset: float,
) -> float:
    """Mean model force (rest force removed) over ``n_lead`` samples of ``dt`` ahead, with the
    input ``e`` and the damper velocity ``v`` held (NaN when the step fails)."""
    scratch[:] = state
    acc = 0.0
    xa = x
    for _ in range(n_lead):
        xb = xa + v * dt
        if C_ADVANCE(form, scratch, xa, v, e, xb, v, e, dt) != 0:
            return np.nan
        acc += C_FORCE(form, scratch, xb, v, e) - offset
        xa = xb
    return acc / n_lead


def _step_inverse(  # pragma: no cover - numba
    form: StepForm,
    state: FloatArray,
    scratch: FloatArray,
    x: float,
    v: float,
    dt: float,
    n_lead: int,
    offset: float,
    target: float,
    a: float,
    b: float,
    prev: float,
    lam2: float,
    n_pts: int,
) -> tuple[float, float]:
    """Regularised inverse of a model through its step, one control sample.

    The lead force ``G(e)``, the mean model force over ``n_lead`` samples of ``dt`` ahead of the
    present ``state`` with ``e`` and the damper velocity held (:func:`_lead_force`), is taken at
    ``n_pts + 1`` inputs evenly over ``[a, b]`` and interpolated linearly in between;
    ``(G(e) - target)^2 + lam2 (e - prev)^2`` is then minimised exactly on every piece.

    Returns
    -------
    e : float
        The input.
    err : float
        ``|G(e) - target|`` of the interpolant [N].
    """
    if not b > a:
        return a, abs(LEAD_FORCE(form, state, scratch, x, v, a, dt, n_lead, offset) - target)
    best, jbest, gbest = a, np.inf, 0.0
    e0 = a
    g0 = LEAD_FORCE(form, state, scratch, x, v, e0, dt, n_lead, offset)
    for i in range(1, n_pts + 1):
        e1 = a + (b - a) * i / n_pts
        g1 = LEAD_FORCE(form, state, scratch, x, v, e1, dt, n_lead, offset)
        sl = (g1 - g0) / (e1 - e0)
        den = sl * sl + lam2
        e = e0 if den == 0.0 else (sl * (target - g0) + sl * sl * e0 + lam2 * prev) / den
        e = min(max(e, e0), e1)
        for c in (e0, e, e1):
            g = g0 + sl * (c - e0)
            j = (g - target) ** 2 + lam2 * (c - prev) ** 2
            if j < jbest:
                best, jbest, gbest = c, j, g
        e0, g0 = e1, g1
    return best, abs(gbest - target)


def _loop(  # pragma: no cover - numba
    zr: FloatArray,
    h: float,
    n_sub: int,
    car: FloatArray,
    form: ControllerForm,
    bound: float,
    c_step: bool,
    c_form: StepForm,
    c_state: FloatArray,
    c_offset: float,
    n_lead: int,
    p_form: StepForm,
    p_state: FloatArray,
    p_offset: float,
    p_every: int,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, BoolArray, int, int]:
    """Run the quarter car with a plant stepped through ``P_FORCE`` / ``P_ADVANCE``.

    Parameters
    ----------
    zr : float64[:]
        Road at the plant rate [m], ``n_ctrl * n_sub + 1`` samples; ``h`` the plant step [s].
    car, form, bound
        As :func:`~mrdamper.control.loop._quarter_car_kernels.simulate`: ``form`` the controller
        (:class:`~mrdamper.control.inverse._forms.ControllerForm`), its inverse arrays ignored when
        ``c_step``.
    c_step : bool
        The controller steps its model (``C_FORCE``, ``C_ADVANCE`` on ``c_form``, state
        ``c_state``, force at rest ``c_offset`` [N]) as an observer driven by the measured damper
        motion and the applied input, and inverts it over ``n_lead`` control samples
        (:func:`_step_inverse`).
    p_form, p_state, p_offset
        The plant's form (for ``P_FORCE`` / ``P_ADVANCE``), state (from rest, updated in place)
        and force at rest [N].
    p_every : int
        0: continuous-time plant, its force evaluated at every Runge-Kutta stage with its state
        held and its state advanced over every plant step; ``m > 0``: discrete-time plant of
        sample ``m h``, its force linear in time between its value at the present sample and
        the value its step gives for the next sample with the motion and input held (first-order
        hold; see :mod:`mrdamper.control.loop.closed_loop`).

    Returns
    -------
    X : float64[:, :]
        ``z_s, v_s, z_u, v_u, a_s`` at the start of every plant step.
    F : float64[:]
        Plant force (rest force removed) at the start of every plant step [N].
    Fd, E : float64[:]
        Per control sample: desired force [N] (NaN when passive) and applied input.
    sat : bool[:]
        Desired force out of reach (per the controller's model).
    bad, status : int
        First failing plant step (-1) and the failure (0 ok, -1 car state beyond ``bound``, else
        the plant's ``advance`` status).
    """
    m_s, m_u, k_s, k_t, c_t = car[0], car[1], car[2], car[3], car[4]
    ctrl, gains, lo, hi, rate_step = form.ctrl, form.gains, form.lo, form.hi, form.rate_step
    alpha = form.inverse.alpha
    i_const = gains[3]
    n_ctrl = (zr.size - 1) // n_sub
    n = n_ctrl * n_sub
    X = np.zeros((n, 5))
    F = np.zeros(n)
    Fd = np.zeros(n_ctrl)
    E = np.zeros(n_ctrl)
    rho = np.zeros(n_ctrl)
    sat = np.zeros(n_ctrl, dtype=np.bool_)
    y = np.zeros(n_ctrl)
    u = np.zeros(n_ctrl)
    cf = np.zeros(alpha.shape[1])
    yb = np.zeros(alpha.shape[0])
    ub = np.zeros(alpha.shape[0])
    scratch = c_state.copy()
    st = np.zeros(4)
    tmp = np.zeros(4)
    kk = np.zeros((4, 4))
    prev = min(max(i_const, lo), hi) if ctrl == CTRL_PASSIVE else lo
    mem = np.array([prev, prev, 0.0, 0.0])
    dt_c = form.dt_c
    e = prev
    xc, vc = 0.0, 0.0  # damper motion at the previous control sample
    Fh, xs, vs_, es = 0.0, 0.0, 0.0, 0.0
    F0h, F1h = 0.0, 0.0
    p_next = p_state.copy()
    for k in range(n_ctrl):
        x_d = st[0] - st[2]
        v_d = st[1] - st[3]
        if c_step:
            if k >= 1 and C_ADVANCE(c_form, c_state, xc, vc, e, x_d, v_d, e, dt_c) != 0:
                return X, F, Fd, E, sat, k * n_sub, -2
            a, b = allowed_interval(k, lo, hi, -1.0, prev, prev, rate_step)
            if ctrl == CTRL_PASSIVE:
                target = np.nan
                r = min(max(i_const, a), b)
                ok = True
            else:
                target = _desired(ctrl, st[1], st[3], gains[0], gains[1], gains[2])
                r, err = STEP_INVERSE(
                    c_form,
                    c_state,
                    scratch,
                    x_d,
                    v_d,
                    dt_c,
                    n_lead,
                    c_offset,
                    target,
                    a,
                    b,
                    prev,
                    form.inverse.lam2,
                    4,
                )
                ok = err <= 0.05 * abs(target) + 1.0
            prev = r
            e = r
        else:
            r, ok, target, _ = control_sample(
                k, st[0], st[1], st[2], st[3], form, y, u, cf, yb, ub, rho, mem
            )
            e = (
                mem[1] if form.inverse.lag >= 0.0 else r
            )  # the command (through a drive lag: its inverse)
        xc, vc = x_d, v_d
        Fd[k] = target
        E[k] = e
        sat[k] = not ok
        # --- plant over the control sample
        for s in range(n_sub):
            j = k * n_sub + s
            z0, z1 = zr[j], zr[j + 1]
            vr = (z1 - z0) / h
            zm = 0.5 * (z0 + z1)
            x0 = st[0] - st[2]
            v0 = st[1] - st[3]
            if p_every > 0 and j % p_every == 0:
                # the force at this sample and at the next, the motion and the input held
                F0h = P_FORCE(p_form, p_state, x0, v0, e) - p_offset
                xs, vs_, es = x0, v0, e
                p_next[:] = p_state
                F1h = F0h
                if P_ADVANCE(p_form, p_next, x0, v0, e, x0, v0, e, p_every * h) == 0:
                    F1h = P_FORCE(p_form, p_next, x0, v0, e) - p_offset
            for q in range(4):
                tmp[q] = st[q]
            for g in range(4):
                if g > 0:
                    c = h if g == 3 else 0.5 * h
                    for q in range(4):
                        tmp[q] = st[q] + c * kk[g - 1, q]
                if p_every == 0:
                    Fh = P_FORCE(p_form, p_state, tmp[0] - tmp[2], tmp[1] - tmp[3], e) - p_offset
                else:
                    Fh = _between(
                        F0h, F1h, j % p_every, 0.0 if g == 0 else (1.0 if g == 3 else 0.5), p_every
                    )
                zg = z0 if g == 0 else (z1 if g == 3 else zm)
                _deriv(tmp[0], tmp[1], tmp[2], tmp[3], zg, vr, Fh, m_s, m_u, k_s, k_t, c_t, kk[g])
                if g == 0:
                    X[j, 0] = st[0]
                    X[j, 1] = st[1]
                    X[j, 2] = st[2]
                    X[j, 3] = st[3]
                    X[j, 4] = kk[0, 1]
                    F[j] = Fh
            for q in range(4):
                st[q] += h / 6.0 * (kk[0, q] + 2.0 * kk[1, q] + 2.0 * kk[2, q] + kk[3, q])
                if not (abs(st[q]) <= bound):
                    return X, F, Fd, E, sat, j, -1
            x1 = st[0] - st[2]
            v1 = st[1] - st[3]
            if p_every == 0:
                status = P_ADVANCE(p_form, p_state, x0, v0, e, x1, v1, e, h)
            elif (j + 1) % p_every == 0:
                status = P_ADVANCE(p_form, p_state, xs, vs_, es, x1, v1, e, p_every * h)
            else:
                status = 0
            if status != 0:
                return X, F, Fd, E, sat, j, status
    return X, F, Fd, E, sat, -1, 0


def _invert_record(  # pragma: no cover - numba
    form: StepForm,
    state: FloatArray,
    x: FloatArray,
    v: FloatArray,
    Fd: FloatArray,
    dt: float,
    n_lead: int,
    offset: float,
    lo: float,
    hi: float,
    lam2: float,
    step_change: float,
    n_pts: int,
) -> tuple[FloatArray, FloatArray, int]:
    """Input of a model through its step along a record (:func:`_step_inverse` per sample).

    At sample ``k`` the model's state is that of the record so far under the inputs chosen;
    the input is chosen for the mean desired force (rest force removed) over the ``n_lead``
    samples ahead, within ``[lo, hi]`` and ``step_change`` of the previous input, and the state
    is advanced to the next sample with it.

    Returns
    -------
    E : float64[:]
        Input per sample.
    err : float64[:]
        ``|G(e) - target|`` of the interpolated lead force [N] per sample.
    bad : int
        First sample whose step failed (-1 when none).
    """
    n = x.size
    E = np.zeros(n)
    err = np.zeros(n)
    scratch = state.copy()
    prev = lo
    for k in range(n):
        a, b = allowed_interval(k, lo, hi, -1.0, prev, prev, step_change)
        j1 = min(n, k + 1 + n_lead)
        target = np.mean(Fd[k + 1 : j1]) if j1 > k + 1 else Fd[k]
        e, err[k] = STEP_INVERSE(
            form, state, scratch, x[k], v[k], dt, n_lead, offset, target, a, b, prev, lam2, n_pts
        )
        E[k] = e
        prev = e
        if k + 1 < n and C_ADVANCE(form, state, x[k], v[k], e, x[k + 1], v[k + 1], e, dt) != 0:
            return E, err, k + 1
    return E, err, -1


def compile_loop(
    c_force: Callable[..., float],
    c_advance: Callable[..., int],
    p_force: Callable[..., float],
    p_advance: Callable[..., int],
    *,
    cache: bool,
    control: Any = None,
    inverse: bool = False,
) -> Any:
    """:func:`_loop` compiled with the controller model's and the plant's step functions bound
    (see the module docstring); ``cache`` caches it on disk (only for functions that are the same
    in every process); ``control`` replaces
    :func:`~mrdamper.control.loop._quarter_car_kernels.control_sample` (a variant with another
    inverse:
    :mod:`mrdamper.control.export.c_inverse`); ``inverse`` compiles :func:`_invert_record` instead
    (the
    controller model's functions bound)."""
    names = dict(globals())
    names.update(C_FORCE=c_force, C_ADVANCE=c_advance, P_FORCE=p_force, P_ADVANCE=p_advance)
    if control is not None:
        names["control_sample"] = control

    def bind(fn: Any, cached: bool) -> Any:
        copy = types.FunctionType(fn.__code__, names, fn.__name__, fn.__defaults__)
        copy.__doc__ = fn.__doc__
        return njit(cache=cached)(copy)

    names["LEAD_FORCE"] = bind(_lead_force, False)
    names["STEP_INVERSE"] = bind(_step_inverse, False)
    if inverse:
        return bind(_invert_record, cache)
    return bind(_loop, cache)


#: The loop for the built-in families, given packed forms
#: (:func:`mrdamper.models.step_dispatch.pack`); compiled once, cached on disk.
run_loop_packed = compile_loop(
    family_force, family_advance, family_force, family_advance, cache=True
)

#: :func:`_invert_record` for the built-in families' packed forms (cached on disk).
invert_record_packed = compile_loop(
    family_force, family_advance, family_force, family_advance, cache=True, inverse=True
)

_RUNTIME: dict[tuple[Any, ...], Any] = {}


def run_loop(
    c_force: Callable[..., float],
    c_advance: Callable[..., int],
    p_force: Callable[..., float],
    p_advance: Callable[..., int],
    control: Any = None,
) -> Any:
    """The loop for step functions of a family added at run time (compiled on its first run in
    this process, kept for the next); ``control`` as :func:`compile_loop`."""
    key = (c_force, c_advance, p_force, p_advance, control)
    if key not in _RUNTIME:
        _RUNTIME[key] = compile_loop(
            c_force, c_advance, p_force, p_advance, cache=False, control=control
        )
    return _RUNTIME[key]
