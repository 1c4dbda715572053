"""Paper Fig. 3: slopes and intercepts of the three zones against current, with their fitted laws.

Each of the six quantities has a panel and a scale of its own: the central slope ``m2`` is one to
two orders of magnitude larger than ``m1`` and ``m3``, which a shared axis would flatten.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_zone_laws"]

_ZONES = ("I", "II", "III")
_COLORS = ("tab:blue", "tab:red", "tab:green")


def plot_zone_laws(laws: Any, *, axes: Any = None, unit: str = "A") -> np.ndarray:
    """Per-level slopes ``m_j`` and intercepts ``c_j`` (points) and their quadratic laws (lines).

    Parameters
    ----------
    laws : ZoneLaws
        Result of :func:`mrdamper.analysis.fit_zone_laws` (``levels``, ``level_m``, ``level_c``,
        ``m(rho)``, ``c(rho)``, ``rho_range``).
    axes : array of 6 Axes, optional
        Panels ``m1, m2, m3, c1, c2, c3`` (row-major); a new 2 x 3 grid when None.
    unit : str
        Unit of the level on the x axis.

    Returns
    -------
    ndarray of 6 Axes
        Shape (2, 3): slopes on the first row, intercepts on the second. Each panel holds the
        fitted values at each level (line labelled ``"m1 fit"``...) and the law (``"m1 law"``...).

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.analysis import fit_zone_laws, fit_zones
    >>> v = np.linspace(-0.2, 0.2, 401)
    >>> fits = [fit_zones(v, np.clip(5e4 * v, -100 - 900 * a, 100 + 900 * a) + 500 * v, level=a)
    ...         for a in (0.0, 0.5, 1.0)]
    >>> axes = plot_zone_laws(fit_zone_laws(fits))
    >>> axes.shape, axes[0, 1].get_lines()[0].get_label()
    ((2, 3), 'm2 fit')
    """
    from mrdamper.plotting._common import new_axes_column

    if axes is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 3, figsize=(7.0, 4.4), sharex=True, layout="constrained")
    arr = new_axes_column(axes, 6, (7.0, 4.4)).reshape(2, 3)
    lo, hi = laws.rho_range
    r = np.linspace(lo, hi, 100)
    lv = np.asarray(laws.levels, dtype=float)
    for row, name, pts, law, unit_y in (
        (0, "m", np.asarray(laws.level_m), np.asarray(laws.m(r)), "N s/m"),
        (1, "c", np.asarray(laws.level_c), np.asarray(laws.c(r)), "N"),
    ):
        for j in range(3):
            ax = arr[row, j]
            ax.plot(lv, pts[:, j], "o", ms=4, color=_COLORS[j], label=f"{name}{j + 1} fit")
            ax.plot(r, law[:, j], "-", color=_COLORS[j], lw=1.3, label=f"{name}{j + 1} law")
            kind = "slope" if name == "m" else "intercept"
            ax.set_title(f"zone {_ZONES[j]}: {kind} {name}{j + 1}", fontsize=9)
            ax.set_ylabel(f"{name}{j + 1} [{unit_y}]")
            if row == 1:
                ax.set_xlabel(f"i [{unit}]")
            ax.grid(True, lw=0.3)
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
    fig = arr[0, 0].figure
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], ls="", marker="o", color="0.3", label="zone fit at one level (eq. 17)"),
        Line2D([], [], color="0.3", label="quadratic law across current (eq. 18)"),
    ]
    if fig.get_layout_engine() is not None:
        fig.legend(handles=handles, loc="outside lower center", ncol=2, frameon=False)
    else:
        fig.legend(handles=handles, loc="lower center", ncol=2, frameon=False)
    return arr
