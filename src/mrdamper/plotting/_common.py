"""Small helpers shared by the figure modules (axes creation, time windows, model colours)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = [
    "PRINT_STYLE",
    "check_same_length",
    "legend_outside",
    "model_color",
    "new_axes",
    "window_mask",
]

#: Matplotlib settings of the report's figures: drawn at the size they are printed (at most
#: 7 in wide, the text width of an A4 or letter page), so no text is smaller than 7 pt on paper.
PRINT_STYLE: dict[str, Any] = {
    "font.size": 9.0,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "figure.titlesize": 10.0,
    "axes.grid": True,
    "grid.linewidth": 0.3,
    "lines.linewidth": 1.0,
}

#: Fixed colour per registry kind so a model looks the same in every figure.
_KIND_COLORS = {
    "measured": "0.15",
    "lpv": "tab:red",
    "lti": "tab:gray",
    "p15": "tab:blue",
    "sp1": "tab:green",
    "sp2": "tab:olive",
    "sp3": "tab:cyan",
    "sp4": "tab:purple",
    "spencer": "tab:orange",
    "bingham": "tab:brown",
    "tanh": "darkgoldenrod",
    "boucwen": "slateblue",
    "dahl": "darkcyan",
    "lugre": "crimson",
}
_FALLBACK = ("tab:pink", "gold", "navy", "teal", "maroon", "lime")


def model_color(label: str, k: int = 0) -> str:
    """Colour of a model label (its kind's colour, else a fallback by position ``k``)."""
    return _KIND_COLORS.get(label.lower(), _FALLBACK[k % len(_FALLBACK)])


def legend_outside(ax: Any, **kwargs: Any) -> Any:
    """Legend to the right of ``ax``, outside the data area; returns the Legend."""
    opts: dict[str, Any] = {
        "loc": "upper left",
        "bbox_to_anchor": (1.01, 1.0),
        "borderaxespad": 0.0,
        "frameon": False,
    }
    opts.update(kwargs)
    return ax.legend(**opts)


def new_axes(ax: Any, figsize: tuple[float, float]) -> Any:
    """Return ``ax`` or a new Axes on a new Figure of ``figsize`` [in]."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=figsize)
    return ax


def new_axes_column(
    axes: Any, n: int, figsize: tuple[float, float], sharex: bool = True
) -> np.ndarray:
    """Return ``axes`` (checked to hold ``n`` Axes) or ``n`` new stacked Axes."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(n, 1, sharex=sharex, figsize=figsize)
    arr = np.atleast_1d(np.asarray(axes, dtype=object)).ravel()
    if arr.size != n:
        raise DataValidationError("axes", f"expected {n} Axes, got {arr.size}")
    return arr


def window_mask(t: np.ndarray, window: Sequence[float] | None) -> np.ndarray:
    """Boolean mask of samples with ``window[0] <= t <= window[1]`` [s] (all when None)."""
    if window is None:
        return np.ones(t.shape, dtype=bool)
    if len(window) != 2 or not window[0] < window[1]:
        raise DataValidationError(
            "window", f"expected (t_start, t_stop) with t_start < t_stop [s], got {window!r}"
        )
    mask = (t >= window[0]) & (t <= window[1])
    if not mask.any():
        raise DataValidationError(
            "window",
            f"{tuple(window)} s holds no sample of a record spanning [{t[0]:g}, {t[-1]:g}] s",
        )
    return mask


def check_same_length(name: str, values: Any, n: int) -> np.ndarray:
    """Return ``values`` as a float array of length ``n`` or raise naming ``name``."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size != n:
        raise DataValidationError(
            name, f"expected {n} samples like the record, got shape {arr.shape}"
        )
    return arr
