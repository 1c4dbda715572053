"""Paper Fig. 3: slopes and intercepts of the three zones against current, with their fitted laws."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_zone_laws"]


def plot_zone_laws(laws: Any, *, axes: Any = None, unit: str = "A") -> np.ndarray:
    """Per-level slopes ``m_j`` and intercepts ``c_j`` (points) and their quadratic laws (lines).

    Parameters
    ----------
    laws : ZoneLaws
        Result of :func:`mrdamper.analysis.fit_zone_laws` (``levels``, ``level_m``, ``level_c``,
        ``m(rho)``, ``c(rho)``, ``rho_range``).
    axes : sequence of 2 Axes, optional
        Slope and intercept panels; new side-by-side panels when None.
    unit : str
        Unit of the level on the x axis.

    Returns
    -------
    ndarray of 2 Axes
        Each panel holds 3 point series (``m1 fit``...) and 3 law curves (``m1 law``...).
    """
    from mrdamper.plotting._common import new_axes_column

    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(9.5, 3.6))
    axes = new_axes_column(axes, 2, (9.5, 3.6))
    lo, hi = laws.rho_range
    r = np.linspace(lo, hi, 100)
    lv = np.asarray(laws.levels, dtype=float)
    colors = ("tab:blue", "tab:red", "tab:green")
    for ax, name, pts, law, unit_y in (
        (axes[0], "m", np.asarray(laws.level_m), laws.m(r), "slope [N s/m]"),
        (axes[1], "c", np.asarray(laws.level_c), laws.c(r), "intercept [N]"),
    ):
        for j in range(3):
            ax.plot(lv, pts[:, j], "o", color=colors[j], label=f"{name}{j + 1} fit")
            ax.plot(r, np.asarray(law)[:, j], "-", color=colors[j], lw=1.4, label=f"{name}{j + 1} law")
        ax.set_xlabel(f"i [{unit}]")
        ax.set_ylabel(unit_y)
        ax.grid(True, lw=0.3)
        ax.legend(loc="best", fontsize=7, ncol=2)
    axes[0].set_title("Slopes against current")
    axes[1].set_title("Intercepts against current")
    return axes
