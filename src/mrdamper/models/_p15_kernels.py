"""Compiled fixed-step integrator of the P-15 force ODE, on plain arrays.

The P-15 relation ``F = f0 + w1 v + w2 dF/dt + w3 d2F/dt2 + w4 F^3 + w5 F^5`` (each ``w_j`` a
quadratic in the electrical input ``i``) is integrated as the first-order system

``dF/dt = G``,
``dG/dt = (F - f0 - w1 v - w2 G - w4 F^3 - w5 F^5) / w3``

with classical fourth-order Runge-Kutta and ``n_sub`` equal sub-steps per sampling interval;
``v`` and ``i`` are interpolated linearly between samples.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["p15_accel", "p15_simulate"]


@njit(cache=True)
def p15_accel(F: float, G: float, vv: float, ii: float, W: np.ndarray, f0: float) -> float:
    """Second derivative of the force [N/s^2] from the P-15 relation.

    Parameters
    ----------
    F, G : float
        Force [N] and its rate [N/s].
    vv, ii : float
        Velocity [m/s] and electrical input [A or V].
    W : ndarray, shape (5, 3)
        ``w_j(i) = W[j-1, 0] + W[j-1, 1] i + W[j-1, 2] i^2``.
    f0 : float
        Force offset [N].
    """
    i2 = ii * ii
    w1 = W[0, 0] + W[0, 1] * ii + W[0, 2] * i2
    w2 = W[1, 0] + W[1, 1] * ii + W[1, 2] * i2
    w3 = W[2, 0] + W[2, 1] * ii + W[2, 2] * i2
    w4 = W[3, 0] + W[3, 1] * ii + W[3, 2] * i2
    w5 = W[4, 0] + W[4, 1] * ii + W[4, 2] * i2
    F2 = F * F
    return (F - f0 - w1 * vv - w2 * G - w4 * F2 * F - w5 * F2 * F2 * F) / w3


@njit(cache=True)
def p15_simulate(
    v: np.ndarray,
    i: np.ndarray,
    dt: float,
    W: np.ndarray,
    f0: float,
    F0: float,
    G0: float,
    n_sub: int,
    bound: float,
) -> tuple[np.ndarray, int]:
    """Free-run simulation of the P-15 ODE.

    Parameters
    ----------
    v, i : ndarray
        Velocity [m/s] and electrical input [A or V] at the samples.
    dt : float
        Sampling interval [s].
    W : ndarray, shape (5, 3)
        Coefficients (see :func:`p15_accel`).
    f0 : float
        Force offset [N].
    F0, G0 : float
        Initial force [N] and force rate [N/s] at the first sample.
    n_sub : int
        RK4 sub-steps per sampling interval (>= 1).
    bound : float
        Largest accepted ``|F|`` [N].

    Returns
    -------
    F : ndarray
        Force [N] at the samples (valid up to the returned sample).
    bad : int
        ``-1`` on success, otherwise the first sample whose force is non-finite or beyond
        ``bound``.
    """
    n = v.size
    F = np.empty(n)
    F[0] = F0
    y0 = F0
    y1 = G0
    if not (np.isfinite(F0) and np.isfinite(G0)) or abs(F0) > bound:
        return F, 0
    h = dt / n_sub
    for k in range(n - 1):
        va, vb = v[k], v[k + 1]
        ia, ib = i[k], i[k + 1]
        for s in range(n_sub):
            a0 = s / n_sub
            a1 = (s + 0.5) / n_sub
            a2 = (s + 1.0) / n_sub
            vs0 = va + (vb - va) * a0
            vs1 = va + (vb - va) * a1
            vs2 = va + (vb - va) * a2
            is0 = ia + (ib - ia) * a0
            is1 = ia + (ib - ia) * a1
            is2 = ia + (ib - ia) * a2
            k1f = y1
            k1g = p15_accel(y0, y1, vs0, is0, W, f0)
            k2f = y1 + 0.5 * h * k1g
            k2g = p15_accel(y0 + 0.5 * h * k1f, k2f, vs1, is1, W, f0)
            k3f = y1 + 0.5 * h * k2g
            k3g = p15_accel(y0 + 0.5 * h * k2f, k3f, vs1, is1, W, f0)
            k4f = y1 + h * k3g
            k4g = p15_accel(y0 + h * k3f, k4f, vs2, is2, W, f0)
            y0 = y0 + h / 6.0 * (k1f + 2.0 * k2f + 2.0 * k3f + k4f)
            y1 = y1 + h / 6.0 * (k1g + 2.0 * k2g + 2.0 * k3g + k4g)
        F[k + 1] = y0
        if not (np.isfinite(y0) and np.isfinite(y1)) or abs(y0) > bound:
            return F, k + 1
    return F, -1


@njit(cache=True)
def _sens_rhs(
    F: float, G: float, SF: np.ndarray, SG: np.ndarray, vv: float, ii: float, W: np.ndarray, f0: float,
    with_offset: bool, dSF: np.ndarray, dSG: np.ndarray,
) -> float:
    """Force acceleration and the derivatives of the sensitivity states (see p15_sensitivities)."""
    i2 = ii * ii
    w1 = W[0, 0] + W[0, 1] * ii + W[0, 2] * i2
    w2 = W[1, 0] + W[1, 1] * ii + W[1, 2] * i2
    w3 = W[2, 0] + W[2, 1] * ii + W[2, 2] * i2
    w4 = W[3, 0] + W[3, 1] * ii + W[3, 2] * i2
    w5 = W[4, 0] + W[4, 1] * ii + W[4, 2] * i2
    F2 = F * F
    F3 = F2 * F
    F5 = F3 * F2
    a = (F - f0 - w1 * vv - w2 * G - w4 * F3 - w5 * F5) / w3
    daF = (1.0 - 3.0 * w4 * F2 - 5.0 * w5 * F2 * F2) / w3
    daG = -w2 / w3
    regs = (vv, G, a, F3, F5)
    for j in range(5):
        r = -regs[j] / w3
        ip = 1.0
        for p in range(3):
            k = 3 * j + p
            dSF[k] = SG[k]
            dSG[k] = daF * SF[k] + daG * SG[k] + r * ip
            ip *= ii
    if with_offset:
        dSF[15] = SG[15]
        dSG[15] = daF * SF[15] + daG * SG[15] - 1.0 / w3
    return a


@njit(cache=True)
def p15_sensitivities(
    v: np.ndarray,
    i: np.ndarray,
    dt: float,
    W: np.ndarray,
    f0: float,
    F0: float,
    G0: float,
    n_sub: int,
    bound: float,
    with_offset: bool,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Free-run simulation with forward sensitivities of the force to the coefficients.

    The sensitivity states ``SF_k = dF/dW_k`` and ``SG_k = d(dF/dt)/dW_k`` (``W_k`` the 15
    monomial coefficients, row-major, then ``f0`` when ``with_offset``) obey
    ``dSF/dt = SG``, ``dSG/dt = da/dF SF + da/dG SG + da/dW_k`` and start at zero (the initial
    state does not depend on the coefficients); they are integrated with the same RK4 steps.

    Returns
    -------
    F : ndarray, shape (n,)
        Force [N].
    J : ndarray, shape (n, 15 + with_offset)
        ``dF / dW_k`` at the samples.
    bad : int
        ``-1`` on success, else the first non-finite or out-of-bound sample.
    """
    n = v.size
    m = 16 if with_offset else 15
    F = np.empty(n)
    J = np.zeros((n, m))
    F[0] = F0
    y0, y1 = F0, G0
    SF = np.zeros(m)
    SG = np.zeros(m)
    k1F = np.empty(m)
    k1G = np.empty(m)
    k2F = np.empty(m)
    k2G = np.empty(m)
    k3F = np.empty(m)
    k3G = np.empty(m)
    k4F = np.empty(m)
    k4G = np.empty(m)
    tF = np.empty(m)
    tG = np.empty(m)
    h = dt / n_sub
    for k in range(n - 1):
        va, vb = v[k], v[k + 1]
        ia, ib = i[k], i[k + 1]
        for s in range(n_sub):
            a0 = s / n_sub
            a1 = (s + 0.5) / n_sub
            a2 = (s + 1.0) / n_sub
            vs0 = va + (vb - va) * a0
            vs1 = va + (vb - va) * a1
            vs2 = va + (vb - va) * a2
            is0 = ia + (ib - ia) * a0
            is1 = ia + (ib - ia) * a1
            is2 = ia + (ib - ia) * a2
            g1 = _sens_rhs(y0, y1, SF, SG, vs0, is0, W, f0, with_offset, k1F, k1G)
            f1 = y1
            for q in range(m):
                tF[q] = SF[q] + 0.5 * h * k1F[q]
                tG[q] = SG[q] + 0.5 * h * k1G[q]
            f2 = y1 + 0.5 * h * g1
            g2 = _sens_rhs(y0 + 0.5 * h * f1, f2, tF, tG, vs1, is1, W, f0, with_offset, k2F, k2G)
            for q in range(m):
                tF[q] = SF[q] + 0.5 * h * k2F[q]
                tG[q] = SG[q] + 0.5 * h * k2G[q]
            f3 = y1 + 0.5 * h * g2
            g3 = _sens_rhs(y0 + 0.5 * h * f2, f3, tF, tG, vs1, is1, W, f0, with_offset, k3F, k3G)
            for q in range(m):
                tF[q] = SF[q] + h * k3F[q]
                tG[q] = SG[q] + h * k3G[q]
            f4 = y1 + h * g3
            g4 = _sens_rhs(y0 + h * f3, f4, tF, tG, vs2, is2, W, f0, with_offset, k4F, k4G)
            y0 = y0 + h / 6.0 * (f1 + 2.0 * f2 + 2.0 * f3 + f4)
            y1 = y1 + h / 6.0 * (g1 + 2.0 * g2 + 2.0 * g3 + g4)
            for q in range(m):
                SF[q] = SF[q] + h / 6.0 * (k1F[q] + 2.0 * k2F[q] + 2.0 * k3F[q] + k4F[q])
                SG[q] = SG[q] + h / 6.0 * (k1G[q] + 2.0 * k2G[q] + 2.0 * k3G[q] + k4G[q])
        F[k + 1] = y0
        for q in range(m):
            J[k + 1, q] = SF[q]
        if not (np.isfinite(y0) and np.isfinite(y1)) or abs(y0) > bound:
            return F, J, k + 1
    return F, J, -1
