"""Amplitude-modulated pseudo-random binary sequence (APRBS).

An APRBS keeps the switching instants of a PRBS and gives every constant segment (run) of it its
own level, drawn uniformly at random within a range. The shortest hold is therefore one clock
period of the underlying PRBS, and the longest ``order`` clock periods.
"""

from __future__ import annotations

import numpy as np

from mrdamper.signals.common import (
    SeedLike,
    check_range,
    child_seeds,
    hold_samples,
    sample_grid,
)
from mrdamper.signals.prbs import mls, prbs_order_for

__all__ = ["aprbs", "run_starts"]


def run_starts(values: np.ndarray) -> np.ndarray:
    """Indices where a new constant segment of ``values`` starts (always includes 0)."""
    values = np.asarray(values)
    if values.size == 0:
        return np.zeros(0, dtype=np.int64)
    return np.concatenate(([0], np.flatnonzero(values[1:] != values[:-1]) + 1))


def aprbs(
    fs: float,
    duration: float,
    *,
    low: float,
    high: float,
    min_hold: float,
    seed: SeedLike,
    order: int | None = None,
) -> np.ndarray:
    """Amplitude-modulated PRBS on the grid ``t = k / fs``.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].
    low, high : float
        Range the levels are drawn from, uniformly (e.g. current [A]).
    min_hold : float
        Shortest time a level is held [s]: the clock period of the underlying PRBS.
    seed : int or numpy.random.SeedSequence
        Seeds both the register state and the level draws.
    order : int, optional
        Register order of the underlying PRBS (default: covers the record without repeating).

    Returns
    -------
    ndarray
        The signal, one value per sample, every value within ``[low, high]``.

    Examples
    --------
    >>> i = aprbs(1000.0, 5.0, low=0.0, high=1.0, min_hold=0.2, seed=1)
    >>> bool(i.min() >= 0.0 and i.max() <= 1.0)
    True
    """
    n, fs = sample_grid(fs, duration)
    lo, hi = check_range("low/high", low, high, "unit of the signal")
    hold = hold_samples("min_hold", min_hold, fs)
    n_clocks = -(-n // hold)
    order = prbs_order_for(n_clocks) if order is None else order
    bits_seed, level_seed = child_seeds(seed, 2)
    bits = mls(order, seed=bits_seed, n_bits=n_clocks)
    starts = run_starts(bits)
    levels = np.random.default_rng(level_seed).uniform(lo, hi, size=starts.size)
    run_id = np.cumsum(np.concatenate(([0], (bits[1:] != bits[:-1]).astype(np.int64))))
    return np.repeat(levels[run_id], hold)[:n]
