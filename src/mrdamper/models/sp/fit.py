"""Identification of the SP-1 ... SP-4 maps: multi-start nonlinear least squares on plain arrays.

Private machinery of the estimators of :mod:`mrdamper.models.sp.model` (see its
docstring for the method: scaling, linear starts, multi-start, bounds, identifiability).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from mrdamper._warn import warn_user
from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import IdentificationError
from mrdamper.models._lag import first_order_lag
from mrdamper.models.sp.kernels import COMPONENTS, N_COMPONENTS, sp_force, sp_force_jacobian
from mrdamper.progress import counted

__all__ = ["component_values", "identify", "single_level_terms", "stack", "velocity_slope_floor"]

#: Upper bound of the normalised tanh velocity coefficient (see module docstring).
_TANH_SLOPE_MAX = 1e3
#: Largest accepted condition number of an input-power matrix (identifiability check).
_MAX_INPUT_COND = 1e6
#: Samples required per coefficient.
_SAMPLES_PER_PARAMETER = 10
#: Components kept non-negative by the monotone fit: A (tanh amplitude), a (tanh velocity
#: coefficient), c (viscous slope); with them ``dF/dv = A a sech^2(.) + c >= 0`` everywhere.
_MONOTONE_COMPONENTS = (0, 1, 3)
#: Input grid points of :func:`velocity_slope_floor`.
_SLOPE_GRID = 257


def identify(
    kind: str,
    source: ElectricalSource,
    comp: np.ndarray,
    power: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    F: np.ndarray,
    *,
    offset: bool,
    seed: int,
    n_starts: int,
    n_candidates: int,
    max_nfev: int,
    screen_samples: int,
    fit_samples: int | None,
    monotone: tuple[float, float] | None = None,
) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Fit the coefficients ``(comp, power)`` of an SP map to ``F`` [N] on the stacked samples.

    Parameters
    ----------
    kind : str
        Model kind (for messages).
    source : {"i", "voltage"}
        Name of the electrical input (for messages).
    comp, power : ndarray of int
        Component (0..4 for A, a, b, c, d) and input exponent of each coefficient to fit.
    x, v, i, F : ndarray
        Displacement [m], velocity [m/s], electrical input [A or V], force [N] of every sample.
    offset, seed, n_starts, n_candidates, max_nfev, screen_samples, fit_samples
        The estimator's settings.
    monotone : (float, float), optional
        Input range ``(low, high)`` [A or V] over which the force must not fall with velocity:
        the components A, a and c are then written in the Bernstein basis of that range with
        non-negative coefficients (:func:`_monotone_basis`), so ``dF/dv >= 0`` at every
        displacement, velocity and input of the range. None: the free fit.

    Returns
    -------
    S : ndarray
        SI coefficients in the order of ``comp``.
    f0 : float
        Force offset [N].
    provenance : dict
        Samples used, scales, start costs and solver status.
    """
    n_par = comp.size + int(offset)
    if F.size < _SAMPLES_PER_PARAMETER * n_par:
        raise IdentificationError(
            f"data: {kind} has {n_par} parameters and needs at least "
            f"{_SAMPLES_PER_PARAMETER * n_par} samples, got {F.size}"
        )
    Fs = float(np.std(F))
    if not Fs > 0:
        raise IdentificationError("F: training force has zero variance; nothing to identify")
    xs, vs = _rms(x), _rms(v)
    i_s = float(np.max(np.abs(i))) or 1.0
    xn, vn, inn, Fn = x / xs, v / vs, i / i_s, F / Fs
    sub = _even_subset(F.size, screen_samples)
    _check_identifiable(kind, comp, power, inn[sub], source)

    # the free fit's coordinates are the coefficients themselves (T None)
    T: np.ndarray | None = None
    T_inv: np.ndarray | None = None
    if monotone is None:
        lb, ub = _bounds(comp, power, offset)
    else:
        T, lb, ub = _monotone_basis(comp, power, offset, monotone[0] / i_s, monotone[1] / i_s)
        T_inv = np.linalg.inv(T)

    def coefficients(th: np.ndarray) -> np.ndarray:
        """Power-basis coefficients (and offset) of the fit's coordinates ``th``."""
        return th if T is None else T @ th

    rng = np.random.default_rng(seed)
    starts = _linear_starts(
        comp, power, xn[sub], vn[sub], inn[sub], Fn[sub], offset, n_candidates, n_starts, rng
    )

    def solve(theta0: np.ndarray, idx: np.ndarray | slice, nfev: int, stage: str) -> Any:
        """Least squares in the fit's coordinates ``th`` (the power-basis coefficients are
        ``T @ th``)."""
        xa, va, ia, Fa = (np.ascontiguousarray(a[idx]) for a in (xn, vn, inn, Fn))

        def fun(th: np.ndarray) -> np.ndarray:
            tp = coefficients(th)
            f0 = tp[-1] if offset else 0.0
            return sp_force(xa, va, ia, comp, power, tp[: comp.size], f0) - Fa

        def jac(th: np.ndarray) -> np.ndarray:
            tp = coefficients(th)
            f0 = tp[-1] if offset else 0.0
            J = sp_force_jacobian(xa, va, ia, comp, power, tp[: comp.size], f0, offset)[1]
            return J if T is None else J @ T

        return least_squares(
            counted(fun, stage, nfev),
            theta0,
            jac=jac,
            bounds=(lb, ub),
            method="trf",
            x_scale="jac",
            max_nfev=nfev,
        )

    results = []
    for k, theta0 in enumerate(starts):
        stage = f"start {k + 1} of {len(starts)}: least squares: evaluation"
        try:
            res = solve(
                np.clip(theta0 if T_inv is None else T_inv @ theta0, lb, ub),
                sub,
                max_nfev,
                stage,
            )
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            continue
        if np.isfinite(res.cost) and np.all(np.isfinite(res.x)):
            results.append(res)
    if not results:
        raise IdentificationError(f"{kind}: no start converged to a finite cost")
    best = min(results, key=lambda r: r.cost)
    full = _even_subset(F.size, fit_samples)
    final = solve(best.x, full, max_nfev, "best start on the fit samples: evaluation")
    if not (np.isfinite(final.cost) and np.all(np.isfinite(final.x))):
        final = best
    if final.status == 0:
        warn_user(
            f"{kind}: least squares stopped at max_nfev={max_nfev} before converging",
            RuntimeWarning,
        )
    S_kept, f0 = _to_physical(
        coefficients(final.x), comp, power, offset, xs=xs, vs=vs, i_s=i_s, Fs=Fs
    )
    rms = float(np.sqrt(2.0 * final.cost / final.fun.size) * Fs)
    provenance = {
        "n_samples_stacked": int(F.size),
        "n_screen_samples": int(sub.size),
        "n_fit_samples": int(full.size),
        "scales": {"x": xs, "v": vs, "input": i_s, "F": Fs},
        "start_costs": sorted(float(r.cost) for r in results),
        "nfev": int(final.nfev),
        "status": int(final.status),
        "message": str(final.message),
        "training_rms_error": rms,
        "training_esr": float(rms**2 / Fs**2),
    }
    return S_kept, f0, provenance


def stack(
    exps: Iterable[Experiment],
    source: ElectricalSource,
    eta: float | None = None,
    max_samples: int | None = None,
) -> tuple[np.ndarray, ...]:
    """Concatenate the samples of all records (valid for a static map: no state crosses records);
    with ``eta`` the electrical input of each record goes through the drive lag first.

    With more than ``max_samples`` samples in all, only an evenly spaced subset of that many is
    gathered (record by record: the whole concatenation is never built).
    """
    cols: dict[str, list[np.ndarray]] = {"x": [], "v": [], "i": [], "F": []}
    exps = list(exps)
    total = sum(e.n for e in exps)
    keep = (
        _even_subset(total, max_samples)
        if max_samples is not None and total > max_samples
        else None
    )
    offset = 0
    for e in exps:
        sel: slice | np.ndarray = slice(None)
        if keep is not None:
            lo, hi = np.searchsorted(keep, [offset, offset + e.n])
            sel = keep[lo:hi] - offset
        offset += e.n
        el = np.ascontiguousarray(e.electrical(source), dtype=np.float64)
        cols["i"].append((el if eta is None else first_order_lag(el, e.dt, eta))[sel])
        cols["x"].append(e.x[sel])
        cols["v"].append(e.v[sel])
        cols["F"].append(e.F[sel])
    return tuple(np.ascontiguousarray(np.concatenate(cols[k])) for k in ("x", "v", "i", "F"))


def _even_subset(n: int, size: int | None) -> np.ndarray:
    """Indices of ``size`` samples evenly spaced over ``0 .. n-1``.

    All samples if ``size`` is None.
    """
    if size is None or size >= n:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, size).astype(np.int64))


def _rms(a: np.ndarray) -> float:
    r = float(np.sqrt(np.mean(a * a)))
    return r if r > 0 else 1.0


def _check_identifiable(
    kind: str, comp: np.ndarray, power: np.ndarray, inn: np.ndarray, source: str
) -> None:
    """Each component's input polynomial must have full column rank over the training input."""
    levels = np.unique(np.round(inn, 9))
    for m in range(N_COMPONENTS):
        pw = power[comp == m]
        if pw.size == 0:
            continue
        V = np.stack([inn**p for p in pw], axis=1)
        norms = np.linalg.norm(V, axis=0)
        if np.any(norms == 0):
            raise IdentificationError(
                f"{source}: {kind} component {COMPONENTS[m]} has a term in "
                f"{source}^{int(pw[norms == 0][0])} but the training input is zero everywhere; "
                "records with a non-zero input are needed"
            )
        sv = np.linalg.svd(V / norms, compute_uv=False)
        if sv[-1] <= sv[0] / _MAX_INPUT_COND:
            rank = int(np.sum(sv > sv[0] / _MAX_INPUT_COND))
            raise IdentificationError(
                f"{source}: {kind} component {COMPONENTS[m]} is a polynomial with {pw.size} "
                f"coefficients in {source} but the training input takes {min(levels.size, 99)} "
                f"distinct value(s) (numerical rank {rank} of {pw.size}); it is not identifiable: "
                f"train on records with at least {pw.size} distinct {source} levels"
            )


def single_level_terms(comp: np.ndarray, power: np.ndarray) -> np.ndarray:
    """Mask keeping, per component, only its lowest power of the input (the constant law)."""
    keep = np.zeros(comp.size, bool)
    for m in np.unique(comp):
        idx = np.flatnonzero(comp == m)
        keep[idx[np.argmin(power[idx])]] = True
    return keep


def _bounds(comp: np.ndarray, power: np.ndarray, offset: bool) -> tuple[np.ndarray, np.ndarray]:
    n = comp.size + int(offset)
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    k = np.flatnonzero((comp == 1) & (power == 0))
    lb[k], ub[k] = 0.0, _TANH_SLOPE_MAX
    return lb, ub


def _monotone_basis(
    comp: np.ndarray, power: np.ndarray, offset: bool, low: float, high: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coordinates of the monotone fit: ``theta = T @ th`` with bounds on ``th``.

    A component of :data:`_MONOTONE_COMPONENTS` whose powers are ``0 .. k`` is written in the
    degree-``k`` Bernstein basis of ``[low, high]`` (normalised input); its Bernstein
    coefficients are bounded below by 0 (for ``a`` also above by the tanh slope bound), which
    keeps the polynomial non-negative over the range. A component with a single power ``p >= 1``
    is non-negative on ``[low, high]`` when its coefficient is, provided ``low >= 0``. Every other
    coefficient is free (bounds of :func:`_bounds`).
    """
    n = comp.size + int(offset)
    T = np.eye(n)
    lb, ub = _bounds(comp, power, offset)
    width = high - low
    for m in _MONOTONE_COMPONENTS:
        idx = np.flatnonzero(comp == m)
        if idx.size == 0:
            continue
        pw = power[idx]
        top = np.inf if m != 1 else _TANH_SLOPE_MAX
        if set(pw.tolist()) == set(range(pw.size)) and width > 0:
            k = pw.size - 1
            # power coefficients = V_power^-1 V_bernstein (Bernstein coefficients), on k+1 nodes
            nodes = low + width * (np.arange(k + 1) + 0.5) / (k + 1)
            s_nodes = (nodes - low) / width
            V_power = nodes[:, None] ** pw[None, :].astype(float)
            V_bern = np.stack(
                [math.comb(k, j) * s_nodes**j * (1 - s_nodes) ** (k - j) for j in range(k + 1)],
                axis=1,
            )
            T[np.ix_(idx, idx)] = np.linalg.solve(V_power, V_bern)
            lb[idx], ub[idx] = 0.0, top
        elif pw.size == 1 and (pw[0] == 0 or low >= 0):
            lb[idx], ub[idx] = 0.0, top
    return T, lb, ub


def component_values(
    S: Iterable[float], comp: Iterable[int], power: Iterable[int], i: np.ndarray | float
) -> np.ndarray:
    """The five components ``A, a, b, c, d`` of an SP map at input ``i`` [A or V].

    Returns
    -------
    ndarray
        Shape ``(5,) + shape(i)``, in the order of
        :data:`~mrdamper.models.sp.kernels.COMPONENTS` (units in
        :meth:`~mrdamper.models.sp.model.SPModel.components`).
    """
    ii = np.asarray(i, dtype=float)
    out = np.zeros((N_COMPONENTS, *ii.shape))
    for s, m, p in zip(S, comp, power):
        out[int(m)] = out[int(m)] + s * ii ** int(p)
    return out


def velocity_slope_floor(
    S: np.ndarray, comp: np.ndarray, power: np.ndarray, low: float, high: float
) -> tuple[float, float]:
    """Smallest slope ``dF/dv`` [N s/m] of an SP map over the inputs ``[low, high]``.

    ``dF/dv = A(i) a(i) sech^2(a v + b x) + c(i)`` takes every value between ``c(i)`` and
    ``A(i) a(i) + c(i)``, so its floor is the smaller of the two, minimised over an even grid of
    :data:`_SLOPE_GRID` inputs (the ends included).

    Returns
    -------
    slope : float
        The floor [N s/m]; negative means the force falls with velocity somewhere.
    at : float
        The input [A or V] where it is reached.
    """
    grid = np.linspace(low, high, _SLOPE_GRID)
    A, a, _, c, _ = component_values(S, comp, power, grid)
    floor = np.minimum(c, A * a + c)
    k = int(np.argmin(floor))
    return float(floor[k]), float(grid[k])


def _linear_columns(
    comp: np.ndarray,
    power: np.ndarray,
    th: np.ndarray,
    xn: np.ndarray,
    vn: np.ndarray,
    inn: np.ndarray,
    offset: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Regressors of the coefficients that enter linearly (A, c, d, f0) for a fixed tanh term."""
    lin = np.flatnonzero(np.isin(comp, (0, 3, 4)))
    base = {0: th, 3: vn, 4: xn}
    cols = [base[int(comp[k])] * inn ** power[k] for k in lin]
    if offset:
        cols.append(np.ones_like(xn))
    return np.stack(cols, axis=1), lin


def _linear_starts(
    comp: np.ndarray,
    power: np.ndarray,
    xn: np.ndarray,
    vn: np.ndarray,
    inn: np.ndarray,
    Fn: np.ndarray,
    offset: bool,
    n_candidates: int,
    n_starts: int,
    rng: np.random.Generator,
) -> list[np.ndarray]:
    """Rank seeded draws of the tanh argument by the cost of the linear least-squares completion."""
    ka = int(np.flatnonzero((comp == 1) & (power == 0))[0])
    kb = int(np.flatnonzero((comp == 2) & (power == 0))[0])
    n_par = comp.size + int(offset)
    slopes = 10.0 ** rng.uniform(-0.5, 2.0, n_candidates)
    ratios = rng.uniform(-1.0, 1.0, n_candidates)
    ratios[: max(1, n_candidates // 8)] = 0.0  # always try a tanh without displacement term
    scored = []
    for a, r in zip(slopes, ratios):
        z = a * vn + a * r * xn
        X, lin = _linear_columns(comp, power, np.tanh(z), xn, vn, inn, offset)
        coef = _normal_lstsq(X, Fn)
        cost = float(np.sum((X @ coef - Fn) ** 2))
        theta = np.zeros(n_par)
        theta[ka], theta[kb] = a, a * r
        theta[lin] = coef[: lin.size]
        if offset:
            theta[-1] = coef[-1]
        if np.isfinite(cost):
            scored.append((cost, theta))
    scored.sort(key=lambda ct: ct[0])
    return [th for _, th in scored[:n_starts]]


def _normal_lstsq(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares through column-equilibrated normal equations (small p, tall X).

    Used for the cheap screening of starts only; a (nearly) singular system returns a
    minimum-norm solution via ``lstsq`` on the small Gram matrix.
    """
    norms = np.sqrt(np.einsum("ij,ij->j", X, X))
    norms[norms == 0] = 1.0
    Xs = X / norms
    coef, *_ = np.linalg.lstsq(Xs.T @ Xs, Xs.T @ y, rcond=1e-12)
    return np.asarray(coef / norms)


def _to_physical(
    theta: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    offset: bool,
    *,
    xs: float,
    vs: float,
    i_s: float,
    Fs: float,
) -> tuple[np.ndarray, float]:
    """Convert normalised coefficients back to SI: exact rescaling per component and power."""
    comp_scale = np.array([Fs, 1.0 / vs, 1.0 / xs, Fs / vs, Fs / xs])
    S = theta[: comp.size] * comp_scale[comp] / i_s ** power.astype(float)
    f0 = float(theta[-1] * Fs) if offset else 0.0
    return S, f0
