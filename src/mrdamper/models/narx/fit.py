"""Identification steps of the polynomial NARX model on plain arrays: OLS-ERR term selection,
least squares of the chosen terms and output-error refinement (see :mod:`mrdamper.models.narx`).

Records are the scaled signal rows ``(F, x, v, e, tanh_v)`` of each training record at the model
rate (shape (5, N)); ``p`` initial samples of each record are conditions, not equations.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
from scipy import optimize

from mrdamper.errors import IdentificationError
from mrdamper.models import _scale
from mrdamper.models.narx import kernels as K
from mrdamper.progress import counted, report

__all__ = [
    "free_run_cost",
    "gram_select",
    "least_squares_terms",
    "refine",
    "select_terms",
]

#: Rows per block when the candidate Gram matrix is accumulated.
_BLOCK = 2048


def select_terms(
    records: Sequence[np.ndarray],
    weights: Sequence[float],
    base: np.ndarray,
    cand: np.ndarray,
    p: int,
    n_terms: int,
    err_tol: float,
    colin_tol: float,
) -> tuple[np.ndarray, np.ndarray]:
    """OLS-ERR selection on the weighted, column-normalised augmented Gram matrix.

    Returns the indices of the chosen candidates (in order of choice) and their error
    reduction ratios [-].
    """
    M = cand.shape[0]
    A = np.zeros((M + 1, M + 1))
    blk = np.empty((_BLOCK, M + 1))
    for r, (S, w) in enumerate(zip(records, weights, strict=True)):
        report("term selection: record", r, len(records))
        sw = math.sqrt(w)
        for k0 in range(p, S.shape[1], _BLOCK):
            k1 = min(k0 + _BLOCK, S.shape[1])
            B = blk[: k1 - k0]
            K.fill_candidates(S, base, cand, k0, k1, B[:, :M])
            B[:, M] = S[0, k0:k1]
            B *= sw
            A += B.T @ B
    report("term selection: record", len(records), len(records))
    d = np.sqrt(np.diag(A)).copy()
    usable = d[:M] > 0
    d[d == 0] = 1.0
    A /= d[:, None] * d[None, :]
    A[~np.append(usable, True), :] = 0.0  # constant-zero candidates: never selectable
    order, err = gram_select(A, min(int(n_terms), M), float(err_tol), float(colin_tol))
    if order.size == 0:
        raise IdentificationError(
            "narx: no candidate term explains the force (all collinear or zero)"
        )
    return np.asarray(order), np.asarray(err)


def gram_select(
    A: np.ndarray, n_max: int, err_tol: float, colin_tol: float
) -> tuple[np.ndarray, np.ndarray]:
    """Forward orthogonal least squares (OLS-ERR) term selection on an augmented Gram matrix.

    Each step picks the candidate with the largest error reduction ratio and eliminates it from
    the candidates left (one Gauss-Jordan step on the free rows and columns of ``A``).

    Parameters
    ----------
    A : ndarray, shape (M + 1, M + 1)
        ``[[Phi^T Phi, Phi^T y], [y^T Phi, y^T y]]`` with unit diagonal on the candidate block
        (columns normalised); overwritten.
    n_max : int
        Largest number of terms to select.
    err_tol : float
        Stop when the unexplained fraction ``||r||^2 / ||y||^2`` falls below it.
    colin_tol : float
        A candidate is skipped when its part orthogonal to the selected terms has squared norm
        below ``colin_tol`` (relative to its own norm: near-collinear).

    Returns
    -------
    order : ndarray of int64
        Selected candidate indices in selection order.
    err : ndarray of float64
        Error reduction ratio of each selected term (fraction of ``||y||^2`` it explains) [-].
    """
    M = A.shape[0] - 1
    yy0 = A[M, M]
    free = np.ones(M + 1, dtype=bool)  # rows and columns not selected (the output's always)
    order: list[int] = []
    err: list[float] = []
    while len(order) < n_max and not A[M, M] <= err_tol * yy0:
        diag = np.diag(A)[:M]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = A[:M, M] * A[:M, M] / (diag * yy0)
        ratio[~(free[:M] & (diag > colin_tol)) | np.isnan(ratio)] = -np.inf
        best = int(np.argmax(ratio)) if M else 0
        if not (M and ratio[best] > 0.0):
            break
        free[best] = False
        order.append(best)
        err.append(float(ratio[best]))
        col = A[:, best].copy()
        idx = np.flatnonzero(free)
        A[np.ix_(idx, idx)] -= np.outer(col[idx] / A[best, best], col[idx])
    return np.array(order, dtype=np.int64), np.array(err, dtype=np.float64)


def least_squares_terms(
    records: Sequence[np.ndarray],
    weights: Sequence[float],
    base: np.ndarray,
    terms: np.ndarray,
    p: int,
    cond_max: float,
) -> tuple[np.ndarray, float]:
    """Weighted least-squares coefficients of the chosen ``terms`` and the condition number of
    their column-normalised regression (refused above ``cond_max``)."""
    # [X y] is reduced block by block to its triangular QR factor R (same least-squares
    # solution and singular values as X itself, never held in memory)
    X, y = _scale.chunked_qr(records, weights, base, terms, p, K.fill_candidates)
    norms = np.linalg.norm(X, axis=0)
    Xn = X / norms
    coef, _, rank, sv = np.linalg.lstsq(Xn, y, rcond=None)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    if rank < X.shape[1] or cond > cond_max:
        raise IdentificationError(
            f"narx: regression of the {X.shape[1]} selected terms is ill-conditioned "
            f"(condition number {cond:.3g}, expected <= cond_max={cond_max:g}); "
            "raise colin_tol or lower n_terms"
        )
    return coef / norms, cond


def refine(
    base: np.ndarray,
    terms: np.ndarray,
    theta0: np.ndarray,
    bound: float,
    records: Sequence[np.ndarray],
    weights: Sequence[float],
    p: int,
    max_nfev: int,
) -> tuple[np.ndarray, float, int]:
    """Output-error refinement of the coefficients ``theta0`` (trust-region least squares with
    the kernel's exact sensitivities); returns the coefficients, their free-run cost and the
    number of evaluations. ``bound`` is the divergence bound in scaled force units."""
    meas = [S[0].copy() for S in records]

    def residual_and_jac(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        res, jac = [], []
        for S, f, w in zip(records, meas, weights, strict=True):
            Sw = S.copy()
            J, bad = K.free_run_sensitivity(Sw, base, terms, theta, p, bound)
            if bad >= 0:
                Sw[0, bad:] = np.sign(Sw[0, bad - 1] if bad > 0 else 1.0) * bound
            sw = math.sqrt(w)
            res.append(sw * (Sw[0, p:] - f[p:]))
            jac.append(sw * J[p:])
        return np.concatenate(res), np.vstack(jac)

    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = theta.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = residual_and_jac(theta)
        return cache[key]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sol = optimize.least_squares(
            counted(lambda th: evaluate(th)[0], "output-error refinement: evaluation", max_nfev),
            np.array(theta0, dtype=np.float64),
            jac=lambda th: evaluate(th)[1],
            method="trf",
            x_scale="jac",
            max_nfev=int(max_nfev),
        )
    theta = np.asarray(sol.x, dtype=np.float64)
    return theta, free_run_cost(base, terms, theta, bound, records, weights, p), int(sol.nfev)


def free_run_cost(
    base: np.ndarray,
    terms: np.ndarray,
    theta: np.ndarray,
    bound: float,
    records: Sequence[np.ndarray],
    weights: Sequence[float],
    p: int,
) -> float:
    """Weighted free-run squared error (sum over records of ESR-like terms); inf if diverged."""
    cost = 0.0
    for S, w in zip(records, weights, strict=True):
        Sw = S.copy()
        if K.free_run(Sw, base, terms, theta, p, bound) >= 0:
            return math.inf
        cost += w * float(np.sum((Sw[0, p:] - S[0, p:]) ** 2))
    return cost
