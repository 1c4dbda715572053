"""The inverse step of the LPV and static-map families: the input that gives a desired force at one
sample (numba, plain values only; a record's inverse in :mod:`mrdamper.control.inverse.current`
runs it
sample by sample, and the C export renders the same choice).

* :func:`solve_interval`: the exact inverse's choice at one sample (see
  :mod:`mrdamper.control.inverse.current`): the previous input when its force is within ``tol``
  of the target, else the exact solution nearest it, else the nearest edge of the tolerance
  band, else the minimum of ``|F - target|``; solutions by bisection of the sign changes on a
  uniform grid;
* :func:`reg_solve_poly` / :func:`reg_solve_static`: the regularised choice, the minimum of
  ``(F - target)^2 + lam2 (r - prev)^2`` over the interval, for the LPV force polynomial and for
  a static map.

The force itself comes from the families' steps (one definition each).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models.lpv.step import dpoly as _dpoly
from mrdamper.models.lpv.step import poly as _poly
from mrdamper.models.sp.kernels import sp_dforce1, sp_force1

__all__ = ["reg_solve_poly", "reg_solve_static", "solve_interval"]

_N_BISECT = 200

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@njit(cache=True)
def _bisect(
    c: FloatArray, target: float, deriv: bool, a: float, b: float
) -> float:  # pragma: no cover - numba
    """Root of ``poly(c) - target`` (or of the derivative) in ``[a, b]`` given a sign change."""
    fa = _dpoly(c, a) if deriv else _poly(c, a) - target
    for _ in range(_N_BISECT):
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        fm = _dpoly(c, m) if deriv else _poly(c, m) - target
        if fm == 0.0:
            return m
        if (fm < 0.0) == (fa < 0.0):
            a, fa = m, fm
        else:
            b = m
    return 0.5 * (a + b)


@njit(cache=True)
def _nearest_root(
    c: FloatArray, target: float, lo: float, hi: float, prev: float, n_grid: int
) -> float:  # pragma: no cover - numba
    """Root of ``poly(c) - target`` in ``[lo, hi]`` nearest ``prev`` (NaN when no sign change)."""
    h = (hi - lo) / n_grid
    best = np.nan
    best_d = np.inf
    ga = _poly(c, lo) - target
    if ga == 0.0:
        best = lo
        best_d = abs(lo - prev)
    for q in range(n_grid):
        a = lo + q * h
        b = hi if q == n_grid - 1 else lo + (q + 1) * h
        gb = _poly(c, b) - target
        r = np.nan
        if gb == 0.0:
            r = b
        elif ga != 0.0 and (ga < 0.0) != (gb < 0.0):
            r = _bisect(c, target, False, a, b)
        if not np.isnan(r):
            d = abs(r - prev)
            if d < best_d:
                best, best_d = r, d
        ga = gb
    return best


@njit(cache=True)
def solve_interval(
    c: FloatArray, target: float, lo: float, hi: float, prev: float, n_grid: int, tol: float
) -> tuple[float, bool]:  # pragma: no cover - numba
    """Admissible ``r`` in ``[lo, hi]`` with ``|poly(c)(r) - target| <= tol`` nearest ``prev``.

    ``prev`` itself is kept when it meets the band; otherwise the exact solution (root of
    ``poly - target``) nearest ``prev``; when there is none, the nearest edge of the band (a root
    of ``poly - (target -/+ tol)``). Landing on the exact solution rather than on the band edge
    lets the next samples hold it. Without any such point the minimiser of ``|poly - target|`` is
    returned (an end of the interval or a stationary point of the polynomial).

    Returns
    -------
    r : float
    exact : bool
        True when ``|poly(c)(r) - target| <= tol`` is met.
    """
    g_prev = _poly(c, prev) - target
    if abs(g_prev) <= tol:
        return prev, True
    if hi <= lo:
        return lo, False
    r0 = _nearest_root(c, target, lo, hi, prev, n_grid)
    if not np.isnan(r0):
        return r0, True
    r1 = _nearest_root(c, target - tol, lo, hi, prev, n_grid)
    r2 = _nearest_root(c, target + tol, lo, hi, prev, n_grid)
    ok1, ok2 = not np.isnan(r1), not np.isnan(r2)
    if ok1 or ok2:
        if not ok2 or (ok1 and abs(r1 - prev) <= abs(r2 - prev)):
            return r1, True
        return r2, True
    # no admissible solution: |g| is smallest at an end or at a stationary point of g
    best = lo
    best_g = abs(_poly(c, lo) - target)
    gh = abs(_poly(c, hi) - target)
    if gh < best_g:
        best, best_g = hi, gh
    h = (hi - lo) / n_grid
    da = _dpoly(c, lo)
    for q in range(n_grid):
        a = lo + q * h
        b = hi if q == n_grid - 1 else lo + (q + 1) * h
        db = _dpoly(c, b)
        if da != 0.0 and db != 0.0 and (da < 0.0) != (db < 0.0):
            r = _bisect(c, target, True, a, b)
            gr = abs(_poly(c, r) - target)
            if gr < best_g:
                best, best_g = r, gr
        da = db
    return best, False


# ----------------------------------------------------------------------------- regularised inverse


@njit(cache=True)
def _slope_poly(
    cf: FloatArray, target: float, r: float, prev: float, lam2: float
) -> float:  # pragma: no cover - numba
    """Half the derivative of the regularised objective, ``(F - target) F' + lam2 (r - prev)``."""
    return (_poly(cf, r) - target) * _dpoly(cf, r) + lam2 * (r - prev)


@njit(cache=True)
def _slope_static(
    x: float,
    v: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    target: float,
    r: float,
    prev: float,
    lam2: float,
) -> float:  # pragma: no cover - numba
    return (sp_force1(x, v, r, comp, power, theta, f0) - target) * sp_dforce1(
        x, v, r, comp, power, theta
    ) + lam2 * (r - prev)


@njit(cache=True)
def _bisect_slope(
    is_poly: bool,
    cf: FloatArray,
    x: float,
    v: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    target: float,
    prev: float,
    lam2: float,
    a: float,
    b: float,
) -> float:  # pragma: no cover
    """Zero of the objective's slope in ``[a, b]``, to machine precision.

    The slope is < 0 at ``a`` and > 0 at ``b``.
    """
    for _ in range(_N_BISECT):
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        if is_poly:
            g = _slope_poly(cf, target, m, prev, lam2)
        else:
            g = _slope_static(x, v, comp, power, theta, f0, target, m, prev, lam2)
        if g == 0.0:
            return m
        if g < 0.0:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


@njit(cache=True)
def _reg_solve(
    is_poly: bool,
    cf: FloatArray,
    x: float,
    v: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    target: float,
    a: float,
    b: float,
    prev: float,
    lam2: float,
    n_grid: int,
) -> tuple[float, bool]:  # pragma: no cover
    """Minimiser of ``(F(r) - target)^2 + lam2 (r - prev)^2`` over ``[a, b]``.

    See :func:`reg_solve_poly`.
    """
    best = min(max(prev, a), b)
    if is_poly:
        f = _poly(cf, best)
    else:
        f = sp_force1(x, v, best, comp, power, theta, f0)
    best_j = (f - target) * (f - target) + lam2 * (best - prev) * (best - prev)
    fmin = f
    fmax = f
    if b <= a:
        return best, fmin == target
    h = (b - a) / n_grid
    for q in range(n_grid + 1):
        r = b if q == n_grid else a + q * h
        if is_poly:
            f = _poly(cf, r)
        else:
            f = sp_force1(x, v, r, comp, power, theta, f0)
        fmin = min(fmin, f)
        fmax = max(fmax, f)
        j = (f - target) * (f - target) + lam2 * (r - prev) * (r - prev)
        if j < best_j:
            best, best_j = r, j
    # local minimum next to the best grid point: the sign change of the slope, bisected
    if is_poly:
        g = _slope_poly(cf, target, best, prev, lam2)
    else:
        g = _slope_static(x, v, comp, power, theta, f0, target, best, prev, lam2)
    if g > 0.0 and best > a:
        lo = max(a, best - h)
        if is_poly:
            g_lo = _slope_poly(cf, target, lo, prev, lam2)
        else:
            g_lo = _slope_static(x, v, comp, power, theta, f0, target, lo, prev, lam2)
        if g_lo < 0.0:
            best = _bisect_slope(
                is_poly, cf, x, v, comp, power, theta, f0, target, prev, lam2, lo, best
            )
    elif g < 0.0 and best < b:
        hi = min(b, best + h)
        if is_poly:
            g_hi = _slope_poly(cf, target, hi, prev, lam2)
        else:
            g_hi = _slope_static(x, v, comp, power, theta, f0, target, hi, prev, lam2)
        if g_hi > 0.0:
            best = _bisect_slope(
                is_poly, cf, x, v, comp, power, theta, f0, target, prev, lam2, best, hi
            )
    return best, fmin <= target <= fmax


@njit(cache=True)
def reg_solve_poly(
    cf: FloatArray, target: float, a: float, b: float, prev: float, lam2: float, n_grid: int
) -> tuple[float, bool]:  # pragma: no cover - numba
    """Minimiser of ``(poly(cf)(r) - target)^2 + lam2 (r - prev)^2`` over ``[a, b]``.

    Grid scan of ``n_grid`` intervals (``prev`` included); then the zero of the objective's slope
    next to the best grid point (where the slope changes sign within one grid step) is bisected to
    machine precision. Returns ``(r, reachable)``: ``reachable`` is False when ``target`` lies
    outside the range of forces on the grid (the damper cannot give it).
    """
    e1 = np.zeros(0, dtype=np.int64)
    return _reg_solve(True, cf, 0.0, 0.0, e1, e1, cf, 0.0, target, a, b, prev, lam2, n_grid)


@njit(cache=True)
def reg_solve_static(
    x: float,
    v: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    target: float,
    a: float,
    b: float,
    prev: float,
    lam2: float,
    n_grid: int,
) -> tuple[float, bool]:  # pragma: no cover
    """As :func:`reg_solve_poly` for one sample of a static map (see :func:`sp_force1`)."""
    return _reg_solve(False, theta, x, v, comp, power, theta, f0, target, a, b, prev, lam2, n_grid)
