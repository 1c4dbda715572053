"""The RK4 sub-step rule of the Bouc-Wen-type kernels (Spencer and the hysteresis families).

One place for the number of sub-steps per interval: from an upper estimate of the model's
fastest rate (:func:`substeps_for_rate`, at fit and ``step()`` time) and from the largest
sub-step a step form carries (:func:`interval_substeps`, inside the compiled step).
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "MAX_AUTO_SUBSTEPS",
    "SUBSTEP_RATE_PRODUCT",
    "interval_substeps",
    "substeps_for_rate",
]

#: Largest product of the RK4 sub-step and the estimated fastest rate of the model [-] (RK4 is
#: stable up to about 2.8 for real eigenvalues; the step-halving check of every fit and
#: tests/models/test_spencer.py measure the remaining error).
SUBSTEP_RATE_PRODUCT = 2.0
#: Upper limit of automatic sub-steps per sampling interval.
MAX_AUTO_SUBSTEPS = 2000


def substeps_for_rate(dt: float, rate: float) -> int:
    """RK4 sub-steps per interval of ``dt`` [s] for a fastest rate ``rate`` [1/s].

    The product of the sub-step and ``rate`` stays at most :data:`SUBSTEP_RATE_PRODUCT`; at
    least 1 and at most :data:`MAX_AUTO_SUBSTEPS` (also for a non-finite rate).
    """
    if not math.isfinite(rate):
        return MAX_AUTO_SUBSTEPS
    return int(min(MAX_AUTO_SUBSTEPS, max(1, math.ceil(dt * rate / SUBSTEP_RATE_PRODUCT))))


@njit(cache=True)
def interval_substeps(dt: float, max_h: float) -> int:  # pragma: no cover - numba
    """Sub-steps over an interval of ``dt`` [s] so that none exceeds ``max_h`` [s] (at least 1;
    a ``dt`` within rounding of a whole number of ``max_h`` takes that number)."""
    n: int = max(1, math.ceil(dt / max_h * (1.0 - 1e-12)))
    return n
