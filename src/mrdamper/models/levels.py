"""Whether an electrical input takes one level (shared by the fit template and the lag choice)."""

from __future__ import annotations

import numpy as np

__all__ = ["single_level"]


def single_level(values: np.ndarray, rel_tol: float = 1e-9) -> float | None:
    """The one level of a constant electrical input, or None when it takes more than one value.

    ``values`` is constant when its spread is at most ``rel_tol * max(1, max |values|)``.

    Parameters
    ----------
    values : ndarray
        Electrical input [A] or [V] (or its extremes).
    rel_tol : float
        Relative spread below which the input is one level [-].
    """
    lo, hi = float(np.min(values)), float(np.max(values))
    if hi - lo <= rel_tol * max(1.0, abs(lo), abs(hi)):
        return 0.5 * (lo + hi)
    return None
