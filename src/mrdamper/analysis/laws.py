"""Zone parameters as laws of the electrical level (paper Section III-C and eq. 18).

Slopes and intercepts are polynomials of the level (quadratic in the paper,
``m_j(i) = gamma_m2 i^2 + gamma_m1 i + gamma_m0``), the zone limits linear
(``v_high(i) = mu1 i + mu2``; ``v_low = -v_high`` when symmetric). Per-level zone fits come from
constant-current records grouped by metadata, from constant plateaus of stepped-current (SC)
records, or from bins of a continuously varying scheduling signal.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd

from mrdamper._warn import warn_user
from mrdamper.analysis.levels import GroupBy, pool_by_level
from mrdamper.analysis.scheduling import Reading, scheduling_input_arrays
from mrdamper.analysis.zones import POST_YIELD_FACTOR, ZoneFit, fit_zones, post_yield_slopes
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, IdentificationError

__all__ = [
    "BLOCK",
    "ZoneLawWarning",
    "ZoneLaws",
    "fit_zone_laws",
    "in_blocks",
    "laws_keeping_eq_20",
    "zone_fits_binned",
    "zone_fits_by_level",
]


class ZoneLawWarning(UserWarning):
    """Zone data break an assumption of the paper (e.g. ``m2`` is not the steepest slope)."""


#: How the outer slopes of each level's zone fit are estimated (see :func:`zone_fits_by_level`).
OuterSlopes = Literal["zones", "post-yield"]

#: Samples per block of the elementwise zone-law evaluations on long records: the per-sample
#: slopes, intercepts and limits of a block are formed at a time, not of the whole record.
BLOCK = 1 << 18


def in_blocks(f: Callable[..., np.ndarray], *arrays: np.ndarray) -> np.ndarray:
    """``f(*arrays)`` for an elementwise ``f`` of 1-D arrays of one length, evaluated on
    :data:`BLOCK` samples at a time above that length: the same values, with temporaries
    bounded by the block instead of the record.

    Parameters
    ----------
    f : callable
        Elementwise function of the arrays, returning one float64 array of their length.
    *arrays : ndarray
        Its arguments, 1-D and of one length (e.g. velocity [m/s] and level [A]).

    Returns
    -------
    ndarray
        ``f(*arrays)``.
    """
    n = arrays[0].size
    if arrays[0].ndim != 1 or n <= BLOCK:
        return f(*arrays)
    out = np.empty(n)
    for a in range(0, n, BLOCK):
        out[a : a + BLOCK] = f(*(x[a : a + BLOCK] for x in arrays))
    return out


def _polyval(coef: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Evaluate rows of ``coef`` (column p = coefficient of rho**p) at ``rho``; shape (n, rows)."""
    out = np.zeros(rho.shape + (coef.shape[0],))
    for p in range(coef.shape[1] - 1, -1, -1):
        out = out * rho[..., None] + coef[:, p]
    return out


@dataclass(frozen=True, eq=False)
class ZoneLaws:
    """Slopes, intercepts and zone limits as functions of the electrical level ``rho``.

    Attributes
    ----------
    gamma_m : ndarray, shape (3, d + 1)
        Row j: coefficients of ``m_{j+1}(rho)``, column p multiplies ``rho**p`` [N s/m per unit^p].
    gamma_c : ndarray, shape (3, d + 1)
        Same for the intercepts ``c_j(rho)`` [N per unit^p].
    mu_high : (float, float)
        ``v_high(rho) = mu_high[0] rho + mu_high[1]`` [m/s per unit, m/s].
    mu_low : (float, float)
        ``v_low(rho) = mu_low[0] rho + mu_low[1]``; ``(-mu1, -mu2)`` when symmetric.
    symmetric : bool
        Whether ``v_low = -v_high`` was imposed.
    rho_range : (float, float)
        Range of the levels the laws were fitted on [A] or [V].
    levels : ndarray, shape (L,)
        Levels of the per-level fits.
    level_m, level_c : ndarray, shape (L, 3)
        Per-level slopes and intercepts (for residuals and plots).
    level_v_low, level_v_high : ndarray, shape (L,)
        Per-level zone limits [m/s].
    """

    gamma_m: np.ndarray
    gamma_c: np.ndarray
    mu_high: tuple[float, float]
    mu_low: tuple[float, float]
    symmetric: bool
    rho_range: tuple[float, float]
    levels: np.ndarray
    level_m: np.ndarray
    level_c: np.ndarray
    level_v_low: np.ndarray
    level_v_high: np.ndarray

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in (
            "gamma_m",
            "gamma_c",
            "levels",
            "level_m",
            "level_c",
            "level_v_low",
            "level_v_high",
        ):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            set_(self, name, arr)
        if (
            self.gamma_m.ndim != 2
            or self.gamma_m.shape[0] != 3
            or self.gamma_c.shape != self.gamma_m.shape
        ):
            raise DataValidationError(
                "gamma_m",
                f"expected two (3, d+1) arrays, got {self.gamma_m.shape} and {self.gamma_c.shape}",
            )
        set_(self, "mu_high", tuple(float(x) for x in self.mu_high))
        set_(self, "mu_low", tuple(float(x) for x in self.mu_low))
        set_(self, "rho_range", tuple(float(x) for x in self.rho_range))
        set_(self, "symmetric", bool(self.symmetric))

    # ---------------------------------------------------------------- evaluation
    def m(self, rho: Any) -> np.ndarray:
        """Slopes ``(m1, m2, m3)`` [N s/m] at levels ``rho``; shape ``rho.shape + (3,)``."""
        return _polyval(self.gamma_m, np.asarray(rho, dtype=float))

    def c(self, rho: Any) -> np.ndarray:
        """Intercepts ``(c1, c2, c3)`` [N] at levels ``rho``; shape ``rho.shape + (3,)``."""
        return _polyval(self.gamma_c, np.asarray(rho, dtype=float))

    def v_high(self, rho: Any) -> np.ndarray:
        """Upper zone limit [m/s] at ``rho`` (eq. 18)."""
        return self.mu_high[0] * np.asarray(rho, dtype=float) + self.mu_high[1]

    def v_low(self, rho: Any) -> np.ndarray:
        """Lower zone limit [m/s] at ``rho`` (``-v_high`` when symmetric)."""
        return self.mu_low[0] * np.asarray(rho, dtype=float) + self.mu_low[1]

    def scheduling_input(self, v: Any, rho: Any, reading: Reading = "continuous") -> np.ndarray:
        """LPV input ``u`` [m/s] from velocity ``v`` [m/s] and level ``rho`` (eqs. 19-22).

        See :mod:`mrdamper.analysis.scheduling` for the two readings.
        """
        v = np.asarray(v, dtype=float)
        rho = np.broadcast_to(np.asarray(rho, dtype=float), v.shape)
        return in_blocks(
            lambda vb, rb: scheduling_input_arrays(
                vb, self.m(rb), self.c(rb), self.v_low(rb), self.v_high(rb), reading
            ),
            v,
            rho,
        )

    def problems(self, n_grid: int = 101) -> list[str]:
        """Violations of the paper's assumptions over ``rho_range`` (empty when none).

        Checked on a grid: ``m2 > 0``, ``0 <= m_j / m2 <= 1`` for the outer zones (eq. 20, m2 the
        biggest slope) and ``v_low < 0 < v_high``.
        """
        r = np.linspace(self.rho_range[0], self.rho_range[1], n_grid)
        m = self.m(r)
        out = []
        if np.any(m[:, 1] <= 0):
            k = int(np.argmax(m[:, 1] <= 0))
            out.append(f"m2({r[k]:.4g}) = {m[k, 1]:.4g} N s/m is not positive")
        else:
            for j, name in ((0, "m1"), (2, "m3")):
                s = m[:, j] / m[:, 1]
                bad = np.flatnonzero((s < 0) | (s > 1))
                if bad.size:
                    k = int(bad[0])
                    out.append(
                        f"{name}/m2 at rho={r[k]:.4g} is {s[k]:.4g}, expected in [0, 1] "
                        f"(m2 must be the biggest slope, outer slopes non-negative)"
                    )
        vh, vl = self.v_high(r), self.v_low(r)
        if np.any(vh <= 0) or np.any(vl >= 0):
            out.append(
                f"zone limits must satisfy v_low < 0 < v_high over [{self.rho_range[0]:.4g}, "
                f"{self.rho_range[1]:.4g}]; got v_high in "
                f"[{vh.min():.4g}, {vh.max():.4g}] m/s, v_low in "
                f"[{vl.min():.4g}, {vl.max():.4g}] m/s"
            )
        return out

    # ---------------------------------------------------------------- reporting
    def to_frame(self) -> pd.DataFrame:
        """Per level: fitted zone parameters, the laws' values and the residuals (fit - law)."""
        lv = self.levels
        m_law, c_law = self.m(lv), self.c(lv)
        df = pd.DataFrame({"level": lv})
        for j in range(3):
            df[f"m{j + 1}"] = self.level_m[:, j]
            df[f"m{j + 1}_law"] = m_law[:, j]
            df[f"m{j + 1}_resid"] = self.level_m[:, j] - m_law[:, j]
        for j in range(3):
            df[f"c{j + 1}"] = self.level_c[:, j]
            df[f"c{j + 1}_law"] = c_law[:, j]
            df[f"c{j + 1}_resid"] = self.level_c[:, j] - c_law[:, j]
        df["v_high"] = self.level_v_high
        df["v_high_law"] = self.v_high(lv)
        df["v_high_resid"] = self.level_v_high - self.v_high(lv)
        df["v_low"] = self.level_v_low
        df["v_low_law"] = self.v_low(lv)
        df["v_low_resid"] = self.level_v_low - self.v_low(lv)
        return df

    def plot(self, axes: Any = None) -> Any:
        """Three panels: slopes, intercepts and zone limits against level (points: fits, lines:
        laws)."""
        import matplotlib.pyplot as plt

        if axes is None:
            _, axes = plt.subplots(1, 3, figsize=(11, 3.2))
        r = np.linspace(self.rho_range[0], self.rho_range[1], 100)
        for j in range(3):
            (line,) = axes[0].plot(r, self.m(r)[:, j], label=f"m{j + 1}")
            axes[0].plot(self.levels, self.level_m[:, j], "o", color=line.get_color())
            (line,) = axes[1].plot(r, self.c(r)[:, j], label=f"c{j + 1}")
            axes[1].plot(self.levels, self.level_c[:, j], "o", color=line.get_color())
        (line,) = axes[2].plot(r, self.v_high(r), label="v_high")
        axes[2].plot(self.levels, self.level_v_high, "o", color=line.get_color())
        (line,) = axes[2].plot(r, self.v_low(r), label="v_low")
        axes[2].plot(self.levels, self.level_v_low, "o", color=line.get_color())
        for ax, lab in zip(axes, ("slope [N s/m]", "intercept [N]", "zone limit [m/s]")):
            ax.set_xlabel("level")
            ax.set_ylabel(lab)
            ax.legend(loc="best")
        return axes

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict (floats exact through ``json``)."""
        return {
            "gamma_m": self.gamma_m.tolist(),
            "gamma_c": self.gamma_c.tolist(),
            "mu_high": list(self.mu_high),
            "mu_low": list(self.mu_low),
            "symmetric": self.symmetric,
            "rho_range": list(self.rho_range),
            "levels": self.levels.tolist(),
            "level_m": self.level_m.tolist(),
            "level_c": self.level_c.tolist(),
            "level_v_low": self.level_v_low.tolist(),
            "level_v_high": self.level_v_high.tolist(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ZoneLaws:
        """Inverse of :meth:`to_dict`."""
        keys = (
            "gamma_m",
            "gamma_c",
            "mu_high",
            "mu_low",
            "symmetric",
            "rho_range",
            "levels",
            "level_m",
            "level_c",
            "level_v_low",
            "level_v_high",
        )
        missing = [k for k in keys if k not in data]
        if missing:
            raise DataValidationError("zone_laws", f"missing key(s) {missing}")
        return cls(**{k: data[k] for k in keys})


# ------------------------------------------------------------------------- per-level fits
def zone_fits_by_level(
    data: Experiment | Iterable[Experiment],
    *,
    by: GroupBy = "current",
    source: Literal["i", "voltage"] = "i",
    symmetric: bool = True,
    plateau_tolerance: float | None = None,
    min_duration: float = 1.0,
    settle: float = 0.2,
    outer_slopes: OuterSlopes = "zones",
) -> list[ZoneFit]:
    """Three-zone fits, one per electrical level, sorted by level.

    Parameters
    ----------
    data : Experiment or iterable of Experiment
        Records. With ``by="current"`` every record needs metadata ``current`` [A] and records of
        equal current are pooled. With ``by="plateaus"`` each record's electrical input (``source``)
        is cut into constant plateaus (stepped-current SC records) and plateaus of equal level
        (within ``plateau_tolerance``) are pooled across records.
    by : {"current", "plateaus"}
        How records are grouped into levels (see ``data``).
    source : {"i", "voltage"}
        Electrical input channel whose plateaus are used with ``by="plateaus"``.
    symmetric : bool
        Impose ``v_low = -v_high`` in each fit.
    plateau_tolerance : float, optional
        Level tolerance for plateaus [A or V]; default 2 % of the input's span.
    min_duration, settle : float
        Shortest plateau kept and time skipped after each step [s].
    outer_slopes : {"zones", "post-yield"}
        ``"zones"``: the outer slopes of the three-zone regression (the paper's). ``"post-yield"``:
        re-estimated on the samples beyond three zone limits (:func:`post_yield_slopes`).
    """
    pools = pool_by_level(
        data,
        by=by,
        source=source,
        tolerance=plateau_tolerance,
        min_duration=min_duration,
        settle=settle,
    )
    if not pools:
        raise IdentificationError("zone_fits_by_level: no constant-level data found")
    fits = []
    for lev in sorted(pools):
        v = np.concatenate([p[0] for p in pools[lev]])
        F = np.concatenate([p[1] for p in pools[lev]])
        fits.append(_outer(fit_zones(v, F, symmetric=symmetric, level=lev), v, F, outer_slopes))
    return fits


def zone_fits_binned(
    v: Sequence[np.ndarray],
    F: Sequence[np.ndarray],
    rho: Sequence[np.ndarray],
    *,
    n_bins: int = 5,
    symmetric: bool = True,
    outer_slopes: OuterSlopes = "zones",
) -> list[ZoneFit]:
    """Three-zone fits on bins of a continuously varying level ``rho`` (equal-count bins).

    Useful when the electrical input never holds a constant level long enough for plateaus
    (e.g. a drive-lag-filtered switching voltage). Each fit's level is the bin's mean ``rho``.

    Parameters
    ----------
    v, F, rho : sequence of ndarray
        Velocity [m/s], force [N] and level (e.g. filtered current [A]) of each record.
    n_bins : int
        Number of equal-count bins of ``rho``.
    symmetric : bool
        Fit the zones symmetric in velocity (see :func:`fit_zones`).
    outer_slopes : {"zones", "post-yield"}
        As in :func:`zone_fits_by_level`.
    """
    vv, FF, rr = (np.concatenate([np.asarray(a, float).ravel() for a in s]) for s in (v, F, rho))
    if not (vv.size == FF.size == rr.size):
        raise DataValidationError("rho", f"lengths differ: v {vv.size}, F {FF.size}, rho {rr.size}")
    if n_bins < 1:
        raise DataValidationError("n_bins", f"expected a positive integer, got {n_bins}")
    edges = np.quantile(rr, np.linspace(0, 1, n_bins + 1))
    idx = np.clip(np.searchsorted(edges, rr, side="right") - 1, 0, n_bins - 1)
    fits = []
    for b in range(n_bins):
        sel = idx == b
        if np.count_nonzero(sel) < 50:
            continue
        level = float(rr[sel].mean())
        fit = fit_zones(vv[sel], FF[sel], symmetric=symmetric, level=level)
        fits.append(_outer(fit, vv[sel], FF[sel], outer_slopes))
    return fits


def _outer(fit: ZoneFit, v: np.ndarray, F: np.ndarray, outer_slopes: OuterSlopes) -> ZoneFit:
    """The fit as it is (``"zones"``) or with its post-yield outer slopes (``"post-yield"``)."""
    if outer_slopes == "zones":
        return fit
    if outer_slopes == "post-yield":
        return post_yield_slopes(fit, v, F, factor=POST_YIELD_FACTOR)
    raise DataValidationError(
        "outer_slopes", f"expected 'zones' or 'post-yield', got {outer_slopes!r}"
    )


# ------------------------------------------------------------------------- laws
def fit_zone_laws(
    data: Experiment | Iterable[Experiment] | Sequence[ZoneFit],
    *,
    degree: int = 2,
    strict: bool = True,
    **level_options: Any,
) -> ZoneLaws:
    """Fit ``m_j(rho)``, ``c_j(rho)`` (polynomials, quadratic by default) and linear zone limits.

    Parameters
    ----------
    data : records or sequence of ZoneFit
        Records are first reduced to per-level fits with :func:`zone_fits_by_level`
        (``level_options`` are passed on: ``by``, ``source``, ``symmetric``, ...); a sequence of
        :class:`ZoneFit` with ``level`` set is used as it is.
    degree : int
        Polynomial degree of the slope and intercept laws (2 in the paper). Needs at least
        ``degree + 1`` levels; the zone limits need two levels (one level gives constant limits).
    strict : bool
        If true, laws that break the paper's assumptions over the level range (see
        :meth:`ZoneLaws.problems`) raise :class:`IdentificationError`; otherwise they warn.
    **level_options
        Options of :func:`zone_fits_by_level` for records (``by``, ``source``, ...).

    Returns
    -------
    ZoneLaws

    Warns
    -----
    ZoneLawWarning
        When a per-level fit has a central slope ``m2`` that is not the biggest.
    """
    items: list[Any] = list(data) if not isinstance(data, Experiment) else [data]
    fits: list[ZoneFit]
    if items and all(isinstance(f, ZoneFit) for f in items):
        fits = sorted(items, key=lambda f: (f.level is None, f.level))
        if any(f.level is None for f in fits):
            raise DataValidationError(
                "level", "every ZoneFit needs a level to fit laws across levels"
            )
    else:
        fits = zone_fits_by_level(items, **level_options)
    if not isinstance(degree, (int, np.integer)) or degree < 0:
        raise DataValidationError("degree", f"expected a non-negative integer, got {degree!r}")
    L = len(fits)
    if L < degree + 1:
        raise IdentificationError(
            f"fit_zone_laws: degree {degree} laws need at least {degree + 1} levels, got {L} "
            f"({[f.level for f in fits]})"
        )
    for f in fits:
        if not f.central_is_steepest:
            warn_user(
                f"zone fit at level {f.level:g}: central slope m2={f.m[1]:.4g} N s/m is not the "
                f"biggest (m1={f.m[0]:.4g}, m3={f.m[2]:.4g}); the normalisation of eq. (20) "
                "assumes it is",
                ZoneLawWarning,
            )
    lv = np.array([f.level for f in fits], dtype=float)
    M = np.array([f.m for f in fits])
    C = np.array([f.c for f in fits])
    vh = np.array([f.v_high for f in fits])
    vl = np.array([f.v_low for f in fits])
    V = np.vander(lv, degree + 1, increasing=True)
    gamma_m = np.linalg.lstsq(V, M, rcond=None)[0].T
    gamma_c = np.linalg.lstsq(V, C, rcond=None)[0].T
    symmetric = all(f.symmetric for f in fits)
    if L >= 2:
        V1 = np.vander(lv, 2, increasing=True)
        mu_h = np.linalg.lstsq(V1, vh, rcond=None)[0][::-1]
        mu_l = -mu_h if symmetric else np.linalg.lstsq(V1, vl, rcond=None)[0][::-1]
    else:
        mu_h = np.array([0.0, vh[0]])
        mu_l = -mu_h if symmetric else np.array([0.0, vl[0]])
    laws = ZoneLaws(
        gamma_m=gamma_m,
        gamma_c=gamma_c,
        mu_high=tuple(mu_h),
        mu_low=tuple(mu_l),
        symmetric=symmetric,
        rho_range=(float(lv.min()), float(lv.max())),
        levels=lv,
        level_m=M,
        level_c=C,
        level_v_low=vl,
        level_v_high=vh,
    )
    bad = laws.problems()
    if bad:
        msg = "zone laws break the paper's assumptions: " + "; ".join(bad)
        if strict:
            raise IdentificationError(msg + " (pass strict=False to continue with a warning)")
        warn_user(msg, ZoneLawWarning)
    return laws


def laws_keeping_eq_20(
    fit: Callable[[OuterSlopes, bool], ZoneLaws], *, strict: bool
) -> tuple[ZoneLaws, OuterSlopes, str]:
    """The post-yield laws, or the regression's where only those keep eq. (20).

    The one rule of every user of post-yield outer slopes (the LPV estimator, the study's
    analysis step): post-yield slopes fitted on few levels, or extrapolated between them, can give
    an outer slope above ``m2``, which eq. (20) forbids; the three-zone regression's slopes then
    often keep it.

    Parameters
    ----------
    fit : callable
        ``fit(outer_slopes, strict)`` fits the laws with those outer slopes (as
        :func:`fit_zone_laws`, ``strict`` raising on laws that break the paper's assumptions).
    strict : bool
        Whether the regression's laws, when they are taken and break the assumptions too, raise.

    Returns
    -------
    laws : ZoneLaws
        The post-yield laws, unless they break eq. (20) and the regression's do not.
    used : {"post-yield", "zones"}
        Which they are.
    note : str
        Why the regression's laws were taken ("" when they were not).
    """
    with warnings.catch_warnings(record=True) as caught:  # kept back until the choice is made
        warnings.simplefilter("always")
        post = fit("post-yield", False)
    bad = post.problems()
    if bad:
        regression = fit("zones", strict)
        if not regression.problems():
            note = (
                f"post-yield outer slopes give laws that break eq. (20) ({bad[0]}); the "
                "three-zone regression's slopes are used"
            )
            return regression, "zones", note
    for w in caught:
        warn_user(str(w.message), w.category)
    return post, "post-yield", ""
