"""The first-order drive lag ``d rho/dt = -eta (rho - w)``, written once for every family.

The LPV/LTI models, the SP maps, Bingham and P-15 may filter their electrical input through this
lag (setting ``eta`` [1/s]); :func:`lag_step` is one sample of its exact zero-order-hold
discretisation (``E = exp(-eta dt)``), :func:`first_order_lag` runs it over a record.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

__all__ = ["first_order_lag", "lag_step"]

FloatArray = npt.NDArray[np.float64]


@njit(cache=True)
def lag_step(r: float, w: float, e: float) -> float:  # pragma: no cover - numba
    """The drive lag's next value from its value ``r`` and the command ``w`` held over the
    sample; ``e = exp(-eta dt)``."""
    return e * r + (1.0 - e) * w


@njit(cache=True)
def first_order_lag(w: FloatArray, dt: float, eta: float) -> FloatArray:  # pragma: no cover - numba
    """Exact zero-order-hold discretisation of ``dr/dt = -eta (r - w)``, ``r[0] = w[0]``."""
    n = w.size
    r = np.empty(n)
    e = np.exp(-eta * dt)
    r[0] = w[0]
    for k in range(1, n):
        r[k] = lag_step(r[k - 1], w[k - 1], e)
    return r
