"""Force-velocity figures of the analysis: the F-v map at several currents (paper Fig. 1) and the
three-zone regression at one current (Fig. 2)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["plot_fv_map", "plot_zone_fit"]


def plot_fv_map(
    curves: Mapping[float, tuple[Any, Any]],
    *,
    ax: Any = None,
    unit: str = "A",
    cmap: str = "viridis",
) -> Any:
    """Paper Fig. 1: force-velocity map, one trace per electrical level.

    Parameters
    ----------
    curves : mapping
        ``level -> (v, F)``: velocity [m/s] and force [N] samples at that level (e.g. from
        :func:`mrdamper.study.analysis_step.fv_curves`).
    ax : Axes, optional
        Where to draw; a new figure when None.
    unit : str
        Unit of the level in the legend (``"A"``, ``"V"``).
    cmap : str
        Matplotlib colour map spanning the levels.

    Returns
    -------
    Axes
        One line per level, labelled ``"i = <level> <unit>"``.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.linspace(-0.1, 0.1, 50)
    >>> ax = plot_fv_map({0.0: (v, 100 * v), 1.0: (v, 900 * np.tanh(30 * v))})
    >>> len(ax.get_lines())
    2
    """
    if not curves:
        raise DataValidationError("curves", "expected at least one level -> (v, F) entry, got none")
    import matplotlib.pyplot as plt

    from mrdamper.plotting._common import new_axes

    ax = new_axes(ax, (5.6, 3.8))
    levels = sorted(curves)
    colors = plt.get_cmap(cmap)(np.linspace(0.0, 0.9, len(levels)))
    for lev, col in zip(levels, colors):
        v, F = (np.asarray(a, dtype=float) for a in curves[lev])
        if v.shape != F.shape:
            raise DataValidationError(
                "curves", f"level {lev}: v has shape {v.shape}, F has {F.shape}"
            )
        ax.plot(v, F, ".", ms=1.2, alpha=0.6, color=col, label=f"i = {round(lev, 3):.3g} {unit}")
    ax.set_xlabel("v [m/s]")
    ax.set_ylabel("F [N]")
    ax.set_title("Force-velocity map")
    ax.grid(True, lw=0.3)
    from mrdamper.plotting._common import legend_outside

    legend_outside(ax, markerscale=8, title=f"level [{unit}]")
    return ax


def _slope_text(m: float) -> str:
    """Slope [N s/m] to 4 significant digits without an exponent (116400, 6202, 12.35)."""
    return f"{float(f'{m:.4g}'):.0f}" if abs(m) >= 1e4 else f"{m:.4g}"


def plot_zone_fit(v: Any, F: Any, fit: Any, *, ax: Any = None, unit: str = "A") -> Any:
    """Paper Fig. 2: measured F-v samples at one level with the three-zone regression (eq. 17).

    Parameters
    ----------
    v, F : array_like
        Velocity [m/s] and force [N] samples at the level.
    fit : ZoneFit
        Result of :func:`mrdamper.analysis.fit_zones` (``v_low``, ``v_high``, ``m``, ``c``).
    ax : Axes, optional
        Where to draw; a new figure when None.
    unit : str
        Unit of ``fit.level`` in the title.

    Returns
    -------
    Axes
        Lines: ``measured``, ``zone I``, ``zone II``, ``zone III`` and two dotted zone limits.
    """
    from mrdamper.plotting._common import new_axes

    v = np.asarray(v, dtype=float)
    F = np.asarray(F, dtype=float)
    if v.shape != F.shape or v.ndim != 1 or v.size == 0:
        raise DataValidationError(
            "F", f"expected 1-D v and F of equal length, got {v.shape} and {F.shape}"
        )
    ax = new_axes(ax, (5.2, 4.4))
    ax.plot(v, F, ".", ms=1.2, alpha=0.4, color="0.55", label="measured")
    lo, hi = float(v.min()), float(v.max())
    spans = ((lo, min(fit.v_low, hi)), (fit.v_low, fit.v_high), (max(fit.v_high, lo), hi))
    for j, ((a, b), name, col) in enumerate(
        zip(spans, ("zone I", "zone II", "zone III"), ("tab:blue", "tab:red", "tab:green"))
    ):
        vv = np.linspace(a, b, 50)
        ax.plot(
            vv,
            fit.m[j] * vv + fit.c[j],
            lw=2.0,
            color=col,
            label=f"{name}: m{j + 1} = {_slope_text(fit.m[j])} N s/m",
        )
    for b, name, ha, dx in ((fit.v_low, "v_low", "right", -2), (fit.v_high, "v_high", "left", 2)):
        ax.axvline(b, ls=":", lw=0.9, color="k")
        ax.annotate(
            f"{name} = {b:.3g} m/s",
            (b, 0.97),
            xycoords=("data", "axes fraction"),
            xytext=(dx, 0),
            textcoords="offset points",
            fontsize=7,
            ha=ha,
            va="top",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8},
        )
    level = getattr(fit, "level", None)
    ax.set_title(
        "Three-zone F-v regression" + ("" if level is None else f" at i = {level:.3g} {unit}")
    )
    ax.set_xlabel("v [m/s]")
    ax.set_ylabel("F [N]")
    ax.grid(True, lw=0.3)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(nbins=6))
    ax.legend(
        loc="upper center",
        bbox_to_anchor=(0.5, -0.14),
        ncol=2,
        fontsize=7.5,
        markerscale=6,
        frameon=False,
    )
    return ax
