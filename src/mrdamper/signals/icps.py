"""ICPS: pseudo-random current with an increased clock period (long dwell times).

The paper lists "ICPS" as a current pattern of its design of experiments (Table II) without
defining it. Following the project's reading notes (``paper/READING-NOTES.md``, item 8), the same
group's earlier work on training patterns for MR dampers found that increasing the clock period of
the pseudo-random current improves identification, so ICPS is read here as a pseudo-random current
sequence whose clock period is long (about a second instead of tens of milliseconds): the damper
dwells at each current long enough to settle and to sweep several displacement cycles.
"""

from __future__ import annotations

import numpy as np

from mrdamper.signals.common import (
    SeedLike,
    check_int_at_least,
    check_range,
    child_seeds,
    hold_samples,
    sample_grid,
)
from mrdamper.signals.prbs import mls, prbs_order_for

__all__ = ["icps"]


def icps(
    fs: float,
    duration: float,
    *,
    low: float,
    high: float,
    clock_period: float = 1.0,
    n_levels: int = 2,
    seed: SeedLike,
) -> np.ndarray:
    """Pseudo-random current with an increased clock period (reading of READING-NOTES item 8).

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].
    low, high : float
        Current range [A].
    clock_period : float
        Dwell time of each value [s] (the "increased" clock period; default 1 s).
    n_levels : int
        Number of equally spaced current levels in ``[low, high]``. With 2 (default) the signal is a
        maximum-length PRBS between ``low`` and ``high`` clocked at ``clock_period``; with more,
        each clock period holds a level drawn uniformly (seeded) from the ``n_levels`` levels.
    seed : int or numpy.random.SeedSequence
        Register state / level draws.

    Returns
    -------
    ndarray
        Current [A], one value per sample, piecewise constant on whole clock periods.

    Examples
    --------
    >>> i = icps(1000.0, 10.0, low=0.0, high=1.0, clock_period=1.0, n_levels=5, seed=2)
    >>> set(i.tolist()) <= {0.0, 0.25, 0.5, 0.75, 1.0}
    True
    """
    n, fs = sample_grid(fs, duration)
    lo, hi = check_range("low/high", low, high, "A")
    hold = hold_samples("clock_period", clock_period, fs)
    n_levels = check_int_at_least("n_levels", n_levels, 2)
    n_clocks = -(-n // hold)
    bits_seed, level_seed = child_seeds(seed, 2)
    if n_levels == 2:
        index = mls(prbs_order_for(n_clocks), seed=bits_seed, n_bits=n_clocks).astype(np.int64)
    else:
        index = np.random.default_rng(level_seed).integers(0, n_levels, size=n_clocks)
    levels = np.linspace(lo, hi, int(n_levels))
    return np.repeat(levels[index], hold)[:n]
