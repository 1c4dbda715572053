"""The record inverses of the two array forms, private to :mod:`.current` (which re-exports
:func:`driver_command`): an LPV / LTI model's (exact at any record rate, or regularised with its
drive lag and lead horizon, on the compiled kernels of :mod:`._inverse_kernels`) and a static
map's exact inverse (vectorised grid scan, then golden-section refinement of the misfit)."""

from __future__ import annotations

from typing import Any

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.control.damper import StaticMapModel
from mrdamper.control.inverse import _inverse_kernels as K
from mrdamper.control.inverse._forms import inverse_form
from mrdamper.control.inverse._inverse_setup import dahl_along, lpv_inverse_fields, lpv_law_arrays
from mrdamper.errors import DataValidationError, MrDamperError, Note
from mrdamper.models.lpv import TransferFunctionModel

__all__ = ["driver_command", "lpv_any_rate", "lpv_reg", "static_exact"]

_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def driver_command(
    rho: Any, eta: float, dt: float, limits: tuple[float, float] | None = None
) -> np.ndarray:
    """Command ``w`` whose first-order drive lag ``d rho/dt = -eta (rho - w)`` gives ``rho``.

    Exact inverse of the zero-order-hold discretisation used by the models
    (``rho[k] = e rho[k-1] + (1 - e) w[k-1]``, ``e = exp(-eta dt)``, ``rho[0] = w[0]``)::

        w[k] = (rho[k+1] - e rho[k]) / (1 - e),   k < n - 1;    w[n-1] = rho[n-1]

    a lead filter. ``w[0]`` reproduces ``rho[1]``; the lag itself starts at rest, so ``rho`` is
    reproduced exactly when ``rho[1] = rho[0]`` (as :func:`inverse_current` ensures).

    Parameters
    ----------
    rho : array_like
        Scheduling trajectory to reach [A] or [V].
    eta : float
        Drive-lag rate [1/s].
    dt : float
        Sampling interval [s].
    limits : (float, float), optional
        Command limits; the command is clipped to them.

    Returns
    -------
    ndarray
        The command [A] or [V].
    """
    r = np.asarray(rho, dtype=float)
    if r.ndim != 1 or r.size == 0 or not np.all(np.isfinite(r)):
        raise DataValidationError(
            "rho", f"expected a non-empty 1-D finite array, got shape {r.shape}"
        )
    if not (np.isfinite(eta) and eta > 0):
        raise DataValidationError("eta", f"expected a positive drive-lag rate [1/s], got {eta!r}")
    if not (np.isfinite(dt) and dt > 0):
        raise DataValidationError("dt", f"expected a positive sampling interval [s], got {dt!r}")
    e = float(np.exp(-eta * dt))
    w = np.empty_like(r)
    w[:-1] = (r[1:] - e * r[:-1]) / (1.0 - e)
    w[-1] = r[-1]
    if limits is not None:
        w = np.clip(w, float(limits[0]), float(limits[1]))
    return w


def lpv_any_rate(
    model: TransferFunctionModel,
    t: np.ndarray,
    v: np.ndarray,
    Fd: np.ndarray,
    lo: float,
    hi: float,
    n_grid: int,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The LPV inverse of a record at any rate: solved at the model rate, as ``simulate`` runs it.

    A record at another rate is resampled to the model rate on the way in (the same resampling
    as the model's prediction, :func:`mrdamper.models.rates.to_model_rate`); the input is
    interpolated back onto the record's samples, with a note.
    """
    from mrdamper.models.rates import to_model_rate

    if t.size < 2:
        raise DataValidationError("t", f"expected at least 2 samples, got {t.size}")
    fs = (t.size - 1) / float(t[-1] - t[0])
    if abs(fs - model.fs) <= 1e-6 * model.fs:
        return _lpv(model, t, v, Fd, lo, hi, n_grid, tol)
    v_m = to_model_rate(v, fs, model.fs)
    Fd_m = to_model_rate(Fd, fs, model.fs)
    if v_m.size < 2:
        raise DataValidationError(
            "t",
            f"record too short: {t.size} samples at {fs:g} Hz give {v_m.size} at the model rate",
        )
    t_m = t[0] + np.arange(v_m.size) / model.fs
    rho_m, w_m, sat_m = _lpv(model, t_m, v_m, Fd_m, lo, hi, n_grid, tol)
    warn_user(
        f"{model.kind}: record sampled at {fs:g} Hz, model at {model.fs:g} Hz; "
        "the inverse is solved at the "
        "model rate and its input interpolated back onto the record's samples",
        Note,
    )
    nearest = np.clip(np.rint((t - t[0]) * model.fs).astype(np.int64), 0, v_m.size - 1)
    return np.interp(t, t_m, rho_m), np.interp(t, t_m, w_m), sat_m[nearest]


def _lpv(
    model: TransferFunctionModel,
    t: np.ndarray,
    v: np.ndarray,
    Fd: np.ndarray,
    lo: float,
    hi: float,
    n_grid: int,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if t.size < 2:
        raise DataValidationError("t", f"expected at least 2 samples, got {t.size}")
    dt = float(t[1] - t[0])
    fs = 1.0 / dt
    if abs(fs - model.fs) > 1e-6 * model.fs:
        raise DataValidationError(
            "t",
            f"record sampled at {fs:g} Hz but the LPV model runs at {model.fs:g} Hz; resample the "
            "record to the model rate first "
            "(the causal inverse works sample by sample at that rate)",
        )
    mode, gm, gc, mu_h, mu_l = lpv_law_arrays(model)
    lag = -1.0 if model.eta is None else float(np.exp(-model.eta * dt))
    v = np.ascontiguousarray(v, dtype=np.float64)
    blend, z = dahl_along(model, v, 1.0 / model.fs)  # as the model: dt = 1 / fs
    rho, _, sat = K.lpv_inverse(
        v,
        np.ascontiguousarray(Fd),
        np.ascontiguousarray(model.alpha),
        np.ascontiguousarray(model.beta),
        float(model.offset),
        lo,
        hi,
        lag,
        mode,
        gm,
        gc,
        mu_h,
        mu_l,
        lo,
        n_grid,
        tol,
        z,
        blend,
    )
    if model.eta is None:
        return rho, rho, sat
    return rho, driver_command(rho, model.eta, dt, (lo, hi)), sat


def lpv_reg(
    model: TransferFunctionModel,
    t: np.ndarray,
    v: np.ndarray,
    Fd: np.ndarray,
    lo: float,
    hi: float,
    n_grid: int,
    lam: float,
    rate: float,
    n_h: int = 1,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Regularised LPV inverse at the model rate.

    Records at another rate are resampled in and out.
    """
    from mrdamper.models.rates import to_model_rate

    if t.size < 2:
        raise DataValidationError("t", f"expected at least 2 samples, got {t.size}")
    fs_rec = 1.0 / float(t[1] - t[0])
    vm = np.ascontiguousarray(to_model_rate(v, fs_rec, model.fs))
    Fm = np.ascontiguousarray(to_model_rate(Fd, fs_rec, model.fs))
    dt = 1.0 / model.fs
    lag = -1.0 if model.eta is None else float(np.exp(-model.eta * dt))
    _, z = dahl_along(model, vm, dt)
    inv = inverse_form(lam=lam, n_grid=n_grid, horizon=n_h, lag=lag, **lpv_inverse_fields(model))
    rho, _, sat = K.lpv_inverse_reg_hys(vm, Fm, inv, lo, hi, lo, rate * dt, z)
    w = rho if model.eta is None else driver_command(rho, model.eta, dt, (lo, hi))
    if abs(fs_rec - model.fs) <= 1e-9 * model.fs:
        return rho, w, sat
    warn_user(
        f"{model.kind}: record sampled at {fs_rec:g} Hz, model at {model.fs:g} Hz; "
        "the inverse is solved at the "
        "model rate and its input interpolated back onto the record's samples",
        Note,
    )
    tm = np.arange(rho.size) * dt
    tr = t - t[0]
    back = np.minimum(np.rint(tr * model.fs).astype(np.int64), rho.size - 1)
    return np.interp(tr, tm, rho), np.interp(tr, tm, w), sat[back]


def _static_force(model: StaticMapModel, x: np.ndarray, v: np.ndarray, i: np.ndarray) -> np.ndarray:
    xb, vb, ib = np.broadcast_arrays(x, v, i)
    shape = xb.shape
    return np.asarray(model.force(xb.ravel(), vb.ravel(), ib.ravel())).reshape(shape)


def static_exact(
    model: StaticMapModel,
    x: np.ndarray,
    v: np.ndarray,
    Fd: np.ndarray,
    lo: float,
    hi: float,
    n_grid: int,
) -> tuple[np.ndarray, np.ndarray]:
    n = x.size
    grid = np.linspace(lo, hi, n_grid + 1)
    g = _static_force(model, x[:, None], v[:, None], grid[None, :]) - Fd[:, None]
    if not np.all(np.isfinite(g)):
        raise MrDamperError(
            f"{model.kind}: the force map is not finite on the input grid {lo:g}..{hi:g}"
        )
    zero = g == 0.0
    change = np.signbit(g[:, :-1]) != np.signbit(g[:, 1:])
    bracket = change | zero[:, :-1] | zero[:, 1:]
    has_root = bracket.any(axis=1)
    q = np.argmax(bracket, axis=1)
    i_out = np.empty(n)
    # exact solutions: bisection on the lowest bracket
    rows = np.flatnonzero(has_root)
    a, b = grid[q[rows]], grid[q[rows] + 1]
    ga = g[rows, q[rows]]
    gb = g[rows, q[rows] + 1]
    a_hit, b_hit = ga == 0.0, (gb == 0.0) & (ga != 0.0)
    xa, va, fa = x[rows], v[rows], Fd[rows]
    for _ in range(60):
        m = 0.5 * (a + b)
        gm = _static_force(model, xa, va, m) - fa
        left = np.signbit(gm) != np.signbit(ga)
        b = np.where(left, m, b)
        a, ga = np.where(left, a, m), np.where(left, ga, gm)
    root = 0.5 * (a + b)
    root = np.where(a_hit, grid[q[rows]], np.where(b_hit, grid[q[rows] + 1], root))
    i_out[rows] = root
    # no exact solution: golden-section search of |g| around the grid minimum
    rows = np.flatnonzero(~has_root)
    if rows.size:
        k = np.argmin(np.abs(g[rows]), axis=1)
        a = grid[np.maximum(k - 1, 0)]
        b = grid[np.minimum(k + 1, n_grid)]
        xa, va, fa = x[rows], v[rows], Fd[rows]
        best = grid[k]
        best_g = np.abs(g[rows, k])
        for _ in range(60):
            c1 = b - _GOLDEN * (b - a)
            c2 = a + _GOLDEN * (b - a)
            g1 = np.abs(_static_force(model, xa, va, c1) - fa)
            g2 = np.abs(_static_force(model, xa, va, c2) - fa)
            lower = g1 <= g2
            b = np.where(lower, c2, b)
            a = np.where(lower, a, c1)
            cand = 0.5 * (a + b)
            gc = np.abs(_static_force(model, xa, va, cand) - fa)
            better = gc < best_g
            best = np.where(better, cand, best)
            best_g = np.where(better, gc, best_g)
        i_out[rows] = best
    return i_out, ~has_root
