"""Compiled kernels of the Spencer et al. (1997) modified Bouc-Wen model (private).

Everything here works on plain float64 arrays. The parameter vector ``p`` has the order of
:data:`PARAM_NAMES` (SI units, see :mod:`mrdamper.models.spencer.model`). The state is
``s = (y, z, u)``: internal displacement y [m], evolutionary variable z, filtered electrical
input u [A] or [V]. Inputs are sampled records of displacement x [m], velocity v [m/s] and the
electrical input e; within one sampling interval they are interpolated linearly, and every
interval of length ``dt`` [s] is integrated with ``nsub`` classical Runge-Kutta (RK4) sub-steps.

:func:`simulate_sens` integrates the forward sensitivities ``S = ds/dp`` with the same RK4
stages as the state (the variational equations are appended to the state), so the force
derivatives it returns are the exact derivatives of the discrete RK4 solution, not
finite-difference estimates.

Status codes returned by the kernels: 0 ok, 1 the state became non-finite or left its bound,
2 the damping ``c0 + c1`` became non-positive (parameters invalid for the input seen).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models._boucwen import boucwen_rate, powers, sign
from mrdamper.models._substeps import (
    MAX_AUTO_SUBSTEPS,
    SUBSTEP_RATE_PRODUCT,
    interval_substeps,
    substeps_for_rate,
)

__all__ = [
    "MAX_AUTO_SUBSTEPS",
    "N_PARAMS",
    "PARAM_NAMES",
    "STATUS_BAD_DAMPING",
    "STATUS_DIVERGED",
    "STATUS_OK",
    "SUBSTEP_RATE_PRODUCT",
    "SpencerForm",
    "auto_substeps",
    "simulate",
    "simulate_sens",
    "step_advance",
    "step_force",
]

#: Parameter order of the vector ``p`` used by every kernel.
PARAM_NAMES: tuple[str, ...] = (
    "c0a",
    "c0b",
    "k0",
    "c1a",
    "c1b",
    "k1",
    "x0",
    "alpha_a",
    "alpha_b",
    "gamma",
    "beta",
    "A",
    "n",
    "eta",
    "f0",
)
N_PARAMS = len(PARAM_NAMES)
STATUS_OK = 0
STATUS_DIVERGED = 1
STATUS_BAD_DAMPING = 2

# parameter indices (module-level ints are frozen into the compiled code)
C0A, C0B, K0, C1A, C1B, K1, X0, ALA, ALB, GAM, BET, AA, NN, ETA, F0 = range(15)

#: |z| and |y - x| [m] beyond these bounds count as divergence.
Z_LIMIT = 1.0e6
Y_LIMIT = 1.0e3

#: Argument types of the kernels (numba types the values passed; these are for mypy).
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@njit(cache=True)
def _rhs(
    x: float, xd: float, e: float, y: float, z: float, u: float, p: FloatArray
) -> tuple[float, float, float, float]:
    """State derivative (dy, dz, du) and the damping c0 + c1 at one instant."""
    c0 = p[C0A] + p[C0B] * u
    c1 = p[C1A] + p[C1B] * u
    al = p[ALA] + p[ALB] * u
    C = c0 + c1
    yd = (al * z + c0 * xd + p[K0] * (x - y)) / C
    w = xd - yd
    zd = boucwen_rate(w, z, p[GAM], p[BET], p[AA], p[NN])
    ud = -p[ETA] * (u - e)
    return yd, zd, ud, C


@njit(cache=True)
def _force(x: float, xd: float, y: float, z: float, u: float, p: FloatArray) -> float:
    c0 = p[C0A] + p[C0B] * u
    c1 = p[C1A] + p[C1B] * u
    al = p[ALA] + p[ALB] * u
    yd = (al * z + c0 * xd + p[K0] * (x - y)) / (c0 + c1)
    F: float = c1 * yd + p[K1] * (x - p[X0]) + p[F0]
    return F


@njit(cache=True)
def _bad_state(y: float, z: float, u: float, x: float) -> bool:
    if not (np.isfinite(y) and np.isfinite(z) and np.isfinite(u)):
        return True
    return abs(z) > Z_LIMIT or abs(y - x) > Y_LIMIT


@njit(cache=True)
def simulate(
    x: FloatArray,
    v: FloatArray,
    e: FloatArray,
    dt: float,
    p: FloatArray,
    nsub: int,
    y0: float,
    z0: float,
    u0: float,
) -> tuple[FloatArray, int, int]:
    """Free-run force of one record.

    Parameters
    ----------
    x, v, e : ndarray
        Displacement [m], velocity [m/s] and electrical input [A] or [V], one value a sample.
    dt : float
        Sampling interval [s].
    p : ndarray
        Parameters in :data:`PARAM_NAMES` order (SI).
    nsub : int
        RK4 sub-steps per sampling interval.
    y0, z0, u0 : float
        Initial state.

    Returns
    -------
    F : ndarray
        Force [N] at every sample (valid before the failing sample when status != 0).
    status : int
        0 ok, 1 diverged, 2 non-positive damping.
    sample : int
        First failing sample, -1 when ok.
    """
    n = x.size
    F = np.zeros(n)
    s = np.array([y0, z0, u0])
    for k in range(n):
        F[k] = _force(x[k], v[k], s[0], s[1], s[2], p)
        if k == n - 1:
            break
        status = _interval(s, x[k], v[k], e[k], x[k + 1], v[k + 1], e[k + 1], dt, p, nsub)
        if status != STATUS_OK:
            return F, status, (k if status == STATUS_BAD_DAMPING else k + 1)
    return F, STATUS_OK, -1


@njit(cache=True)
def _interval(
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
    p: FloatArray,
    nsub: int,
) -> int:
    """Integrate the state ``s = (y, z, u)`` in place over one interval of ``dt`` [s].

    The inputs are linear between the interval's ends; ``nsub`` classical RK4 sub-steps. Returns
    a status code (the state is left where the failure was found).
    """
    y, z, u = s[0], s[1], s[2]
    hf = 1.0 / nsub
    h = dt * hf
    dx = x1 - x0
    dv = v1 - v0
    de = e1 - e0
    for j in range(nsub):
        t0 = j * hf
        tm = t0 + 0.5 * hf
        t1 = t0 + hf
        xa, va, ea = x0 + t0 * dx, v0 + t0 * dv, e0 + t0 * de
        xm, vm, em = x0 + tm * dx, v0 + tm * dv, e0 + tm * de
        xb, vb, eb = x0 + t1 * dx, v0 + t1 * dv, e0 + t1 * de
        a1, b1, g1, C = _rhs(xa, va, ea, y, z, u, p)
        if not C > 0.0:
            return STATUS_BAD_DAMPING
        a2, b2, g2, _ = _rhs(xm, vm, em, y + 0.5 * h * a1, z + 0.5 * h * b1, u + 0.5 * h * g1, p)
        a3, b3, g3, _ = _rhs(xm, vm, em, y + 0.5 * h * a2, z + 0.5 * h * b2, u + 0.5 * h * g2, p)
        a4, b4, g4, _ = _rhs(xb, vb, eb, y + h * a3, z + h * b3, u + h * g3, p)
        y += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        z += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
        u += h / 6.0 * (g1 + 2.0 * g2 + 2.0 * g3 + g4)
    s[0], s[1], s[2] = y, z, u
    if _bad_state(y, z, u, x1):
        return STATUS_DIVERGED
    return STATUS_OK


class SpencerForm(NamedTuple):
    """The Spencer model as the per-sample step reads it.

    Attributes
    ----------
    p : ndarray
        Parameters in :data:`PARAM_NAMES` order (SI).
    max_h : float
        Largest RK4 sub-step [s]; an interval of ``dt`` takes ``ceil(dt / max_h)`` sub-steps.
    """

    p: FloatArray
    max_h: float


@njit(cache=True)
def step_force(form: SpencerForm, s: FloatArray, x: float, v: float, e: float) -> float:
    """Force [N] at the state ``s = (y, z, u)`` and the present motion (see :mod:`..step`)."""
    return _force(x, v, s[0], s[1], s[2], form.p)


@njit(cache=True)
def step_advance(
    form: SpencerForm,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """Advance ``s`` over one interval of ``dt`` [s] (RK4, inputs linear in between)."""
    nsub = interval_substeps(dt, form.max_h)
    return _interval(s, x0, v0, e0, x1, v1, e1, dt, form.p, nsub)


@njit(cache=True)
def _rhs_jac(
    x: float,
    xd: float,
    e: float,
    y: float,
    z: float,
    u: float,
    p: FloatArray,
    f: FloatArray,
    Js: FloatArray,
    Jp: FloatArray,
) -> float:
    """Fill f = ds/dt, Js = df/ds (3x3), Jp = df/dp (3xP); return c0 + c1."""
    c0 = p[C0A] + p[C0B] * u
    c1 = p[C1A] + p[C1B] * u
    al = p[ALA] + p[ALB] * u
    C: float = c0 + c1
    iC = 1.0 / C
    yd = (al * z + c0 * xd + p[K0] * (x - y)) * iC
    w = xd - yd
    nn = p[NN]
    zn, zn1, lz = powers(z, nn)
    sz = sign(z)
    aw = abs(w)
    gam, bet, A = p[GAM], p[BET], p[AA]
    zd = -gam * aw * sz * zn - bet * w * zn + A * w
    f[0] = yd
    f[1] = zd
    f[2] = -p[ETA] * (u - e)
    # derivatives of yd
    dy_y = -p[K0] * iC
    dy_z = al * iC
    dy_u = (p[ALB] * z + p[C0B] * xd - yd * (p[C0B] + p[C1B])) * iC
    # derivatives of zd with respect to w and z (w held fixed)
    g_w = -gam * sign(w) * sz * zn - bet * zn + A
    g_z = -gam * aw * nn * zn1 - bet * w * nn * sz * zn1
    Js[0, 0] = dy_y
    Js[0, 1] = dy_z
    Js[0, 2] = dy_u
    Js[1, 0] = -g_w * dy_y
    Js[1, 1] = g_z - g_w * dy_z
    Js[1, 2] = -g_w * dy_u
    Js[2, 0] = 0.0
    Js[2, 1] = 0.0
    Js[2, 2] = -p[ETA]
    for j in range(Jp.shape[1]):
        Jp[0, j] = 0.0
        Jp[1, j] = 0.0
        Jp[2, j] = 0.0
    Jp[0, C0A] = w * iC
    Jp[0, C0B] = u * w * iC
    Jp[0, K0] = (x - y) * iC
    Jp[0, C1A] = -yd * iC
    Jp[0, C1B] = -u * yd * iC
    Jp[0, ALA] = z * iC
    Jp[0, ALB] = u * z * iC
    for j in (C0A, C0B, K0, C1A, C1B, ALA, ALB):
        Jp[1, j] = -g_w * Jp[0, j]
    Jp[1, GAM] = -aw * sz * zn
    Jp[1, BET] = -w * zn
    Jp[1, AA] = w
    if nn == 2.0 and z != 0.0:
        lz = np.log(abs(z))
    Jp[1, NN] = (-gam * aw * sz - bet * w) * zn * lz
    Jp[2, ETA] = -(u - e)
    return C


@njit(cache=True)
def _force_jac(
    x: float,
    xd: float,
    y: float,
    z: float,
    u: float,
    p: FloatArray,
    dFs: FloatArray,
    dFp: FloatArray,
) -> float:
    """Return F and fill dF/ds (3) and dF/dp (P)."""
    c0 = p[C0A] + p[C0B] * u
    c1 = p[C1A] + p[C1B] * u
    al = p[ALA] + p[ALB] * u
    C = c0 + c1
    iC = 1.0 / C
    yd = (al * z + c0 * xd + p[K0] * (x - y)) * iC
    w = xd - yd
    for j in range(dFp.size):
        dFp[j] = 0.0
    dFs[0] = -c1 * p[K0] * iC
    dFs[1] = c1 * al * iC
    dFs[2] = c1 * (p[ALB] * z + p[C0B] * xd - yd * (p[C0B] + p[C1B])) * iC + p[C1B] * yd
    dFp[C0A] = c1 * w * iC
    dFp[C0B] = c1 * u * w * iC
    dFp[K0] = c1 * (x - y) * iC
    dFp[C1A] = yd - c1 * yd * iC
    dFp[C1B] = u * yd - c1 * u * yd * iC
    dFp[ALA] = c1 * z * iC
    dFp[ALB] = c1 * u * z * iC
    dFp[K1] = x - p[X0]
    dFp[X0] = -p[K1]
    dFp[F0] = 1.0
    F: float = c1 * yd + p[K1] * (x - p[X0]) + p[F0]
    return F


@njit(cache=True)
def _stage(
    s: FloatArray,
    S: FloatArray,
    h: float,
    k: FloatArray,
    K: FloatArray,
    out_s: FloatArray,
    out_S: FloatArray,
) -> None:
    """out = (s, S) + h * (k, K)."""
    for i in range(3):
        out_s[i] = s[i] + h * k[i]
        for j in range(S.shape[1]):
            out_S[i, j] = S[i, j] + h * K[i, j]


@njit(cache=True)
def _sens_rhs(
    xx: float,
    xd: float,
    e: float,
    s: FloatArray,
    S: FloatArray,
    p: FloatArray,
    cols: IntArray,
    f: FloatArray,
    Js: FloatArray,
    Jp: FloatArray,
    dS: FloatArray,
) -> float:
    C = _rhs_jac(xx, xd, e, s[0], s[1], s[2], p, f, Js, Jp)
    m = S.shape[1]
    for i in range(3):
        for j in range(m):
            dS[i, j] = Js[i, 0] * S[0, j] + Js[i, 1] * S[1, j] + Js[i, 2] * S[2, j] + Jp[i, cols[j]]
    return C


@njit(cache=True)
def simulate_sens(
    x: FloatArray,
    v: FloatArray,
    e: FloatArray,
    dt: float,
    p: FloatArray,
    nsub: int,
    y0: float,
    z0: float,
    u0: float,
    cols: IntArray,
) -> tuple[FloatArray, FloatArray, int, int]:
    """Free-run force of one record and its derivatives with respect to chosen parameters.

    Same arguments as :func:`simulate`, plus ``cols`` (int64 array): indices of the parameters to
    differentiate. Returns ``(F, G, status, sample)`` where ``G[k, j]`` is dF[k]/dp[cols[j]]
    [N per parameter unit], integrated as forward sensitivities together with the state.
    """
    n = x.size
    P = p.size
    m = cols.size
    F = np.zeros(n)
    G = np.zeros((n, m))
    s = np.array([y0, z0, u0])
    S = np.zeros((3, m))
    f1 = np.empty(3)
    f2 = np.empty(3)
    f3 = np.empty(3)
    f4 = np.empty(3)
    K1_ = np.empty((3, m))
    K2_ = np.empty((3, m))
    K3_ = np.empty((3, m))
    K4_ = np.empty((3, m))
    st = np.empty(3)
    St = np.empty((3, m))
    Js = np.empty((3, 3))
    Jp = np.empty((3, P))
    dFs = np.empty(3)
    dFp = np.empty(P)
    hf = 1.0 / nsub
    h = dt * hf
    for k in range(n):
        F[k] = _force_jac(x[k], v[k], s[0], s[1], s[2], p, dFs, dFp)
        for j in range(m):
            G[k, j] = dFs[0] * S[0, j] + dFs[1] * S[1, j] + dFs[2] * S[2, j] + dFp[cols[j]]
        if k == n - 1:
            break
        dx = x[k + 1] - x[k]
        dv = v[k + 1] - v[k]
        de = e[k + 1] - e[k]
        for jj in range(nsub):
            t0 = jj * hf
            tm = t0 + 0.5 * hf
            t1 = t0 + hf
            xa, va, ea = x[k] + t0 * dx, v[k] + t0 * dv, e[k] + t0 * de
            xm, vm, em = x[k] + tm * dx, v[k] + tm * dv, e[k] + tm * de
            xb, vb, eb = x[k] + t1 * dx, v[k] + t1 * dv, e[k] + t1 * de
            C = _sens_rhs(xa, va, ea, s, S, p, cols, f1, Js, Jp, K1_)
            if not C > 0.0:
                return F, G, STATUS_BAD_DAMPING, k
            _stage(s, S, 0.5 * h, f1, K1_, st, St)
            _sens_rhs(xm, vm, em, st, St, p, cols, f2, Js, Jp, K2_)
            _stage(s, S, 0.5 * h, f2, K2_, st, St)
            _sens_rhs(xm, vm, em, st, St, p, cols, f3, Js, Jp, K3_)
            _stage(s, S, h, f3, K3_, st, St)
            _sens_rhs(xb, vb, eb, st, St, p, cols, f4, Js, Jp, K4_)
            for i in range(3):
                s[i] += h / 6.0 * (f1[i] + 2.0 * f2[i] + 2.0 * f3[i] + f4[i])
                for j in range(m):
                    S[i, j] += h / 6.0 * (K1_[i, j] + 2.0 * K2_[i, j] + 2.0 * K3_[i, j] + K4_[i, j])
        if _bad_state(s[0], s[1], s[2], x[k + 1]):
            return F, G, STATUS_DIVERGED, k + 1
    return F, G, STATUS_OK, -1


# ----------------------------------------------------------------------------- step size


def auto_substeps(p: np.ndarray, dt: float, vmax: float, emin: float, emax: float) -> int:
    """Sub-steps per sampling interval from an upper estimate of the model's fastest rate.

    Parameters
    ----------
    p : ndarray
        Parameters in :data:`PARAM_NAMES` order.
    dt : float
        Sampling interval [s].
    vmax : float
        Largest absolute velocity of the record [m/s].
    emin, emax : float
        Range of the electrical input [A] or [V] (u stays inside it).
    """
    c0a, c0b, k0, c1a, c1b, _, _, ala, alb, gam, bet, A, n, eta, _ = (float(a) for a in p)
    damping = [c0a + c0b * u + c1a + c1b * u for u in (emin, emax)]
    cmin = min(damping)
    if not cmin > 0.0:
        return 1  # the kernel reports the invalid damping at the first sample
    # alpha(u) / C(u) is linear-fractional in u, so its extremes lie at the ends of the range
    al_over_c = max(abs(ala + alb * u) / c for u, c in zip((emin, emax), damping))
    shape = bet + gam
    if shape > 0.0 and A != 0.0:
        zmax = (abs(A) / shape) ** (1.0 / n)
    else:
        zmax = abs(A) * 1e-2  # no saturation: a generous guess of the reach of z
    rate = (
        abs(eta)
        + abs(k0) / cmin
        + abs(A) * al_over_c
        + n * (abs(bet) + abs(gam)) * zmax ** (n - 1.0) * 1.5 * vmax
    )
    return substeps_for_rate(dt, rate)
