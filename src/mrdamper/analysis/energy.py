"""Energy dissipated per displacement cycle: the area of the force-displacement loop.

A cycle runs from one upward crossing of the displacement through its mid-range to the next.
Crossings are detected with a hysteresis band (a Schmitt trigger) so sensor noise near the
mid-range does not split a cycle: a cycle starts where the displacement last rose through ``mid``
before it reached ``mid + band * half_range``, after having been below ``mid - band * half_range``.
The work done on the damper over a cycle is ``W = integral F v dt`` [J] (trapezoidal rule over the
samples), which equals the loop area ``closed integral F dx`` when ``v = dx/dt``. Cycle boundaries
come from the displacement only, so the measured force and every model's force are integrated over
the same cycles.
"""

from __future__ import annotations

from itertools import pairwise
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["cycle_starts", "energy_per_cycle"]


def _arrays(**named: Any) -> dict[str, np.ndarray]:
    out = {k: np.asarray(v, dtype=float) for k, v in named.items()}
    n = {a.shape for a in out.values()}
    if len(n) != 1 or next(iter(out.values())).ndim != 1:
        raise DataValidationError(
            next(iter(out)), f"expected 1-D arrays of one length, got shapes {sorted(n)}"
        )
    for k, a in out.items():
        if not np.all(np.isfinite(a)):
            raise DataValidationError(k, "contains NaN or infinite values")
    return out


def cycle_starts(x: Any, band: float = 0.1) -> np.ndarray:
    """Sample indices where the displacement crosses its mid-range upwards (cycle starts).

    Parameters
    ----------
    x : array_like
        Displacement [m].
    band : float
        Hysteresis band as a fraction of the half-range of ``x`` [-]: a start counts once ``x``
        has been below ``mid - band * half_range`` and then reaches ``mid + band * half_range``.

    Returns
    -------
    ndarray of int
        Increasing indices; consecutive pairs delimit complete cycles.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0, 3, 0.001)
    >>> np.round(t[cycle_starts(np.sin(2 * np.pi * 2 * t))], 2)  # upward crossings every 0.5 s
    array([0.5, 1. , 1.5, 2. , 2.5])
    """
    xa = _arrays(x=x)["x"]
    if not 0.0 <= band < 1.0:
        raise DataValidationError("band", f"expected a fraction in [0, 1), got {band!r}")
    if xa.size < 3:
        return np.zeros(0, dtype=int)
    lo, hi = float(xa.min()), float(xa.max())
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    if half <= 0.0:
        return np.zeros(0, dtype=int)
    arm, fire = mid - band * half, mid + band * half
    starts: list[int] = []
    armed = bool(xa[0] < arm)
    last_up = -1  # last sample where x rose through mid
    for k in range(1, xa.size):
        if xa[k - 1] < mid <= xa[k]:
            last_up = k
        if not armed:
            armed = bool(xa[k] < arm)
        elif xa[k] >= fire and last_up > 0:
            starts.append(last_up)
            armed = False
    return np.asarray(starts, dtype=int)


def energy_per_cycle(t: Any, x: Any, v: Any, F: Any, band: float = 0.1) -> np.ndarray:
    """Energy dissipated in each complete displacement cycle, ``W = integral F v dt`` [J].

    Parameters
    ----------
    t : array_like
        Time [s].
    x : array_like
        Displacement [m] (defines the cycles).
    v : array_like
        Velocity [m/s].
    F : array_like
        Damper force [N] (measured or a model's).
    band : float
        Hysteresis band of :func:`cycle_starts` [-].

    Returns
    -------
    ndarray
        One energy per complete cycle [J] (positive for a dissipative damper); empty when the
        record holds less than one complete cycle.

    Examples
    --------
    A viscous damper ``F = c v`` on ``x = X sin(w t)`` dissipates ``pi c w X^2`` per cycle:

    >>> import numpy as np
    >>> t = np.arange(0, 2, 1e-4); w = 2 * np.pi * 2; X = 0.01
    >>> W = energy_per_cycle(
    ...     t, X * np.sin(w * t), X * w * np.cos(w * t), 1000 * X * w * np.cos(w * t)
    ... )
    >>> bool(np.allclose(W, np.pi * 1000 * w * X**2, rtol=1e-3))
    True
    """
    from scipy.integrate import trapezoid

    a = _arrays(t=t, x=x, v=v, F=F)
    starts = cycle_starts(a["x"], band)
    power = a["F"] * a["v"]
    out = []
    for s, e in pairwise(starts):
        seg = slice(int(s), int(e) + 1)
        out.append(float(trapezoid(power[seg], a["t"][seg])))
    return np.asarray(out, dtype=float)
