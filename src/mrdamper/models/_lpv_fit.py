"""Identification steps of the LPV input-output model: joint least squares and output-error
refinement. Works on lists of per-record arrays (records are never concatenated in time: each
keeps its own initial conditions)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from scipy import optimize

from mrdamper.errors import IdentificationError
from mrdamper.models import _lpv_kernels as K
from mrdamper.models import _scale

__all__ = [
    "STABILITY_GRID",
    "STABILITY_LIMIT",
    "LSResult",
    "Records",
    "frozen_poles",
    "largest_frozen_pole",
    "ls_identify",
    "refine_output_error",
    "split_theta",
]

#: Condition number of the column-scaled Gram matrix above which the QR fall-back is used.
GRAM_COND_LIMIT = 1e8
#: Condition number of the column-scaled regression matrix above which identification fails.
REGRESSION_COND_LIMIT = 1e12
#: Largest frozen-pole modulus the output-error refinement accepts (strictly inside the unit circle).
STABILITY_LIMIT = 0.999
#: Points of the scheduling grid (identified range, ends included) on which frozen stability is checked.
STABILITY_GRID = 101


@dataclass
class Records:
    """Per-record training arrays at the model rate.

    Attributes
    ----------
    F, u, rho : list of ndarray
        Measured force [N], LPV input [m/s] (or velocity), scheduling variable, per record.
    weights : ndarray
        Weight of each record's squared errors (``1 / (n var F)`` for ESR weighting).
    """

    F: list[np.ndarray]
    u: list[np.ndarray]
    rho: list[np.ndarray]
    weights: np.ndarray

    def flat(self, y: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Concatenate ``y``, ``u``, ``rho`` and return record boundaries (for the Gram kernel)."""
        starts = np.zeros(len(self.u) + 1, dtype=np.int64)
        starts[1:] = np.cumsum([a.size for a in self.u])
        return (np.concatenate(y), np.concatenate(self.u), np.concatenate(self.rho), starts)


@dataclass
class LSResult:
    """Least-squares solution and diagnostics."""

    theta: np.ndarray
    offset: float
    cond: float
    solver: str
    n_eq: int


def split_theta(theta: np.ndarray, n_m: int, n_p: int) -> tuple[np.ndarray, np.ndarray]:
    """``theta = [alpha.ravel(), beta.ravel()]`` -> ``alpha, beta`` of shape ``(n_m, n_p)``."""
    k = n_m * n_p
    return theta[:k].reshape(n_m, n_p).copy(), theta[k : 2 * k].reshape(n_m, n_p).copy()


def _solve(y, u, rho, starts, w, n_m, n_p, with_const):
    if isinstance(u, _scale.RecordList):  # long campaigns: record by record, never concatenated
        G, g, _, n_eq = _scale.lpv_gram_records(y, u, rho, w, n_m, n_p, with_const, K.gram_pass)
    else:
        G, g, _, n_eq = K.gram_pass(y, u, rho, starts, w, n_m, n_p, with_const)
    P = G.shape[0]
    if n_eq < P:
        raise IdentificationError(
            f"lpv: {n_eq} equations for {P} unknowns; give longer or more records"
        )
    d = np.sqrt(np.diag(G))
    if np.any(d == 0):
        col = int(np.flatnonzero(d == 0)[0])
        raise IdentificationError(
            f"lpv: regression column {col} is identically zero (constant-zero input or scheduling "
            f"variable?); the model cannot be identified"
        )
    Gs = G / np.outer(d, d)
    ev = np.linalg.eigvalsh(Gs)
    cond = float(ev[-1] / ev[0]) if ev[0] > 0 else np.inf
    cond_x = float(np.sqrt(cond))
    if not cond_x < REGRESSION_COND_LIMIT:
        raise IdentificationError(
            f"lpv: regression is rank deficient (condition number of the scaled regressors "
            f"{cond_x:.3g} > {REGRESSION_COND_LIMIT:.0e}); lower the order n_m or the degree n_rho, or "
            f"give data with more distinct scheduling levels"
        )
    if cond_x > 1e7:
        warnings.warn(
            f"lpv: ill-conditioned regression (scaled condition number {cond_x:.3g}); the "
            f"coefficients are poorly determined",
            RuntimeWarning,
            stacklevel=3,
        )
    if cond <= GRAM_COND_LIMIT:
        c, low = scipy.linalg.cho_factor(Gs, check_finite=False)
        z = scipy.linalg.cho_solve((c, low), g / d, check_finite=False)
        solver = "cholesky"
    else:  # normal equations lose too many digits: QR of the scaled regression matrix
        if isinstance(u, _scale.RecordList):
            X, t = _scale.lpv_qr_records(y, u, rho, w, n_m, n_p, with_const, K.build_regressors)
        else:
            X, t = _scale.lpv_qr_factor(
                y, u, rho, starts, w, n_m, n_p, with_const, K.build_regressors
            )
        z = np.linalg.lstsq(X / d, t, rcond=None)[0]
        solver = "qr"
    return z / d, cond_x, solver, int(n_eq)


def ls_identify(rec: Records, n_m: int, n_p: int, offset: bool) -> LSResult:
    """Joint equation-error least squares over all records (eqs. 7-9, ``b0 = 0``).

    With ``offset`` the output offset ``F0`` (``F = y + F0``) is estimated first from a pass with
    affine terms ``delta_p rho^p`` (``delta = F0 (e_0 + sum_j alpha_j)`` in least squares), then the
    coefficients are re-estimated on ``F - F0``.
    """
    y: Any
    u: Any
    rho: Any
    if sum(a.size for a in rec.u) > _scale.WINDOW_THRESHOLD:  # long campaigns: no concatenation
        y, u, rho, starts = (
            _scale.RecordList(rec.F),
            _scale.RecordList(rec.u),
            _scale.RecordList(rec.rho),
            np.zeros(1, dtype=np.int64),
        )
    else:
        y, u, rho, starts = rec.flat(rec.F)
    F0 = 0.0
    if offset:
        th, *_ = _solve(y, u, rho, starts, rec.weights, n_m, n_p, True)
        alpha, _ = split_theta(th, n_m, n_p)
        delta = th[2 * n_m * n_p :]
        s = alpha.sum(axis=0)
        s[0] += 1.0
        den = float(s @ s)
        F0 = float(delta @ s / den) if den > 0 else 0.0
        y = _scale.RecordList(a - F0 for a in y) if isinstance(y, _scale.RecordList) else y - F0
    th, cond, solver, n_eq = _solve(y, u, rho, starts, rec.weights, n_m, n_p, False)
    return LSResult(theta=th, offset=F0, cond=cond, solver=solver, n_eq=n_eq)


def frozen_poles(alpha: np.ndarray, rho_grid: np.ndarray) -> np.ndarray:
    """Poles of ``z^n + a_1(rho) z^(n-1) + ... + a_n(rho)`` for each ``rho``; shape (len, n_m)."""
    n_m, n_p = alpha.shape
    out = np.empty((rho_grid.size, n_m), dtype=complex)
    for k, r in enumerate(rho_grid):
        a = alpha @ (r ** np.arange(n_p))
        out[k] = np.roots(np.r_[1.0, a]) if n_m else np.empty(0)
    return out


def largest_frozen_pole(alpha: np.ndarray, rho_grid: np.ndarray) -> tuple[float, float, complex]:
    """Largest frozen-pole modulus over ``rho_grid``, the ``rho`` where it occurs and the pole.

    The poles are the eigenvalues of the companion matrices of ``z^n + a_1(rho) z^(n-1) + ...``,
    computed for the whole grid at once.
    """
    n_m, n_p = alpha.shape
    a = (np.asarray(rho_grid, float)[:, None] ** np.arange(n_p)) @ alpha.T  # (G, n_m)
    C = np.zeros((a.shape[0], n_m, n_m))
    C[:, 0, :] = -a
    if n_m > 1:
        C[:, np.arange(1, n_m), np.arange(n_m - 1)] = 1.0
    ev = np.linalg.eigvals(C)
    if not np.all(np.isfinite(ev)):
        return float("inf"), float(rho_grid[0]), complex("nan")
    mod = np.abs(ev)
    g, j = np.unravel_index(int(np.argmax(mod)), mod.shape)
    return float(mod[g, j]), float(rho_grid[g]), complex(ev[g, j])


def refine_output_error(
    rec: Records,
    theta0: np.ndarray,
    F0: float,
    n_m: int,
    n_p: int,
    *,
    offset: bool,
    bound: float,
    max_nfev: int,
    solver: str = "gauss-newton",
    rho_grid: np.ndarray | None = None,
) -> tuple[np.ndarray, float, optimize.OptimizeResult]:
    """Minimise the weighted free-run (simulation) error from a least-squares start.

    ``solver="gauss-newton"`` (default): Levenberg-Marquardt on the Gauss-Newton normal equations
    ``J^T J``, ``J^T e`` accumulated by :func:`~mrdamper.models._lpv_kernels.oe_normal_equations`
    in one pass per record without storing the Jacobian. ``solver="least_squares"``:
    ``scipy.optimize.least_squares`` (MINPACK Levenberg-Marquardt) with the analytic Jacobian of
    :func:`~mrdamper.models._lpv_kernels.simulate_sensitivity` (slower: it stores and factors
    ``J``). A candidate whose free run diverges is rejected (infinite cost / large residuals).

    With ``rho_grid`` the refinement is constrained to frozen stability over that grid: a
    candidate with a frozen pole of modulus ``>= STABILITY_LIMIT`` at any grid point is rejected
    like a diverging one (Levenberg-Marquardt raises its damping and takes a shorter step), so a
    frozen-stable start stays frozen-stable.
    """
    P = 2 * n_m * n_p
    sw = np.sqrt(rec.weights)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = p.tobytes()
        if key in cache:
            return cache[key]
        alpha, beta = split_theta(p, n_m, n_p)
        f0 = float(p[P]) if offset else F0
        res, jacs = [], []
        unstable = (
            rho_grid is not None and largest_frozen_pole(alpha, rho_grid)[0] >= STABILITY_LIMIT
        )
        for r in range(len(rec.u)):
            yh, J, bad = K.simulate_sensitivity(rec.u[r], rec.rho[r], alpha, beta, bound)
            if bad >= 0 or unstable:
                e = np.full(rec.F[r].size, 10.0 * bound)
                J = np.zeros_like(J)
            else:
                e = yh + f0 - rec.F[r]
            res.append(sw[r] * e)
            Jr = sw[r] * J
            if offset:
                Jr = np.column_stack((Jr, np.full(e.size, sw[r])))
            jacs.append(Jr)
        out = (np.concatenate(res), np.vstack(jacs))
        cache.clear()
        cache[key] = out
        return out

    x0 = np.r_[theta0, F0] if offset else theta0.copy()
    if solver == "gauss-newton":
        return _levenberg_marquardt(
            rec,
            x0,
            n_m,
            n_p,
            offset=offset,
            F0=F0,
            bound=bound,
            max_iter=max_nfev,
            rho_grid=rho_grid,
        )
    sol = optimize.least_squares(
        lambda p: evaluate(p)[0],
        x0,
        jac=lambda p: evaluate(p)[1],
        method="lm",
        x_scale="jac",
        max_nfev=max_nfev,
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
    )
    theta = sol.x[:P].copy()
    f0 = float(sol.x[P]) if offset else F0
    return theta, f0, sol


def _normal_eq(
    rec: Records, x: np.ndarray, n_m: int, n_p: int, offset: bool, F0: float, bound: float
):
    P = 2 * n_m * n_p
    alpha, beta = split_theta(x, n_m, n_p)
    f0 = float(x[P]) if offset else F0
    Q = P + 1 if offset else P
    H = np.zeros((Q, Q))
    g = np.zeros(Q)
    cost = 0.0
    for r in range(len(rec.u)):
        c, gr, Hr, bad = K.oe_normal_equations(
            rec.u[r], rec.rho[r], alpha, beta, rec.F[r], f0, float(rec.weights[r]), bound, offset
        )
        if bad >= 0:
            return np.inf, g, H
        cost += c
        g += gr
        H += Hr
    return cost, g, H


def _free_run_cost(
    rec: Records, x: np.ndarray, n_m: int, n_p: int, offset: bool, F0: float, bound: float
) -> float:
    P = 2 * n_m * n_p
    alpha, beta = split_theta(x, n_m, n_p)
    f0 = float(x[P]) if offset else F0
    total = 0.0
    for r in range(len(rec.u)):
        y, bad = K.simulate_record(rec.u[r], rec.rho[r], alpha, beta, bound)
        if bad >= 0:
            return np.inf
        e = y + f0 - rec.F[r]
        total += rec.weights[r] * float(e @ e)
    return total


def _levenberg_marquardt(
    rec, x0, n_m, n_p, *, offset, F0, bound, max_iter, tol=1e-7, rho_grid=None
):
    P = 2 * n_m * n_p
    x = x0.copy()
    cost, g, H = _normal_eq(rec, x, n_m, n_p, offset, F0, bound)
    if not np.isfinite(cost):
        raise IdentificationError(
            "lpv: the free run of the least-squares start diverges; cannot refine"
        )
    lam = 1e-4
    nfev, status = 1, 0
    for _ in range(max_iter):
        d = np.sqrt(np.maximum(np.diag(H), 1e-300))
        Hs = H / np.outer(d, d)
        gs = g / d
        step_ok = False
        while lam < 1e12:
            try:
                c, low = scipy.linalg.cho_factor(Hs + lam * np.eye(Hs.shape[0]), check_finite=False)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            dx = -scipy.linalg.cho_solve((c, low), gs, check_finite=False) / d
            xn = x + dx
            if (
                rho_grid is not None
                and largest_frozen_pole(split_theta(xn, n_m, n_p)[0], rho_grid)[0]
                >= STABILITY_LIMIT
            ):
                cn = np.inf  # leaves the frozen-stable set over the identified range: rejected
            else:
                cn = _free_run_cost(rec, xn, n_m, n_p, offset, F0, bound)
            nfev += 1
            if cn < cost:
                rel = (cost - cn) / cost
                x = xn
                cost, g, H = _normal_eq(rec, x, n_m, n_p, offset, F0, bound)
                lam = max(lam / 3.0, 1e-12)
                step_ok = True
                break
            lam *= 4.0
        if not step_ok:
            status = 2  # no decrease possible: at a (local) minimum within precision
            break
        if rel < tol:
            status = 1
            break
    sol = optimize.OptimizeResult(x=x, cost=cost, nfev=nfev, status=status)
    return x[:P].copy(), (float(x[P]) if offset else F0), sol
