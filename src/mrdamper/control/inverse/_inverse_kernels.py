"""Numba kernel of the causal LPV inverse (plain arrays only; see
:mod:`mrdamper.control.inverse.current`).

At sample ``k`` the LPV output is a polynomial in the present scheduling value ``rho[k]`` once
the past (``y[k-j]``, ``u[k-j]``, j >= 1) is fixed::

    F(rho) = F0 + sum_p c_p rho^p,   c_p = sum_j beta[j-1, p] u[k-j] - alpha[j-1, p] y[k-j]

The kernel picks, in an interval ``[lo_k, hi_k]``: the previous ``rho`` when its force is within
``tol`` of ``F_desired[k]``; else the exact solution ``F = F_desired`` nearest the previous
``rho``; else the nearest edge of the band ``|F - F_desired| <= tol``. Solutions are found by
bisecting (to machine precision) the sign changes on a uniform grid. Without any such ``rho`` the
minimum of ``|F - F_desired|`` lies at an end of the interval or at a stationary point of ``F``;
those are bisected from the sign changes of ``F'`` on the same grid.

The model itself (the LPV output step, its polynomial, the zone-law input, the Dahl step and the
static map) is not written here: it comes from :mod:`mrdamper.models.kernels`, one definition
each, shared with the models' per-sample steps; this module only solves for the input.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.control.inverse._forms import InverseForm
from mrdamper.models.kernels import (
    allowed_interval,
    dahl_step,
    held_input,
    lag_command,
    lpv_coefficients,
    reg_solve_poly,
    reg_solve_static,
    solve_interval,
    sp_force1,
)
from mrdamper.models.kernels import poly as _poly
from mrdamper.models.kernels import zone_input as _u_of

__all__ = [
    "dahl_step",
    "horizon_step",
    "inverse_input",
    "lpv_inverse",
    "lpv_inverse_reg_hys",
    "reg_solve_poly",
    "reg_solve_static",
    "sp_force1",
    "static_inverse_reg",
]

#: Golden-section ratio and iterations of the drive-lag horizon solver (the C export uses the same).
GOLDEN = 0.5 * (5.0**0.5 - 1.0)
N_GOLDEN = 50


FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@njit(cache=True)
def inverse_input(inv: InverseForm, v: float, r: float, z: float) -> float:  # pragma: no cover
    """The LPV model's input ``u`` at velocity ``v`` [m/s], scheduling value ``r`` and Dahl state
    ``z`` [-], by the input law of ``inv`` (its mode, zone laws and hysteretic share)."""
    u: float = _u_of(v, r, inv.mode, inv.gm, inv.gc, inv.mu_high, inv.mu_low, z, inv.blend)
    return u


@njit(cache=True)
def lpv_inverse(  # pragma: no cover - numba
    v: FloatArray,
    F_desired: FloatArray,
    alpha: FloatArray,
    beta: FloatArray,
    offset: float,
    lo: float,
    hi: float,
    lag: float,
    mode: int,
    gm: FloatArray,
    gc: FloatArray,
    mu_high: FloatArray,
    mu_low: FloatArray,
    rho0: float,
    n_grid: int,
    tol: float,
    z: FloatArray,
    blend: float,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Causal, one-pass inverse of the LPV input-output model.

    Parameters
    ----------
    v, F_desired : float64[:]
        Velocity [m/s] and desired force [N] at the model rate.
    alpha, beta : float64[:, :]
        Model coefficients, shape ``(n_m, n_rho + 1)``.
    offset : float
        Force offset ``F0`` [N].
    lo, hi : float
        Admissible range of the electrical input.
    lag : float
        ``exp(-eta dt)`` of the drive lag, or -1 for none. With a lag the command ``w`` in
        ``[lo, hi]`` reaches ``rho[k] = lag rho[k-1] + (1 - lag) w[k-1]``, so ``rho[k]`` is confined
        to ``[lag rho[k-1] + (1-lag) lo, lag rho[k-1] + (1-lag) hi]``, and ``rho[1] = rho[0]``
        (the lag starts at rest, ``rho[0] = w[0]``).
    mode : int
        0: ``u = v``; 1 / 2: continuous / literal reading of eq. 22 with the laws
        ``gm``, ``gc`` (3, d + 1), ``mu_high``, ``mu_low`` (2,).
    rho0 : float
        ``rho`` before the first sample (tie-breaking only).
    n_grid : int
        Grid intervals of the per-sample search.
    tol : float
        Force tolerance [N]: the previous ``rho`` is held while it meets the target within ``tol``.
    z : float64[:]
        Dahl state [-] of the hysteretic input at every sample (it follows the motion only).
    blend : float
        Share of the hysteretic state in the input (0: the static input; ``z`` is then unused).

    Returns
    -------
    rho, F : float64[:]
        Chosen scheduling values and the model force they give [N].
    saturated : bool[:]
        True where no admissible ``rho`` reaches ``F_desired`` exactly.
    """
    n = v.size
    n_p = alpha.shape[1]
    y = np.zeros(n)
    u = np.zeros(n)
    rho = np.zeros(n)
    F = np.zeros(n)
    sat = np.zeros(n, dtype=np.bool_)
    c = np.zeros(n_p)
    prev = rho0
    for k in range(n):
        lpv_coefficients(c, y, u, k, alpha, beta, offset)
        a, b = allowed_interval(k, lo, hi, lag, rho[k - 1], prev, np.inf)
        r, exact = solve_interval(c, F_desired[k], a, b, min(max(prev, a), b), n_grid, tol)
        rho[k] = r
        F[k] = _poly(c, r)
        y[k] = F[k] - offset
        sat[k] = not exact
        u[k] = _u_of(v[k], r, mode, gm, gc, mu_high, mu_low, z[k], blend)
        prev = r
    return rho, F, sat


@njit(cache=True)
def horizon_cost(  # pragma: no cover - numba
    inv: InverseForm,
    cf: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    valid: int,
    r: float,
    w: float,
    v: float,
    target: float,
    z: float,
    ys: FloatArray,
    us: FloatArray,
    c2: FloatArray,
) -> float:
    """Mean squared force error over ``horizon`` samples with the command ``w`` held.

    ``inv`` is the model's :class:`~mrdamper.control.inverse._forms.InverseForm`. Sample 0 has the
    coefficients ``cf`` (fixed by the past) and scheduling value ``r``; then the model runs on:
    ``rho <- lag rho + (1 - lag) w``, the velocity held at ``v`` and the Dahl state at ``z`` (the
    hysteretic input with share ``blend``; 0: static input), the past buffers
    ``yb``, ``ub`` (most recent first, ``valid`` entries in use) copied into ``ys``, ``us``. Every
    sample is compared with the same ``target`` (the desired force now: nothing later is known).
    """
    alpha, beta, offset, lag = inv.alpha, inv.beta, inv.offset, inv.lag
    n_m, n_p = alpha.shape
    for j in range(n_m):
        ys[j] = yb[j]
        us[j] = ub[j]
    F = _poly(cf, r)
    e = F - target
    acc = e * e
    rr = r
    nv = valid
    for _ in range(1, inv.horizon):
        for j in range(n_m - 1, 0, -1):
            ys[j] = ys[j - 1]
            us[j] = us[j - 1]
        ys[0] = F - offset
        us[0] = inverse_input(inv, v, rr, z)
        if nv < n_m:
            nv += 1
        rr = lag * rr + (1.0 - lag) * w
        for p in range(n_p):
            acc2 = 0.0
            for j in range(nv):
                acc2 += beta[j, p] * us[j] - alpha[j, p] * ys[j]
            c2[p] = acc2
        c2[0] += offset
        F = _poly(c2, rr)
        e = F - target
        acc += e * e
    return acc / inv.horizon


@njit(cache=True)
def _horizon_j(  # pragma: no cover - numba
    inv: InverseForm,
    cf: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    valid: int,
    r: float,
    prev: float,
    hold: float,
    v: float,
    target: float,
    z: float,
    ys: FloatArray,
    us: FloatArray,
    c2: FloatArray,
) -> float:
    w = (r - inv.lag * prev) / (1.0 - inv.lag)
    d = r - hold
    return horizon_cost(inv, cf, yb, ub, valid, r, w, v, target, z, ys, us, c2) + inv.lam2 * d * d


@njit(cache=True)
def horizon_step(  # pragma: no cover - numba
    inv: InverseForm,
    cf: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    valid: int,
    a: float,
    b: float,
    prev: float,
    hold: float,
    v: float,
    target: float,
    z: float,
) -> tuple[float, bool]:
    """``rho[k]`` in ``[a, b]`` minimising the horizon cost (:func:`horizon_cost`) of the command it
    implies, ``w = (rho - lag prev) / (1 - lag)``, plus ``lam2 (rho - hold)^2`` (``inv``: the
    model's :class:`~mrdamper.control.inverse._forms.InverseForm`, with ``lag``, ``horizon``,
    ``lam2``,
    ``n_grid``).

    Grid scan of ``n_grid`` intervals (``hold`` included), then ``N_GOLDEN`` golden-section steps
    on the grid intervals either side of the best point (the result is kept only if better).
    Returns ``(rho, reachable)``: ``reachable`` is False when ``target`` lies outside the forces of
    the present sample on the grid.
    """
    n_m, n_p = inv.alpha.shape
    n_grid = inv.n_grid
    ys = np.zeros(n_m)
    us = np.zeros(n_m)
    c2 = np.zeros(n_p)

    def cost(r: float) -> float:  # the horizon cost at rho = r (inlined by numba)
        return _horizon_j(inv, cf, yb, ub, valid, r, prev, hold, v, target, z, ys, us, c2)

    best = min(max(hold, a), b)
    best_j = cost(best)
    f = _poly(cf, best)
    fmin = f
    fmax = f
    if b <= a:
        return best, fmin == target
    h = (b - a) / n_grid
    for q in range(n_grid + 1):
        r = b if q == n_grid else a + q * h
        f = _poly(cf, r)
        fmin = min(fmin, f)
        fmax = max(fmax, f)
        j = cost(r)
        if j < best_j:
            best, best_j = r, j
    lo = max(a, best - h)
    hi = min(b, best + h)
    for _ in range(N_GOLDEN):
        c1 = hi - GOLDEN * (hi - lo)
        c3 = lo + GOLDEN * (hi - lo)
        j1 = cost(c1)
        j3 = cost(c3)
        if j1 <= j3:
            hi = c3
        else:
            lo = c1
    m = 0.5 * (lo + hi)
    jm = cost(m)
    if jm < best_j:
        best = m
    return best, fmin <= target <= fmax


@njit(cache=True)
def past_buffers(  # pragma: no cover - numba
    y: FloatArray, u: FloatArray, k: int, yb: FloatArray, ub: FloatArray
) -> int:
    """``yb[j] = y[k-1-j]``, ``ub[j] = u[k-1-j]`` (zero before the start).

    Returns the entries in use.
    """
    n_m = yb.size
    for j in range(n_m):
        q = k - 1 - j
        yb[j] = y[q] if q >= 0 else 0.0
        ub[j] = u[q] if q >= 0 else 0.0
    return min(n_m, k)


@njit(cache=True)
def lpv_inverse_reg_hys(  # pragma: no cover - numba
    v: FloatArray,
    F_desired: FloatArray,
    inv: InverseForm,
    lo: float,
    hi: float,
    rho0: float,
    rate_step: float,
    z: FloatArray,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Regularised causal inverse of the LPV model (see :mod:`mrdamper.control.inverse.current`).

    Per sample: ``rho[k]`` minimises ``(F_k(rho) - F_desired[k])^2 + lam^2 (rho - hold)^2`` over
    the admissible interval (input limits, the reach of the drive lag when ``lag >= 0``, and
    ``|rho - rho[k-1]| <= rate_step``); ``hold = rho[k-1]``, or with a drive lag the value
    ``rho[k]`` would take with the previous command held (the regularisation then penalises command
    changes, not the lag's own motion). With a drive lag and ``horizon > 1`` (from the third sample
    on) the force term is the mean over ``horizon`` samples with the implied command held
    (:func:`horizon_step`): a causal lead over the lag. ``inv`` is the model's
    :class:`~mrdamper.control.inverse._forms.InverseForm` (with ``lam2``, ``n_grid`` and
    ``horizon``); the
    Dahl state ``z`` of the hysteretic input (share ``inv.blend``) and the other arguments as
    :func:`lpv_inverse`. ``blend = 0``: the static input (``z`` unused).

    Returns
    -------
    rho, F : float64[:]
    saturated : bool[:]
        True where ``F_desired[k]`` lies outside the forces the admissible interval gives.
    """
    alpha, beta, offset, lag = inv.alpha, inv.beta, inv.offset, inv.lag
    n = v.size
    n_p = alpha.shape[1]
    y = np.zeros(n)
    u = np.zeros(n)
    rho = np.zeros(n)
    F = np.zeros(n)
    sat = np.zeros(n, dtype=np.bool_)
    cf = np.zeros(n_p)
    yb = np.zeros(alpha.shape[0])
    ub = np.zeros(alpha.shape[0])
    prev = min(max(rho0, lo), hi)
    w_prev = prev
    for k in range(n):
        lpv_coefficients(cf, y, u, k, alpha, beta, offset)
        a, b = allowed_interval(k, lo, hi, lag, rho[k - 1], prev, rate_step)
        hold = held_input(k, lag, prev, w_prev, a, b)
        if lag >= 0.0 and k >= 2 and inv.horizon > 1:
            valid = past_buffers(y, u, k, yb, ub)
            r, ok = horizon_step(inv, cf, yb, ub, valid, a, b, prev, hold, v[k], F_desired[k], z[k])
        else:
            r, ok = reg_solve_poly(cf, F_desired[k], a, b, hold, inv.lam2, inv.n_grid)
        w_prev = lag_command(k, lag, r, prev, lo, hi, w_prev)
        rho[k] = r
        F[k] = _poly(cf, r)
        y[k] = F[k] - offset
        sat[k] = not ok
        u[k] = inverse_input(inv, v[k], r, z[k])
        prev = r
    return rho, F, sat


@njit(cache=True)
def static_inverse_reg(  # pragma: no cover - numba
    x: FloatArray,
    v: FloatArray,
    F_desired: FloatArray,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    lo: float,
    hi: float,
    i0: float,
    n_grid: int,
    lam: float,
    rate_step: float,
    lag: float,
) -> tuple[FloatArray, BoolArray]:
    """Regularised causal inverse of a static map, sample by sample (see :func:`reg_solve_static`).

    With a drive lag (``lag = exp(-eta dt) >= 0``; -1 for none) the map sees ``rho``, the lagged
    command, and the unknown is ``rho[k]`` within the lag's reach from ``rho[k-1]`` (the command in
    ``[lo, hi]``), regularised towards the ``rho`` the previous command would give, exactly as
    :func:`lpv_inverse_reg_hys`; ``rho[1] = rho[0]`` (the lag starts at rest).
    """
    n = x.size
    out = np.zeros(n)
    sat = np.zeros(n, dtype=np.bool_)
    prev = min(max(i0, lo), hi)
    w_prev = prev
    lam2 = lam * lam
    for k in range(n):
        a, b = allowed_interval(k, lo, hi, lag, out[k - 1], prev, rate_step)
        hold = held_input(k, lag, prev, w_prev, a, b)
        r, ok = reg_solve_static(
            x[k], v[k], comp, power, theta, f0, F_desired[k], a, b, hold, lam2, n_grid
        )
        w_prev = lag_command(k, lag, r, prev, lo, hi, w_prev)
        out[k] = r
        sat[k] = not ok
        prev = r
    return out, sat
