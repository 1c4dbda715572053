"""SC: stepped increments of constant current across a range (paper, Table II, experiments 6-8)."""

from __future__ import annotations

from typing import Literal

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.signals.common import check_int_at_least, check_range, n_samples

__all__ = ["StepDirection", "stepped_current"]

StepDirection = Literal["up", "down", "up-down"]


def stepped_current(
    fs: float,
    duration: float,
    *,
    low: float,
    high: float,
    n_levels: int = 5,
    direction: StepDirection = "up",
) -> np.ndarray:
    """Staircase of constant current levels, each held for an equal dwell time.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s]; split into equal dwell times, one per step.
    low, high : float
        First and last level [A] (levels are equally spaced, both ends included).
    n_levels : int
        Number of distinct levels (>= 2).
    direction : {"up", "down", "up-down"}
        ``"up"``: low to high; ``"down"``: high to low; ``"up-down"``: low to high and back
        (``2 * n_levels - 1`` steps).

    Returns
    -------
    ndarray
        Current [A], one value per sample. Deterministic (no seed).

    Examples
    --------
    >>> i = stepped_current(10.0, 2.0, low=0.0, high=1.0, n_levels=2)
    >>> i.tolist()  # doctest: +NORMALIZE_WHITESPACE
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
     1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]
    """
    n = n_samples(fs, duration)
    lo, hi = check_range("low/high", low, high, "A")
    n_levels = check_int_at_least("n_levels", n_levels, 2)
    levels = np.linspace(lo, hi, int(n_levels))
    if direction == "up":
        steps = levels
    elif direction == "down":
        steps = levels[::-1]
    elif direction == "up-down":
        steps = np.concatenate((levels, levels[-2::-1]))
    else:
        raise DataValidationError(
            "direction", f"expected 'up', 'down' or 'up-down', got {direction!r}"
        )
    if steps.size > n:
        raise DataValidationError("n_levels", f"{steps.size} steps do not fit in {n} samples")
    # step k covers samples [k*n/steps, (k+1)*n/steps): equal dwell within one sample
    index = (np.arange(n) * steps.size) // n
    return steps[index]
