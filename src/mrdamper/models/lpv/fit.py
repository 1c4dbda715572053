"""Identification steps of the LPV input-output model: joint least squares and output-error
refinement. Works on lists of per-record arrays (records are never concatenated in time: each
keeps its own initial conditions)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import scipy.linalg
from scipy import optimize

from mrdamper._warn import warn_user
from mrdamper.errors import IdentificationError
from mrdamper.models import _scale
from mrdamper.models._arrays import readonly
from mrdamper.models.lpv import kernels as K
from mrdamper.models.lpv.kernels import frozen_poles, largest_frozen_pole, split_theta
from mrdamper.progress import counted, report

__all__ = [
    "STABILITY_GRID",
    "STABILITY_LIMIT",
    "LPVFit",
    "LSResult",
    "Records",
    "free_run_cost",
    "frozen_poles",
    "identify",
    "largest_frozen_pole",
    "ls_identify",
    "refine_output_error",
    "split_theta",
]

#: Condition number of the column-scaled Gram matrix above which the QR fall-back is used.
GRAM_COND_LIMIT = 1e8
#: Condition number of the column-scaled regression matrix above which identification fails.
REGRESSION_COND_LIMIT = 1e12
#: Largest frozen-pole modulus the output-error refinement accepts (strictly inside the unit
#: circle).
STABILITY_LIMIT = 0.999
#: Points of the scheduling grid (identified range, ends included) on which frozen stability is
#: checked.
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
    x : list of ndarray, optional
        Displacement [m] per record (needed by a parallel stiffness; None: zeros).
    """

    F: list[np.ndarray]
    u: list[np.ndarray]
    rho: list[np.ndarray]
    weights: np.ndarray
    x: list[np.ndarray] | None = None

    def displacement(self, r: int) -> np.ndarray:
        """Displacement of record ``r`` [m] (zeros when the records carry none)."""
        return self.x[r] if self.x is not None else np.zeros(self.F[r].size)

    def without_stiffness(self, stiffness: float) -> Records:
        """The records with ``stiffness * x`` taken out of the force (themselves for 0)."""
        if stiffness == 0.0:
            return self
        return dataclasses.replace(
            self,
            F=[readonly(f - stiffness * self.displacement(r)) for r, f in enumerate(self.F)],
        )

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


def _solve(
    y: Any,
    u: Any,
    rho: Any,
    starts: np.ndarray,
    w: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
) -> tuple[np.ndarray, float, str, int]:
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
            "lpv: regression is rank deficient (condition number of the scaled regressors "
            f"{cond_x:.3g} > {REGRESSION_COND_LIMIT:.0e}); lower the order n_m or the degree "
            "n_rho, or give data with more distinct scheduling levels"
        )
    if cond_x > 1e7:
        warn_user(
            f"lpv: ill-conditioned regression (scaled condition number {cond_x:.3g}); the "
            f"coefficients are poorly determined",
            RuntimeWarning,
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


def refine_output_error(
    rec: Records,
    theta0: np.ndarray,
    F0: float,
    *,
    n_m: int,
    n_p: int,
    offset: bool,
    bound: float,
    max_nfev: int,
    solver: str = "gauss-newton",
    rho_grid: np.ndarray | None = None,
    stiffness: float = 0.0,
    fit_stiffness: bool = False,
) -> tuple[np.ndarray, float, float, optimize.OptimizeResult]:
    """Minimise the weighted free-run (simulation) error from a least-squares start.

    The unknowns are ``theta``, the offset ``F0`` (with ``offset``) and the parallel stiffness
    ``k_x`` [N/m] (with ``fit_stiffness``, from ``stiffness``; both enter the output linearly).
    Returns ``(theta, F0, k_x, solution)``.

    ``solver="gauss-newton"`` (default): :func:`_levenberg_marquardt` on the Gauss-Newton normal
    equations ``J^T J``, ``J^T e`` accumulated by
    :func:`~mrdamper.models.lpv.kernels.oe_normal_equations` in one pass per record without
    storing the Jacobian. ``solver="least_squares"``: ``scipy.optimize.least_squares`` (MINPACK
    Levenberg-Marquardt) with the analytic Jacobian of
    :func:`~mrdamper.models.lpv.kernels.simulate_sensitivity` (slower: it stores and factors
    ``J``). A candidate whose free run diverges is rejected (infinite cost / large residuals).

    With ``rho_grid`` the refinement is constrained to frozen stability over that grid: a
    candidate with a frozen pole of modulus ``>= STABILITY_LIMIT`` at any grid point is rejected
    like a diverging one (Levenberg-Marquardt raises its damping and takes a shorter step), so a
    frozen-stable start stays frozen-stable.
    """
    P = 2 * n_m * n_p
    lin = _Linear(P, offset, fit_stiffness, F0, stiffness)
    x0 = lin.pack(theta0)
    if solver == "gauss-newton":
        return _levenberg_marquardt(
            rec, x0, n_m, n_p, lin=lin, bound=bound, max_iter=max_nfev, rho_grid=rho_grid
        )
    sw = np.sqrt(rec.weights)
    last: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}  # residuals and Jacobian at one point

    def evaluate(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = p.tobytes()
        if key in last:
            return last[key]
        alpha, beta = split_theta(p, n_m, n_p)
        f0, k_x = lin.values(p)
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
                if k_x != 0.0:
                    e = e + k_x * rec.displacement(r)
            res.append(sw[r] * e)
            Jr = sw[r] * J
            if offset:
                Jr = np.column_stack((Jr, np.full(e.size, sw[r])))
            if fit_stiffness:
                Jr = np.column_stack((Jr, sw[r] * rec.displacement(r)))
            jacs.append(Jr)
        out = (np.concatenate(res), np.vstack(jacs))
        last.clear()
        last[key] = out
        return out

    # scipy's "lm" may evaluate the start once more than max_nfev
    residuals = counted(
        lambda p: evaluate(p)[0], "output-error refinement: evaluation", max_nfev + 1
    )
    sol = optimize.least_squares(
        residuals,
        x0,
        jac=lambda p: evaluate(p)[1],
        method="lm",
        x_scale="jac",
        max_nfev=max_nfev,
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
    )
    f0, k_x = lin.values(sol.x)
    return sol.x[:P].copy(), f0, k_x, sol


#: Placeholder displacement for the kernel when no stiffness is used (it is then never read).
_NO_X = np.zeros(1)
_NO_X.setflags(write=False)


@dataclass(frozen=True)
class _Linear:
    """Where the output's linear unknowns sit in the refinement's vector
    ``x = [theta, (F0), (k_x)]``, and their fixed values when they are not unknowns."""

    P: int
    offset: bool
    stiffness: bool
    F0: float
    k_x: float

    @property
    def size(self) -> int:
        """Length of the unknown vector."""
        return self.P + int(self.offset) + int(self.stiffness)

    def pack(self, theta: np.ndarray) -> np.ndarray:
        """The unknown vector from ``theta`` and the start values."""
        tail = ([self.F0] if self.offset else []) + ([self.k_x] if self.stiffness else [])
        return np.concatenate([np.asarray(theta, dtype=np.float64), np.asarray(tail, dtype=float)])

    def values(self, x: np.ndarray) -> tuple[float, float]:
        """``(F0, k_x)`` at the unknown vector ``x``."""
        f0 = float(x[self.P]) if self.offset else self.F0
        k_x = float(x[self.size - 1]) if self.stiffness else self.k_x
        return f0, k_x


def _normal_eq(
    rec: Records, x: np.ndarray, n_m: int, n_p: int, lin: _Linear, bound: float
) -> tuple[float, np.ndarray, np.ndarray]:
    alpha, beta = split_theta(x, n_m, n_p)
    f0, k_x = lin.values(x)
    Q = lin.size
    H = np.zeros((Q, Q))
    g = np.zeros(Q)
    cost = 0.0
    use_x = lin.stiffness or k_x != 0.0
    for r in range(len(rec.u)):
        c, gr, Hr, bad = K.oe_normal_equations(
            rec.u[r],
            rec.rho[r],
            alpha,
            beta,
            rec.F[r],
            rec.displacement(r) if use_x else _NO_X,
            f0,
            k_x,
            float(rec.weights[r]),
            bound,
            lin.offset,
            lin.stiffness,
        )
        if bad >= 0:
            return np.inf, g, H
        cost += c
        g += gr
        H += Hr
    return cost, g, H


def free_run_cost(
    rec: Records,
    alpha: np.ndarray,
    beta: np.ndarray,
    f0: float,
    bound: float,
    stiffness: float = 0.0,
) -> float:
    """Weighted free-run squared error ``sum_r w_r |y_r + f0 + k_x x_r - F_r|^2`` over the
    records [N^2] (``k_x = stiffness`` [N/m]; ``inf`` when a record's free run leaves ``bound``
    or becomes non-finite)."""
    total = 0.0
    for r in range(len(rec.u)):
        y, bad = K.simulate_record(rec.u[r], rec.rho[r], alpha, beta, bound)
        if bad >= 0:
            return float("inf")
        xd = rec.displacement(r) if stiffness != 0.0 else _NO_X
        total += rec.weights[r] * K.residual_sse(y, rec.F[r], f0, xd, stiffness)
    return total


def _cost_of(rec: Records, x: np.ndarray, n_m: int, n_p: int, lin: _Linear, bound: float) -> float:
    """:func:`free_run_cost` of the unknown vector ``x`` (:class:`_Linear`)."""
    alpha, beta = split_theta(x, n_m, n_p)
    f0, k_x = lin.values(x)
    return free_run_cost(rec, alpha, beta, f0, bound, k_x)


#: Stage reported by :func:`_levenberg_marquardt` with the accepted iterations so far.
_LM_STAGE = "output-error refinement: iteration"

#: Levenberg-Marquardt constants of :func:`_levenberg_marquardt` (see its docstring).
LM_DAMPING_START = 1e-4
LM_DAMPING_MIN = 1e-12
LM_DAMPING_MAX = 1e12
LM_DAMPING_ACCEPT = 1.0 / 3.0
LM_DAMPING_REJECT = 4.0
LM_DAMPING_SINGULAR = 10.0
LM_DIAG_FLOOR = 1e-300
LM_REL_TOL = 1e-7


def _levenberg_marquardt(
    rec: Records,
    x0: np.ndarray,
    n_m: int,
    n_p: int,
    *,
    lin: _Linear,
    bound: float,
    max_iter: int,
    tol: float = LM_REL_TOL,
    rho_grid: np.ndarray | None = None,
) -> tuple[np.ndarray, float, float, optimize.OptimizeResult]:
    """Levenberg-Marquardt minimisation of the weighted free-run cost of the LPV model.

    What is solved: ``min_x C(x)``, ``C(x) = sum_r w_r |y_r(x) + f0 + k_x x_r - F_r|^2``, the
    weighted squared free-run error over the records (:func:`free_run_cost`), over the unknowns
    ``x = [alpha.ravel(), beta.ravel()]`` (plus ``f0`` and ``k_x`` where ``lin`` makes them
    unknowns). ``y_r(x)`` is the free run of record ``r`` from rest.

    How: at the current ``x`` the kernel accumulates the Gauss-Newton normal equations
    ``H = J^T W J`` and ``g = J^T W e`` (``J`` the sensitivity of the free run, never stored).
    Each iteration solves, by Cholesky, the Jacobi-scaled damped system
    ``(D^-1 H D^-1 + lam I) D dx = -D^-1 g`` with ``D = sqrt(diag H)`` (floored at
    :data:`LM_DIAG_FLOOR` so that a zero column does not divide by zero). The candidate
    ``x + dx`` is accepted only if its free-run cost is lower (a diverging free run, or with
    ``rho_grid`` a frozen pole of modulus ``>= STABILITY_LIMIT`` on the grid, counts as infinite
    cost); the damping ``lam`` then shrinks by :data:`LM_DAMPING_ACCEPT` (not below
    :data:`LM_DAMPING_MIN`), otherwise it grows by :data:`LM_DAMPING_REJECT` and the step is
    retried. A damped matrix that is not positive definite raises ``lam`` by
    :data:`LM_DAMPING_SINGULAR`. ``lam`` starts at :data:`LM_DAMPING_START`, a nearly pure
    Gauss-Newton step, since the start is the least-squares estimate.

    Stops (``status``) after ``max_iter`` accepted steps (0), when an accepted step lowers the
    cost by less than the relative ``tol`` (1), or when no step with ``lam`` below
    :data:`LM_DAMPING_MAX` lowers the cost (2: a local minimum within precision).

    Returns
    -------
    theta : ndarray
        ``[alpha.ravel(), beta.ravel()]`` at the minimum.
    f0 : float
        Offset [N] (``F0`` when not estimated).
    k_x : float
        Parallel stiffness [N/m] (the fixed value when not estimated).
    result : OptimizeResult
        ``x``, ``cost`` (the free-run cost), ``nfev`` (cost evaluations) and ``status``.

    Raises
    ------
    IdentificationError
        If the free run of the start ``x0`` already diverges.
    """
    P = 2 * n_m * n_p
    x = x0.copy()
    cost, g, H = _normal_eq(rec, x, n_m, n_p, lin, bound)
    if not np.isfinite(cost):
        raise IdentificationError(
            "lpv: the free run of the least-squares start diverges; cannot refine"
        )
    lam = LM_DAMPING_START
    nfev, status = 1, 0
    report(_LM_STAGE, 0, max_iter)
    for it in range(max_iter):
        d = np.sqrt(np.maximum(np.diag(H), LM_DIAG_FLOOR))
        Hs = H / np.outer(d, d)
        gs = g / d
        step_ok = False
        while lam < LM_DAMPING_MAX:
            try:
                c, low = scipy.linalg.cho_factor(Hs + lam * np.eye(Hs.shape[0]), check_finite=False)
            except np.linalg.LinAlgError:
                lam *= LM_DAMPING_SINGULAR
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
                cn = _cost_of(rec, xn, n_m, n_p, lin, bound)
            nfev += 1
            if cn < cost:
                rel = (cost - cn) / cost
                x = xn
                cost, g, H = _normal_eq(rec, x, n_m, n_p, lin, bound)
                lam = max(lam * LM_DAMPING_ACCEPT, LM_DAMPING_MIN)
                step_ok = True
                break
            lam *= LM_DAMPING_REJECT
        if not step_ok:
            status = 2  # no decrease possible: at a (local) minimum within precision
            break
        report(_LM_STAGE, it + 1, max_iter)
        if rel < tol:
            status = 1
            break
    sol = optimize.OptimizeResult(x=x, cost=cost, nfev=nfev, status=status)
    f0, k_x = lin.values(x)
    return x[:P].copy(), f0, k_x, sol


# ----------------------------------------------------------------------------- whole identification
@dataclass
class LPVFit:
    """Result of :func:`identify`.

    Attributes
    ----------
    theta : ndarray
        ``[alpha.ravel(), beta.ravel()]`` with ``n_p`` powers of ``rho``.
    offset : float
        Output offset ``F0`` [N].
    stiffness : float
        Parallel stiffness ``k_x`` [N/m].
    largest_pole : (float, float, complex)
        Largest frozen-pole modulus over the stability grid, the ``rho`` where it occurs, the pole.
    provenance : dict
        Solver facts: least-squares solver and condition number, free-run costs, refinement
        evaluations, status and notes.
    """

    theta: np.ndarray
    offset: float
    stiffness: float
    largest_pole: tuple[float, float, complex]
    provenance: dict[str, Any]


def identify(
    rec: Records,
    n_m: int,
    n_p: int,
    *,
    offset: bool,
    bound: float,
    refine: bool,
    max_nfev: int,
    solver: str,
    enforce_stability: bool,
    rho_range: tuple[float, float],
    windows: Callable[[Records], tuple[Records, dict[str, Any] | None]],
    stiffness: float | None = 0.0,
) -> LPVFit:
    """Least squares, then (with ``refine``) output-error refinement from a stable start.

    The refined model is kept when it lowers the free-run cost on every training sample, or when
    the least-squares model is not frozen-stable and ``enforce_stability`` holds. ``windows``
    gives the records the refinement runs on (evenly spread windows of long campaigns, with a
    provenance entry, or the records themselves and None).

    ``stiffness``: the parallel stiffness ``k_x`` [N/m] of ``F = y + F0 + k_x x``, fixed at the
    given value, or None to identify it. Least squares runs on ``F - k_x x`` with the fixed
    value (0 when identified). An identified ``k_x`` takes three stages: the refinement with
    ``k_x = 0``; ``F0`` and ``k_x`` by linear least squares on that filter's free-run residual
    (:func:`residual_stiffness`); the refinement of every unknown jointly from there
    (``provenance["stiffness_stages"]``). Refining jointly from the least-squares start instead
    crept along a narrow valley: on three constant-current rig records it used its whole
    budget and reached a higher cost, with a filter that then failed on a switching current
    (ESR 0.34 against 0.028). Without ``refine`` an identified stiffness stays 0 (noted).

    Progress (:mod:`mrdamper.progress`): ``"least squares"``, the free runs, and the refinement's
    iterations (Gauss-Newton) or residual evaluations (``least_squares``) against their budget.
    """
    report("least squares")
    k_x = 0.0 if stiffness is None else float(stiffness)
    rec_ls = rec.without_stiffness(k_x)  # a fixed stiffness's force taken out once
    ls = ls_identify(rec_ls, n_m, n_p, offset)
    theta, F0 = ls.theta, ls.offset
    prov: dict[str, Any] = {"ls_solver": ls.solver, "ls_condition_number": ls.cond}
    grid = np.linspace(*rho_range, STABILITY_GRID)
    report("free run of the least-squares model")
    ls_cost = free_run_cost(rec, *split_theta(theta, n_m, n_p), F0, bound, k_x)
    prov["ls_free_run_cost"] = ls_cost
    if stiffness is None and not refine:
        prov["stiffness_note"] = "stiffness is identified by the refinement; refine=False keeps 0"
    if refine:
        report("stable start of the refinement")
        theta0, shrink = _stable_start(theta, n_m, n_p, grid, rec_ls, F0, bound)
        if shrink != 1.0:
            prov["oe_start_pole_scaling"] = shrink
        rec_oe, win = windows(rec)
        refine_from = partial(
            refine_output_error,
            rec_oe,
            n_m=n_m,
            n_p=n_p,
            offset=offset,
            bound=bound,
            max_nfev=max_nfev,
            solver=solver,
            rho_grid=grid if enforce_stability else None,
        )
        th_r, f0_r, k_r, sol = refine_from(theta0, F0, stiffness=k_x)
        if stiffness is None:  # then the stiffness, from the filter's residual, and all jointly
            f0_s, k_s = residual_stiffness(rec_oe, th_r, f0_r, n_m, n_p, bound, offset)
            nfev_filter = int(sol.nfev)
            th_r, f0_r, k_r, sol = refine_from(th_r, f0_s, stiffness=k_s, fit_stiffness=True)
            prov["stiffness_stages"] = {
                "filter_nfev": nfev_filter,
                "start": k_s,
                "joint_nfev": int(sol.nfev),
                "identified": k_r,
            }
        report("free run of the refined model on all records")
        oe_cost = free_run_cost(rec, *split_theta(th_r, n_m, n_p), f0_r, bound, k_r)
        prov.update(oe_cost=oe_cost, oe_nfev=int(sol.nfev), oe_status=int(sol.status))
        if win is not None:
            prov.update(oe_windows=win, full_data_check={"ls_cost": ls_cost, "oe_cost": oe_cost})
        ls_ok = (
            not enforce_stability
            or largest_frozen_pole(split_theta(theta, n_m, n_p)[0], grid)[0] < 1.0
        )
        if oe_cost < ls_cost or not ls_ok:
            theta, F0, k_x = th_r, f0_r, k_r
            if oe_cost >= ls_cost:
                prov["oe_note"] = (
                    "least-squares model has a lower free-run cost but is not frozen-stable; "
                    "refined (frozen-stable) model kept"
                )
        else:
            prov["oe_note"] = "refinement did not lower the free-run cost; least-squares model kept"
    pole = largest_frozen_pole(split_theta(theta, n_m, n_p)[0], grid)
    return LPVFit(theta=theta, offset=F0, stiffness=k_x, largest_pole=pole, provenance=prov)


def residual_stiffness(
    rec: Records, theta: np.ndarray, F0: float, n_m: int, n_p: int, bound: float, offset: bool
) -> tuple[float, float]:
    """``(F0, k_x)`` minimising the weighted free-run cost with the filter ``theta`` held: the
    weighted linear least squares of the free-run residual ``F - y`` on ``[1, x]`` (on ``x``
    alone, ``F0`` kept, without ``offset``)."""
    alpha, beta = split_theta(theta, n_m, n_p)
    G = np.zeros((2, 2))
    g = np.zeros(2)
    for r in range(len(rec.u)):
        y, bad = K.simulate_record(rec.u[r], rec.rho[r], alpha, beta, bound)
        if bad >= 0:
            return F0, 0.0
        x = rec.displacement(r)
        res = rec.F[r] - y - (0.0 if offset else F0)
        w = float(rec.weights[r])
        G += w * np.array([[x.size, x.sum()], [x.sum(), x @ x]])
        g += w * np.array([res.sum(), res @ x])
    if offset:
        f0, k = np.linalg.solve(G, g)
        return float(f0), float(k)
    return F0, float(g[1] / G[1, 1]) if G[1, 1] > 0 else 0.0


#: Pole scaling of :func:`_stable_start`: target modulus of the largest frozen pole, and the
#: factor by which the scaling shrinks while the time-varying free run still diverges.
START_POLE_MODULUS = 0.98
START_SHRINK = 0.95
START_TRIES = 20


def _stable_start(
    theta: np.ndarray,
    n_m: int,
    n_p: int,
    grid: np.ndarray,
    rec: Records,
    F0: float,
    bound: float,
) -> tuple[np.ndarray, float]:
    """Start for the refinement whose free run stays bounded on the training records.

    An equation-error estimate can be frozen-unstable. Scaling ``a_j`` by ``lambda**j`` scales
    every frozen pole by ``lambda``, so ``lambda = START_POLE_MODULUS / max|pole|`` (then smaller
    by :data:`START_SHRINK`, if the time-varying run still diverges) gives a frozen-stable start
    with the same pole pattern.
    """
    alpha, beta = split_theta(theta, n_m, n_p)
    pmax = largest_frozen_pole(alpha, grid)[0]
    lam = 1.0 if pmax < STABILITY_LIMIT else START_POLE_MODULUS / pmax
    for _ in range(START_TRIES):
        al = alpha * (lam ** np.arange(1, n_m + 1))[:, None]
        if np.isfinite(free_run_cost(rec, al, beta, F0, bound)):
            return np.r_[al.ravel(), beta.ravel()], lam
        lam *= START_SHRINK
    raise IdentificationError(
        "lpv: no bounded free run found from the least-squares estimate; try a lower order n_m"
    )
