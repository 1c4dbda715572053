"""Compiled L-stable integrator of the P-15 force ODE, with exact discrete sensitivities.

The P-15 relation ``F = f0 + w1 v + w2 F' + w3 F'' + w4 F^3 + w5 F^5`` is integrated as
``F' = G``, ``G' = a(F, G) = (F - f0 - w1 v - w2 G - w4 F^3 - w5 F^5) / w3`` with the two-stage,
second-order, L-stable and stiffly accurate singly diagonally implicit Runge-Kutta scheme of
Alexander (1977), ``gamma = 1 - 1/sqrt(2)``::

    Y1 = y_n + h gamma f(t_n + gamma h, Y1)
    Y2 = y_n + h (1 - gamma) f(t_n + gamma h, Y1) + h gamma f(t_n + h, Y2),   y_{n+1} = Y2

``v`` and ``i`` are interpolated linearly between samples. Each stage is one scalar equation in
``G`` (``F = A + h gamma G``): ``psi(G) = G - B - h gamma a(A + h gamma G, G) = 0`` with
``psi' = 1 + h gamma c / m + (h gamma)^2 g'(F) / m`` (``m = -w3``, ``c = -w2``,
``g(F) = F - w4 F^3 - w5 F^5``). When ``m, c > 0`` and ``g' > 0`` (the conditions the output-error
fit guarantees), ``psi`` is strictly increasing and has exactly one root; it is found by
Newton's method safeguarded by bisection. A stage whose root is not found (possible only when
those conditions fail) stops the simulation and is reported like a divergence.

The sensitivities are those of the discrete scheme (exact derivatives of the computed force with
respect to the coefficients): differentiating each stage equation gives a 2 x 2 linear system
with the stage's Newton matrix, solved in closed form.

Coefficients: ``w_j(i) = sum_k C[j, k] phi_k(i)`` with ``phi`` the monomials ``1, i, i^2``
(``basis = 0``) or the Bernstein polynomials ``(1-s)^2, 2 s (1-s), s^2`` of
``s = (i - lo) / (hi - lo)`` clipped to ``[0, 1]`` (``basis = 1``: the coefficients are held at
their edge values outside ``[lo, hi]``, where positive Bernstein coefficients no longer imply
positive quadratics).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from mrdamper.models._lag import lag_step
from mrdamper.models.step import STATUS_DIVERGED, STATUS_OK

__all__ = ["GAMMA", "MAX_SUBSTEPS", "P15Form", "p15i_run", "step_advance", "step_force", "substeps"]

GAMMA = 1.0 - 1.0 / math.sqrt(2.0)
#: Upper limit of integration steps per sampling interval.
MAX_SUBSTEPS = 2000


@njit(cache=True)
def _basis(ii: float, basis: int, lo: float, hi: float, out: np.ndarray) -> None:
    if basis == 0:
        out[0] = 1.0
        out[1] = ii
        out[2] = ii * ii
    else:
        s = min(1.0, max(0.0, (ii - lo) / (hi - lo)))
        out[0] = (1.0 - s) * (1.0 - s)
        out[1] = 2.0 * s * (1.0 - s)
        out[2] = s * s


@njit(cache=True)
def _coefs(C: np.ndarray, phi: np.ndarray, w: np.ndarray) -> None:
    for j in range(5):
        w[j] = C[j, 0] * phi[0] + C[j, 1] * phi[1] + C[j, 2] * phi[2]


@njit(cache=True)
def _accel(F: float, G: float, vv: float, w: np.ndarray, f0: float) -> float:
    F2 = F * F
    a: float = (F - f0 - w[0] * vv - w[1] * G - w[3] * F2 * F - w[4] * F2 * F2 * F) / w[2]
    return a


@njit(cache=True)
def _stage(
    A: float, B: float, hg: float, vv: float, w: np.ndarray, f0: float, G0: float
) -> tuple[float, bool]:
    """Root ``G`` of ``G - B - hg * a(A + hg G, G) = 0`` (safeguarded Newton)."""
    G = G0
    lo_b, hi_b = -np.inf, np.inf
    scale = abs(B) + abs(G0) + 1e-300
    for _ in range(200):
        F = A + hg * G
        F2 = F * F
        t3 = w[3] * F2 * F
        t5 = w[4] * F2 * F2 * F
        a = (F - f0 - w[0] * vv - w[1] * G - t3 - t5) / w[2]
        psi = G - B - hg * a
        if not np.isfinite(psi):
            return G, False
        # rounding level of psi: the terms of a's numerator cancel, so |psi| cannot go below it
        noise = (
            1e-14
            * (
                abs(G)
                + abs(B)
                + hg
                * (abs(F) + abs(f0) + abs(w[0] * vv) + abs(w[1] * G) + abs(t3) + abs(t5))
                / abs(w[2])
            )
            + 1e-300
        )
        if abs(psi) <= noise:
            return G, True
        aF = (1.0 - 3.0 * w[3] * F2 - 5.0 * w[4] * F2 * F2) / w[2]
        aG = -w[1] / w[2]
        dpsi = 1.0 - hg * (hg * aF + aG)
        if psi > 0.0:
            hi_b = min(hi_b, G)
        else:
            lo_b = max(lo_b, G)
        step = psi / dpsi if dpsi > 0.0 else np.nan
        Gn = G - step
        if not (np.isfinite(Gn) and Gn > lo_b and Gn < hi_b):
            if np.isfinite(lo_b) and np.isfinite(hi_b):
                Gn = 0.5 * (lo_b + hi_b)
            elif np.isfinite(lo_b):
                Gn = lo_b + 2.0 * (abs(lo_b - G0) + scale)
            else:
                Gn = hi_b - 2.0 * (abs(hi_b - G0) + scale)
        if abs(Gn - G) <= 1e-14 * (abs(Gn) + scale) or hi_b - lo_b <= 1e-13 * (abs(G) + scale):
            return Gn, True
        G = Gn
    return G, False


@njit(cache=True)
def _dacc(
    F: float, G: float, a: float, vv: float, w: np.ndarray, phi: np.ndarray, m: int, out: np.ndarray
) -> None:
    """Partial derivatives of the acceleration with respect to the 15 (+ offset) coefficients."""
    regs0 = -vv / w[2]
    regs1 = -G / w[2]
    regs2 = -a / w[2]
    regs3 = -F * F * F / w[2]
    regs4 = -F * F * F * F * F / w[2]
    for k in range(3):
        out[k] = regs0 * phi[k]
        out[3 + k] = regs1 * phi[k]
        out[6 + k] = regs2 * phi[k]
        out[9 + k] = regs3 * phi[k]
        out[12 + k] = regs4 * phi[k]
    if m > 15:
        out[15] = -1.0 / w[2]


@njit(cache=True)
def _substep(
    yF: float,
    yG: float,
    va: float,
    vb: float,
    ia: float,
    ib: float,
    s: int,
    n_sub: int,
    h: float,
    C: np.ndarray,
    f0: float,
    basis: int,
    lo: float,
    hi: float,
    phi1: np.ndarray,
    phi2: np.ndarray,
    w1: np.ndarray,
    w2: np.ndarray,
) -> tuple[float, float, float, float, float, float, float, bool]:
    """Integration step ``s`` of ``n_sub`` (length ``h``) of a sampling interval from the state
    ``(yF, yG)``; ``v``, ``i`` linear from ``(va, ia)`` to ``(vb, ib)`` over the interval.

    Returns the first stage ``(F1, G1, a1, v1)``, the new state ``(F2, G2)`` with its velocity
    ``v2``, and whether both implicit stages found their root; fills the stages' basis values
    ``phi1``, ``phi2`` and coefficients ``w1``, ``w2``. The one step both the free run
    (:func:`p15i_run`, which adds the sensitivities) and the per-sample step take.
    """
    g = GAMMA
    hg = h * g
    ta = (s + g) / n_sub
    tb = (s + 1.0) / n_sub
    v1 = va + (vb - va) * ta
    v2 = va + (vb - va) * tb
    _basis(ia + (ib - ia) * ta, basis, lo, hi, phi1)
    _basis(ia + (ib - ia) * tb, basis, lo, hi, phi2)
    _coefs(C, phi1, w1)
    _coefs(C, phi2, w2)
    # stage 1
    G1, ok1 = _stage(yF, yG, hg, v1, w1, f0, yG)
    F1 = yF + hg * G1
    a1 = _accel(F1, G1, v1, w1, f0)
    # stage 2
    A2 = yF + h * (1.0 - g) * G1
    B2 = yG + h * (1.0 - g) * a1
    G2, ok2 = _stage(A2, B2, hg, v2, w2, f0, G1)
    F2 = A2 + hg * G2
    return F1, G1, a1, v1, F2, G2, v2, ok1 and ok2


@njit(cache=True)
def p15i_run(
    v: np.ndarray,
    i: np.ndarray,
    dt: float,
    C: np.ndarray,
    f0: float,
    basis: int,
    lo: float,
    hi: float,
    n_sub: int,
    bound: float,
    seg_start: np.ndarray,
    seg_end: np.ndarray,
    F0: np.ndarray,
    G0: np.ndarray,
    S0: np.ndarray,
    with_sens: bool,
    with_offset: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulate segments ``[seg_start[q], seg_end[q])`` of one record, each from its own state.

    Parameters
    ----------
    v, i : ndarray
        Velocity [m/s] and electrical input [A or V] at the samples.
    dt : float
        Sampling interval [s].
    C : ndarray, shape (5, 3)
        Coefficients of ``w_1 .. w_5`` in the chosen basis.
    f0 : float
        Force offset [N].
    basis : int
        0 monomials in ``i``, 1 Bernstein polynomials on ``[lo, hi]`` (input clipped to it).
    n_sub : int
        Integration steps per sampling interval.
    bound : float
        Largest accepted ``|F|`` [N].
    seg_start, seg_end : ndarray of int64
        Segments (sample indices, end exclusive).
    F0, G0 : ndarray
        Force [N] and force rate [N/s] at each segment's first sample.
    S0 : ndarray, shape (n_segments, n_par)
        Sensitivity of each segment's initial force to the coefficients (the initial rate's is 0).
    with_sens, with_offset : bool
        Compute the sensitivities; include ``f0`` as the 16th parameter.

    Returns
    -------
    F : ndarray, shape (n,)
        Force [N] (samples outside every segment are left at 0).
    J : ndarray, shape (n, n_par) or (0, n_par)
        ``dF / dC`` (row-major ``C``, then ``f0``) at the samples.
    bad : ndarray of int64, shape (n_segments,)
        ``-1`` for a segment that ran to its end, else the first sample whose state is non-finite,
        beyond ``bound``, or whose implicit stage had no root.
    """
    n = v.size
    m = 16 if with_offset else 15
    F = np.zeros(n)
    J = np.zeros((n if with_sens else 0, m))
    bad = np.full(seg_start.size, -1, dtype=np.int64)
    g = GAMMA
    h = dt / n_sub
    hg = h * g
    w1 = np.empty(5)
    w2 = np.empty(5)
    d1 = np.empty(m)
    d2 = np.empty(m)
    SF = np.empty(m)
    SG = np.empty(m)
    K1F = np.empty(m)
    K1G = np.empty(m)
    phi1 = np.empty(3)
    phi2 = np.empty(3)
    for q in range(seg_start.size):
        k0, k1 = seg_start[q], seg_end[q]
        yF, yG = F0[q], G0[q]
        F[k0] = yF
        for p in range(m):
            SF[p] = S0[q, p]
            SG[p] = 0.0
            if with_sens:
                J[k0, p] = SF[p]
        if not (np.isfinite(yF) and np.isfinite(yG)) or abs(yF) > bound:
            bad[q] = k0
            continue
        for k in range(k0, k1 - 1):
            va, vb = v[k], v[k + 1]
            ia, ib = i[k], i[k + 1]
            ok = True
            for s in range(n_sub):
                F1, G1, a1, v1, F2, G2, v2, ok = _substep(
                    yF, yG, va, vb, ia, ib, s, n_sub, h, C, f0, basis, lo, hi, phi1, phi2, w1, w2
                )
                if not ok:
                    break
                if with_sens:
                    a2 = _accel(F2, G2, v2, w2, f0)
                    # Jacobians of the acceleration at both stages
                    aF1 = (1.0 - 3.0 * w1[3] * F1 * F1 - 5.0 * w1[4] * F1**4) / w1[2]
                    aG1 = -w1[1] / w1[2]
                    aF2 = (1.0 - 3.0 * w2[3] * F2 * F2 - 5.0 * w2[4] * F2**4) / w2[2]
                    aG2 = -w2[1] / w2[2]
                    det1 = 1.0 - hg * aG1 - hg * hg * aF1
                    det2 = 1.0 - hg * aG2 - hg * hg * aF2
                    _dacc(F1, G1, a1, v1, w1, phi1, m, d1)
                    _dacc(F2, G2, a2, v2, w2, phi2, m, d2)
                    for p in range(m):
                        # stage 1: (I - hg J1) dY1 = S_n + hg (0, d1)
                        r1 = SF[p]
                        r2 = SG[p] + hg * d1[p]
                        x1 = ((1.0 - hg * aG1) * r1 + hg * r2) / det1
                        x2 = (hg * aF1 * r1 + r2) / det1
                        K1F[p] = x2
                        K1G[p] = aF1 * x1 + aG1 * x2 + d1[p]
                        # stage 2: (I - hg J2) dY2 = S_n + h (1-g) K1 + hg (0, d2)
                        r1 = SF[p] + h * (1.0 - g) * K1F[p]
                        r2 = SG[p] + h * (1.0 - g) * K1G[p] + hg * d2[p]
                        SF[p] = ((1.0 - hg * aG2) * r1 + hg * r2) / det2
                        SG[p] = (hg * aF2 * r1 + r2) / det2
                yF, yG = F2, G2
            F[k + 1] = yF
            if with_sens:
                for p in range(m):
                    J[k + 1, p] = SF[p]
            if not ok or not (np.isfinite(yF) and np.isfinite(yG)) or abs(yF) > bound:
                bad[q] = k + 1
                break
    return F, J, bad


# ----------------------------------------------------------------------------- per-sample step
class P15Form(NamedTuple):
    """The P-15 model as its per-sample step reads it.

    Attributes
    ----------
    C : ndarray, shape (5, 3)
        Coefficients of ``w_1 .. w_5`` in the basis ``basis``.
    f0 : float
        Force offset [N].
    basis : int
        0 monomials, 1 Bernstein polynomials on ``[lo, hi]``.
    lo, hi : float
        Range of the Bernstein basis (unused for monomials).
    max_step : float
        Largest integration step [s] (``inf``: one step a sampling interval).
    bound : float
        Largest accepted ``|F|`` [N].
    eta : float
        Drive-lag rate [1/s]; negative: no lag.
    """

    C: np.ndarray
    f0: float
    basis: int
    lo: float
    hi: float
    max_step: float
    bound: float
    eta: float


@njit(cache=True)
def substeps(dt: float, max_step: float) -> int:
    """Integration steps over an interval of ``dt`` [s]: ``ceil(dt / max_step)``, at least 1 and
    at most :data:`MAX_SUBSTEPS` (one step for an infinite ``max_step``)."""
    if not math.isfinite(max_step):
        return 1
    return int(min(MAX_SUBSTEPS, max(1, math.ceil(dt / max_step - 1e-12))))


@njit(cache=True)
def step_force(form: P15Form, s: np.ndarray, x: float, v: float, e: float) -> float:
    """Force [N]: the state's first entry (the force is a state of the P-15 ODE)."""
    F: float = s[0]
    return F


@njit(cache=True)
def step_advance(
    form: P15Form,
    s: np.ndarray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """Integrate ``s = (F, G, rho)`` over one interval of ``dt`` [s] (:func:`_substep`, with
    ``ceil(dt / max_step)`` steps; ``v`` and the model's input linear in between)."""
    if form.eta >= 0.0:
        ia = s[2]
        ib = lag_step(ia, e0, math.exp(-form.eta * dt))
    else:
        ia, ib = e0, e1
    n_sub = substeps(dt, form.max_step)
    h = dt / n_sub
    phi1 = np.empty(3)
    phi2 = np.empty(3)
    w1 = np.empty(5)
    w2 = np.empty(5)
    yF, yG = s[0], s[1]
    ok = True
    for q in range(n_sub):
        _, _, _, _, yF, yG, _, ok = _substep(
            yF,
            yG,
            v0,
            v1,
            ia,
            ib,
            q,
            n_sub,
            h,
            form.C,
            form.f0,
            form.basis,
            form.lo,
            form.hi,
            phi1,
            phi2,
            w1,
            w2,
        )
        if not ok:
            break
    s[0], s[1], s[2] = yF, yG, ib
    if not ok or not (np.isfinite(yF) and np.isfinite(yG)) or abs(yF) > form.bound:
        return STATUS_DIVERGED
    return STATUS_OK
