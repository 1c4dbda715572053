"""Equation-error least squares of P-15 on filtered force derivatives (the paper's literal fit).

Private machinery of :class:`~mrdamper.models.phenomenological.P15Estimator`. Per record (records
are never joined: filtering and differentiation stop at record edges):

1. ``F`` and ``v`` pass a zero-phase Butterworth low-pass (order ``filter_order`` run forward and
   backward) with cut-off ``cutoff`` [Hz] (``"auto"``: ``min(fs / 10, 100)`` per record).
2. ``dF/dt`` and ``d2F/dt2`` are central differences of the filtered force; ``3 fs / cutoff``
   samples are trimmed at both record edges.
3. The quadratics ``w_j(i)`` are expanded in the Bernstein basis of ``s = (i - lo) / (hi - lo)``;
   columns are scaled to unit norm; the condition number of the scaled regression is checked.
4. ``form="free"``: plain least squares; ``"stable"``: every Bernstein coefficient of ``w3`` and
   ``w2`` below zero and of ``w5`` at most zero (bounded least squares); ``"monotone"``: also
   ``w4 <= 0``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.optimize import lsq_linear
from scipy.signal import butter, sosfiltfilt

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError

__all__ = ["check_levels", "cutoff_hz", "equation_error", "filtered_state"]

#: Condition number of the scaled regression above which identification fails / warns.
COND_FAIL, COND_WARN = 1e10, 1e6
#: Samples required per coefficient.
SAMPLES_PER_PARAMETER = 10


def cutoff_hz(setting: float | str | None, fs: float) -> float | None:
    """Derivative-filter cut-off [Hz] of a record sampled at ``fs`` [Hz]."""
    if setting is None:
        return None
    return float(min(fs / 10.0, 100.0)) if setting == "auto" else float(setting)


def _filtered(
    e: Experiment, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray, float | None]:
    fc = cutoff_hz(cutoff, e.fs)
    if fc is None:
        return e.F, e.v, None
    if not fc < 0.5 * e.fs:
        raise DataValidationError(
            "cutoff",
            f"{fc:g} Hz is not below the Nyquist frequency {0.5 * e.fs:g} Hz of record {e.name!r}",
        )
    sos = butter(order, fc, btype="low", fs=e.fs, output="sos")
    if e.n <= 3 * (2 * len(sos) + 1):
        return e.F, e.v, fc  # too short to filter; regressors() then returns no samples
    return sosfiltfilt(sos, e.F), sosfiltfilt(sos, e.v), fc


def filtered_state(
    e: Experiment, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray]:
    """Filtered force [N] and its central-difference rate [N/s] over the whole record."""
    Ff, _, _ = _filtered(e, cutoff, order)
    return Ff, np.gradient(Ff, e.dt)


def regressors(
    e: Experiment, source: ElectricalSource, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filtered force (target), input and the five regressor signals of one record, trimmed."""
    i = e.electrical(source)
    Ff, vf, fc = _filtered(e, cutoff, order)
    dF = np.gradient(Ff, e.dt)
    ddF = np.gradient(dF, e.dt)
    trim = 2 if fc is None else math.ceil(3.0 * e.fs / fc)
    if fc is not None and e.n <= 2 * trim + 3 * order:
        return np.empty(0), np.empty(0), np.empty((0, 5))
    sl = slice(trim, e.n - trim)
    F = Ff[sl]
    return F, np.asarray(i[sl]), np.stack([vf[sl], dF[sl], ddF[sl], F**3, F**5], axis=1)


def check_levels(i: np.ndarray, lo: float, hi: float, source: str) -> None:
    """Quadratics in the input need at least three distinct input levels."""
    if hi - lo <= 1e-9 * max(1.0, abs(hi)):
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels, but the training input is constant ({lo:g}); rank 1 of 3"
        )
    s = (i - lo) / (hi - lo)
    V = np.stack([np.ones_like(s), s, s * s], axis=1)
    sv = np.linalg.svd(V / np.linalg.norm(V, axis=0), compute_uv=False)
    rank = int(np.sum(sv > sv[0] * 1e-6))
    if rank < 3:
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels; the training input has numerical rank {rank} of 3"
        )


def _form_bounds(form: str, n_basis: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the scaled Bernstein coefficients (``n_basis`` per quadratic, ``n`` unknowns)
    that impose the sign constraints of ``form``."""
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)

    def row(j: int) -> slice:
        return slice(j * n_basis, (j + 1) * n_basis)

    if form != "free":
        ub[row(1)] = -1e-9  # w2 Bernstein coefficients < 0
        ub[row(2)] = -1e-9  # w3 < 0
        ub[row(4)] = 0.0  # w5 <= 0
    if form == "monotone":
        ub[row(3)] = 0.0  # w4 <= 0: g(F) increasing, no bistable branch
    return lb, ub


def equation_error(
    exps: Sequence[Experiment],
    source: ElectricalSource,
    lo: float,
    hi: float,
    *,
    form: str,
    offset: bool,
    cutoff: float | str | None,
    order: int,
    single: bool = False,
) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Least squares of the P-15 relation on filtered derivatives.

    With ``single`` (training input at one level, ``lo == hi``) each ``w_j`` is a constant: one
    coefficient per quadratic is identified and returned in all three Bernstein columns (the
    Bernstein coefficients of a constant).

    Returns
    -------
    B : ndarray, shape (5, 3)
        Bernstein coefficients of ``w_1 .. w_5`` on ``[lo, hi]``.
    f0 : float
        Force offset [N].
    info : dict
        ``n_samples``, ``condition_number``, ``equation_error_rms`` [N], ``cutoff_hz``.
    """
    parts = [regressors(e, source, cutoff, order) for e in exps]
    y = np.concatenate([p[0] for p in parts])
    n_basis = 1 if single else 3
    n_par = 5 * n_basis + int(offset)
    if y.size < SAMPLES_PER_PARAMETER * n_par:
        raise IdentificationError(
            f"data: p15 has {n_par} parameters and needs at least {SAMPLES_PER_PARAMETER * n_par} "
            f"samples after trimming the filter edges, got {y.size}"
        )
    i_reg = np.concatenate([p[1] for p in parts])
    cols = np.concatenate([p[2] for p in parts], axis=0)  # (n, 5): v, dF, ddF, F^3, F^5
    if single:
        basis = np.ones((y.size, 1))
    else:
        check_levels(i_reg, lo, hi, source)
        s = (i_reg - lo) / (hi - lo)
        basis = np.stack([(1 - s) ** 2, 2 * s * (1 - s), s**2], axis=1)
    X = (cols[:, :, None] * basis[:, None, :]).reshape(y.size, 5 * n_basis)
    if offset:
        X = np.concatenate([X, np.ones((y.size, 1))], axis=1)
    norms = np.sqrt(np.einsum("ij,ij->j", X, X))
    if np.any(norms == 0):
        j = int(np.flatnonzero(norms == 0)[0])
        raise IdentificationError(
            f"data: regressor {j} of p15 is identically zero; nothing to identify"
        )
    ynorm = float(np.linalg.norm(y)) or 1.0
    Xs, ys = X / norms, y / ynorm
    # einsum without BLAS: the same bytes whatever the BLAS thread count
    gram = np.einsum("ij,ik->jk", Xs, Xs)
    ev = np.linalg.eigvalsh(gram)
    cond = float(np.sqrt(ev[-1] / ev[0])) if ev[0] > 0 else math.inf
    if not cond < COND_FAIL:
        raise IdentificationError(
            f"data: p15 regression is ill-conditioned (condition number {cond:.3g} > {COND_FAIL:g}); "
            f"the records do not excite all {5 * n_basis} terms (vary velocity amplitude and "
            f"{source})"
        )
    if cond > COND_WARN:
        warnings.warn(f"p15: regression condition number {cond:.3g}", RuntimeWarning, stacklevel=3)
    lb, ub = _form_bounds(form, n_basis, X.shape[1])
    if form == "free":
        theta = np.linalg.solve(gram, np.einsum("ij,i->j", Xs, ys))
    else:
        theta = lsq_linear(Xs, ys, bounds=(lb, ub), method="bvls").x
    coef = theta * ynorm / norms
    resid = float(np.sqrt(np.mean((X @ coef - y) ** 2)))
    info = {
        "n_samples": int(y.size),
        "condition_number": cond,
        "equation_error_rms": resid,
        "cutoff_hz": {e.name: cutoff_hz(cutoff, e.fs) for e in exps},
    }
    B = coef[: 5 * n_basis].reshape(5, n_basis)
    if single:
        B = np.repeat(B, 3, axis=1)
    return B, float(coef[5 * n_basis]) if offset else 0.0, info
