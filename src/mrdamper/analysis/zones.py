"""Three-zone continuous piecewise-linear force-velocity regression (paper eq. 17).

Zone labels follow eq. (17) (see the reading notes, item 5):

* zone I   ``v < v_low``:            ``F = m1 v + c1``
* zone II  ``v_low <= v <= v_high``: ``F = m2 v + c2``
* zone III ``v > v_high``:           ``F = m3 v + c3``

The fit is continuous at both breakpoints. For fixed breakpoints it is linear least squares on the
hinge basis ``[1, v, min(v - v_low, 0), max(v - v_high, 0)]``; the breakpoints are found by
profiling the residual sum of squares over a grid of velocity quantiles and refining the best grid
point with a bounded scalar (symmetric, ``v_low = -v_high`` as in eq. 18) or Nelder-Mead search.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd
from scipy import optimize

from mrdamper.errors import DataValidationError, IdentificationError

__all__ = ["POST_YIELD_FACTOR", "ZoneFit", "fit_zones", "post_yield_slopes", "segment_plateaus"]

#: Post-yield samples are those beyond this many zone limits (``|v| > 3 v_high``) [-].
POST_YIELD_FACTOR = 3.0


@dataclass(frozen=True)
class ZoneFit:
    """Result of a three-zone force-velocity regression at one electrical level.

    Attributes
    ----------
    v_low, v_high : float
        Breakpoints [m/s], ``v_low < v_high``.
    m : tuple of 3 float
        Slopes ``(m1, m2, m3)`` of zones I, II, III [N s/m].
    c : tuple of 3 float
        Intercepts ``(c1, c2, c3)`` [N].
    r2 : float
        Coefficient of determination of the fit [-].
    resid_std : float
        Standard deviation of the residuals [N].
    n : int
        Number of samples fitted.
    symmetric : bool
        Whether ``v_low = -v_high`` was imposed.
    level : float or None
        Electrical level of the data (current [A] or scheduling value), if known.
    """

    v_low: float
    v_high: float
    m: tuple[float, float, float]
    c: tuple[float, float, float]
    r2: float
    resid_std: float
    n: int
    symmetric: bool
    level: float | None = None

    def predict(self, v: Any) -> np.ndarray:
        """Force of the piecewise-linear law [N] at velocities ``v`` [m/s]."""
        v = np.asarray(v, dtype=float)
        m1, m2, m3 = self.m
        c1, c2, c3 = self.c
        return np.where(
            v < self.v_low, m1 * v + c1, np.where(v > self.v_high, m3 * v + c3, m2 * v + c2)
        )

    @property
    def central_is_steepest(self) -> bool:
        """True when ``m2`` is the biggest slope, as the paper's normalisation assumes."""
        return bool(self.m[1] >= self.m[0] and self.m[1] >= self.m[2])

    def to_dict(self) -> dict[str, Any]:
        """Plain-float dict (one row of :meth:`to_frame`)."""
        return {
            "level": self.level,
            "v_low": self.v_low,
            "v_high": self.v_high,
            "m1": self.m[0],
            "m2": self.m[1],
            "m3": self.m[2],
            "c1": self.c[0],
            "c2": self.c[1],
            "c3": self.c[2],
            "r2": self.r2,
            "resid_std": self.resid_std,
            "n": self.n,
            "symmetric": self.symmetric,
        }

    def to_frame(self) -> pd.DataFrame:
        """One-row DataFrame: level, v_low, v_high [m/s], m1..m3 [N s/m], c1..c3 [N], r2, ..."""
        return pd.DataFrame([self.to_dict()])

    def plot(self, ax: Any = None, v: Any = None, F: Any = None) -> Any:
        """Draw the three lines (and the data ``v`` [m/s], ``F`` [N] when given).

        Returns the Axes.
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(5, 4))
        if v is not None and F is not None:
            ax.plot(v, F, ".", ms=1.5, alpha=0.3, color="0.5", label="measured")
            lo, hi = float(np.min(v)), float(np.max(v))
        else:
            span = max(abs(self.v_low), abs(self.v_high))
            lo, hi = -3 * span, 3 * span
        vv = np.linspace(lo, hi, 400)
        label = "zones" if self.level is None else f"zones at {self.level:g}"
        ax.plot(vv, self.predict(vv), lw=1.5, label=label)
        for b in (self.v_low, self.v_high):
            ax.axvline(b, ls=":", lw=0.8, color="k")
        ax.set_xlabel("v [m/s]")
        ax.set_ylabel("F [N]")
        ax.legend(loc="best")
        return ax


class _Profile:
    """Residual sum of squares of the hinge regression for any breakpoint pair, in O(log n).

    The Gram matrix of the basis ``[1, v, min(v - lo, 0), max(v - hi, 0)]`` and its right-hand
    side are sums of ``1, v, v^2, F, v F`` over the zones, read from prefix sums over sorted ``v``.
    """

    def __init__(self, v: np.ndarray, F: np.ndarray) -> None:
        order = np.argsort(v, kind="stable")
        self.v = v[order]
        f = F[order]
        z = np.zeros(1)
        self.S0 = np.arange(v.size + 1, dtype=float)
        self.S1 = np.concatenate((z, np.cumsum(self.v)))
        self.S2 = np.concatenate((z, np.cumsum(self.v**2)))
        self.T0 = np.concatenate((z, np.cumsum(f)))
        self.T1 = np.concatenate((z, np.cumsum(self.v * f)))
        self.FF = float(f @ f)
        self.n = v.size

    def solve(self, lo: float, hi: float) -> tuple[float, np.ndarray]:
        n = self.n
        a = int(np.searchsorted(self.v, lo, side="left"))  # v < lo: [0, a)
        b = int(np.searchsorted(self.v, hi, side="right"))  # v > hi: [b, n)
        S0, S1, S2, T0, T1 = self.S0, self.S1, self.S2, self.T0, self.T1
        l0, l1, l2, lt0, lt1 = S0[a], S1[a], S2[a], T0[a], T1[a]
        u0, u1, u2 = S0[n] - S0[b], S1[n] - S1[b], S2[n] - S2[b]
        ut0, ut1 = T0[n] - T0[b], T1[n] - T1[b]
        G = np.array(
            [
                [S0[n], S1[n], l1 - lo * l0, u1 - hi * u0],
                [S1[n], S2[n], l2 - lo * l1, u2 - hi * u1],
                [l1 - lo * l0, l2 - lo * l1, l2 - 2 * lo * l1 + lo * lo * l0, 0.0],
                [u1 - hi * u0, u2 - hi * u1, 0.0, u2 - 2 * hi * u1 + hi * hi * u0],
            ]
        )
        g = np.array([T0[n], T1[n], lt1 - lo * lt0, ut1 - hi * ut0])
        try:
            coef = np.linalg.solve(G, g)
        except np.linalg.LinAlgError:
            coef = np.linalg.lstsq(G, g, rcond=None)[0]
        return max(self.FF - float(coef @ g), 0.0), coef


def fit_zones(
    v: Any,
    F: Any,
    *,
    symmetric: bool = True,
    level: float | None = None,
    min_fraction: float = 0.03,
    grid: int = 60,
) -> ZoneFit:
    """Fit the continuous three-zone law of eq. (17) to force-velocity data.

    Parameters
    ----------
    v : array_like
        Velocity [m/s].
    F : array_like
        Force [N], same length.
    symmetric : bool
        Impose ``v_low = -v_high`` (eq. 18). Otherwise both breakpoints are free.
    level : float, optional
        Electrical level the data belong to (stored in the result).
    min_fraction : float
        Smallest fraction of the samples each outer zone must hold [-].
    grid : int
        Number of grid points per breakpoint for the profiled search.

    Returns
    -------
    ZoneFit

    Raises
    ------
    DataValidationError
        If ``v`` and ``F`` differ in length, are not finite, or do not cover both signs of ``v``.
    IdentificationError
        If no breakpoint pair leaves enough samples in every zone.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.linspace(-0.1, 0.1, 2001)
    >>> F = np.where(np.abs(v) < 0.02, 2e4 * v, np.sign(v) * (400 + 2e3 * (np.abs(v) - 0.02)))
    >>> fz = fit_zones(v, F)
    >>> round(fz.v_high, 4), round(fz.m[1])
    (0.02, 20000)
    """
    v = np.asarray(v, dtype=float).ravel()
    F = np.asarray(F, dtype=float).ravel()
    if v.size != F.size:
        raise DataValidationError("F", f"has {F.size} samples but 'v' has {v.size}")
    for name, a in (("v", v), ("F", F)):
        if not np.all(np.isfinite(a)):
            raise DataValidationError(
                name, "contains non-finite values; zone regression needs finite data"
            )
    if not 0 < min_fraction < 0.34:
        raise DataValidationError(
            "min_fraction", f"expected a value in (0, 0.34), got {min_fraction}"
        )
    if grid < 3:
        raise DataValidationError("grid", f"expected at least 3 grid points, got {grid}")
    n_min = max(5, int(np.ceil(min_fraction * v.size)))
    if v.size < 3 * n_min or np.sum(v < 0) < n_min or np.sum(v > 0) < n_min:
        raise DataValidationError(
            "v",
            f"expected at least {n_min} samples of each sign among {3 * n_min} or more "
            f"(got {int(np.sum(v < 0))} negative, {int(np.sum(v > 0))} positive of {v.size})",
        )
    vs = np.sort(v)
    prof = _Profile(v, F)
    if symmetric:
        a = np.sort(np.abs(v))
        # the outer zones together hold samples with |v| > b; each needs n_min on its own side
        neg, pos = np.sort(-v[v < 0]), np.sort(v[v > 0])
        b_max = min(neg[-n_min], pos[-n_min])
        b_min = a[min(n_min, a.size - 1)]
        if not b_max > b_min:
            raise IdentificationError(
                "fit_zones: no symmetric breakpoint leaves enough samples in every zone"
            )
        cand = np.linspace(b_min, b_max, grid)
        sse = np.array([prof.solve(-b, b)[0] for b in cand])
        k = int(np.argmin(sse))
        lo_b, hi_b = cand[max(k - 1, 0)], cand[min(k + 1, grid - 1)]
        res = optimize.minimize_scalar(
            lambda b: prof.solve(-b, b)[0],
            bounds=(lo_b, hi_b),
            method="bounded",
            options={"xatol": 1e-9 * max(abs(b_max), 1e-12)},
        )
        b = float(res.x) if res.fun <= sse[k] else float(cand[k])
        lo, hi = -b, b
    else:
        q_lo = np.linspace(vs[n_min], vs[v.size // 2], grid)
        q_hi = np.linspace(vs[v.size // 2], vs[-n_min - 1], grid)
        best = (np.inf, 0.0, 0.0)
        for lo_c in q_lo:
            for hi_c in q_hi:
                if hi_c <= lo_c or np.sum(v < lo_c) < n_min or np.sum(v > hi_c) < n_min:
                    continue
                s = prof.solve(lo_c, hi_c)[0]
                if s < best[0]:
                    best = (s, lo_c, hi_c)
        if not np.isfinite(best[0]):
            raise IdentificationError(
                "fit_zones: no breakpoint pair leaves enough samples in every zone"
            )

        def objective(p: np.ndarray) -> float:
            lo_p, hi_p = float(p[0]), float(p[1])
            if hi_p <= lo_p or np.sum(v < lo_p) < n_min or np.sum(v > hi_p) < n_min:
                return best[0] * 10 + 1.0
            return prof.solve(lo_p, hi_p)[0]

        res = optimize.minimize(
            objective,
            np.array(best[1:]),
            method="Nelder-Mead",
            options={"xatol": 1e-9 * (vs[-1] - vs[0]), "fatol": 1e-12 * best[0]},
        )
        lo, hi = (float(res.x[0]), float(res.x[1])) if res.fun <= best[0] else (best[1], best[2])
    _, coef = prof.solve(lo, hi)
    a0, b1, d1, d3 = (float(x) for x in coef)
    resid = F - (a0 + b1 * v + d1 * np.minimum(v - lo, 0.0) + d3 * np.maximum(v - hi, 0.0))
    sse_final = float(resid @ resid)
    m = (b1 + d1, b1, b1 + d3)
    c = (a0 - d1 * lo, a0, a0 - d3 * hi)
    var = float(np.sum((F - F.mean()) ** 2))
    r2 = 1.0 - sse_final / var if var > 0 else float("nan")
    return ZoneFit(
        v_low=float(lo),
        v_high=float(hi),
        m=m,
        c=c,
        r2=float(r2),
        resid_std=float(np.sqrt(sse_final / v.size)),
        n=int(v.size),
        symmetric=symmetric,
        level=None if level is None else float(level),
    )


def post_yield_slopes(
    fit: ZoneFit,
    v: Any,
    F: Any,
    *,
    factor: float = POST_YIELD_FACTOR,
    min_samples: int = 50,
) -> ZoneFit:
    """Re-estimate the outer slopes ``m1``, ``m3`` on the post-yield samples only.

    The three-zone regression fits each outer line over every sample beyond its limit. Samples
    just past the limit include motions that have not yielded yet (small strokes, the first
    samples after a reversal), whose force lies below the post-yield line, so the fitted outer
    slope is steeper than the damper's slope at high velocity, and a model built on it
    over-predicts the force there (on the virtual rig's Table II: 1.2 to 1.7 times the reference
    damper's slope). Here each outer slope is the least-squares slope of ``F = m v + c`` over
    the samples beyond ``factor`` times the limit (``v > factor v_high``, ``v < factor v_low``).
    The intercept is then the one that keeps the law continuous at the limit (the continuous
    reading of eq. 22 only uses the slope ratio ``m_j / m2``).

    A side keeps the zone fit's slope when it has fewer than ``min_samples`` such samples, when
    their velocities span less than a factor 1.5 (the slope would be ill-determined), or when
    the estimate is outside ``[0, m2]`` (the range eq. 20 needs).

    Parameters
    ----------
    fit : ZoneFit
        Three-zone fit of the same data.
    v, F : array_like
        Velocity [m/s] and force [N] of the data ``fit`` was fitted on.
    factor : float
        Post-yield samples are beyond ``factor`` times each zone limit [-].
    min_samples : int
        Fewest post-yield samples a side needs.

    Returns
    -------
    ZoneFit
        ``fit`` with the re-estimated slopes and continuous intercepts.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.linspace(-0.2, 0.2, 4001)
    >>> F = np.sign(v) * np.minimum(2e4 * np.abs(v), 200 + 1e3 * np.abs(v))
    >>> knee = np.abs(v) < 0.03
    >>> F[knee] *= 0.8  # a rounded knee: the zone fit's outer lines get steeper
    >>> zf = fit_zones(v, F)
    >>> py = post_yield_slopes(zf, v, F)
    >>> round(py.m[2]), round(zf.m[2]) > 1000
    (1000, True)
    """
    v = np.asarray(v, dtype=float).ravel()
    F = np.asarray(F, dtype=float).ravel()
    if v.size != F.size:
        raise DataValidationError("F", f"has {F.size} samples but 'v' has {v.size}")
    m = list(fit.m)
    c = list(fit.c)
    for j, limit in ((0, fit.v_low), (2, fit.v_high)):
        side = v < factor * limit if j == 0 else v > factor * limit
        vs, Fs = v[side], F[side]
        if vs.size < min_samples:
            continue
        span = np.abs(vs)
        if span.max() < 1.5 * span.min():
            continue
        slope = float(np.polyfit(vs, Fs, 1)[0])
        if not 0.0 <= slope <= fit.m[1]:
            continue
        m[j] = slope
        c[j] = fit.m[1] * limit + fit.c[1] - slope * limit
    return replace(fit, m=(m[0], m[1], m[2]), c=(c[0], c[1], c[2]))


def segment_plateaus(
    signal: Any,
    dt: float,
    *,
    tolerance: float,
    min_duration: float = 1.0,
    settle: float = 0.0,
) -> list[tuple[int, int, float]]:
    """Find constant-level plateaus of a stepped signal (e.g. stepped-current SC records).

    Parameters
    ----------
    signal : array_like
        The stepped signal (current [A] or voltage [V]).
    dt : float
        Sampling interval [s].
    tolerance : float
        Largest deviation from the plateau's first value still counted as the same level
        [signal units].
    min_duration : float
        Shortest plateau kept [s] (after removing ``settle``).
    settle : float
        Time skipped at the start of each plateau to let transients die out [s].

    Returns
    -------
    list of (start, stop, level)
        Sample ranges ``start:stop`` and the median level of each plateau.
    """
    s = np.asarray(signal, dtype=float).ravel()
    if not np.all(np.isfinite(s)):
        raise DataValidationError("signal", "contains non-finite values")
    if not tolerance > 0:
        raise DataValidationError("tolerance", f"expected a positive value, got {tolerance}")
    if not dt > 0:
        raise DataValidationError("dt", f"expected a positive interval [s], got {dt}")
    out: list[tuple[int, int, float]] = []
    start = 0
    n_settle = round(settle / dt)
    n_min = max(2, round(min_duration / dt))
    for k in range(1, s.size + 1):
        if k == s.size or abs(s[k] - s[start]) > tolerance:
            a = start + n_settle
            if k - a >= n_min:
                out.append((a, k, float(np.median(s[a:k]))))
            start = k
    return out
