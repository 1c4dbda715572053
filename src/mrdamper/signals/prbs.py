"""Pseudo-random binary sequences (PRBS) from maximum-length linear-feedback shift registers.

A register of order n with a primitive feedback polynomial cycles through all 2**n - 1 non-zero
states, so its output bit sequence (an m-sequence) has period N = 2**n - 1, contains 2**(n-1) ones
and 2**(n-1) - 1 zeros, has 2**(n-1) runs of which half have length 1, a quarter length 2, ...,
and, mapped to +-1, a two-valued circular autocorrelation: 1 at lag 0 and -1/N at every other lag.
"""

from __future__ import annotations

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.signals._signal_kernels import lfsr_bits
from mrdamper.signals.common import SeedLike, as_rng, hold_samples, sample_grid

__all__ = ["PRIMITIVE_TAPS", "mls", "prbs", "prbs_order_for"]

#: Taps of one primitive feedback polynomial per register order n: ``(n, a, b, ...)`` stands for
#: x**n + x**a + x**b + ... + 1 over GF(2). Every entry is checked for primitivity (and the short
#: ones for their full period) in the test suite.
PRIMITIVE_TAPS: dict[int, tuple[int, ...]] = {
    2: (2, 1),
    3: (3, 2),
    4: (4, 3),
    5: (5, 3),
    6: (6, 5),
    7: (7, 6),
    8: (8, 6, 5, 4),
    9: (9, 5),
    10: (10, 7),
    11: (11, 9),
    12: (12, 6, 4, 1),
    13: (13, 4, 3, 1),
    14: (14, 5, 3, 1),
    15: (15, 14),
    16: (16, 15, 13, 4),
    17: (17, 14),
    18: (18, 11),
    19: (19, 6, 2, 1),
    20: (20, 17),
    21: (21, 19),
    22: (22, 21),
    23: (23, 18),
    24: (24, 23, 22, 17),
    25: (25, 22),
    26: (26, 6, 2, 1),
    27: (27, 5, 2, 1),
    28: (28, 25),
    29: (29, 27),
    30: (30, 6, 4, 1),
    31: (31, 28),
    32: (32, 22, 2, 1),
}


def _check_order(order: int) -> int:
    if (
        isinstance(order, bool)
        or not isinstance(order, (int, np.integer))
        or order not in PRIMITIVE_TAPS
    ):
        raise DataValidationError(
            "order", f"expected an int register order in 2..32, got {order!r}"
        )
    return int(order)


def mls(order: int, *, seed: SeedLike, n_bits: int | None = None) -> np.ndarray:
    """Maximum-length sequence (m-sequence) of a register of ``order`` bits.

    Parameters
    ----------
    order : int
        Register order n, 2..32. The period is ``2**n - 1`` bits.
    seed : int or numpy.random.SeedSequence
        Chooses the non-zero initial register state (a cyclic shift of the sequence).
    n_bits : int, optional
        Number of bits to return; default one period ``2**n - 1``.

    Returns
    -------
    ndarray of uint8
        Bits 0 / 1.

    Examples
    --------
    >>> b = mls(5, seed=0)
    >>> b.size, int(b.sum())
    (31, 16)
    """
    order = _check_order(order)
    period = (1 << order) - 1
    if n_bits is None:
        n_bits = period
    if isinstance(n_bits, bool) or not isinstance(n_bits, (int, np.integer)) or n_bits < 1:
        raise DataValidationError("n_bits", f"expected a positive int, got {n_bits!r}")
    taps = PRIMITIVE_TAPS[order]
    shifts = np.array([order - t for t in taps], dtype=np.int64)
    state = int(as_rng(seed).integers(1, period + 1))
    return lfsr_bits(order, shifts, state, int(n_bits))


def prbs_order_for(n_clocks: int) -> int:
    """Smallest register order whose period ``2**n - 1`` is at least ``n_clocks`` (min 2)."""
    if n_clocks < 1:
        raise DataValidationError("n_clocks", f"expected >= 1, got {n_clocks}")
    order = max(2, int(np.ceil(np.log2(n_clocks + 1))))
    if order > 32:
        raise DataValidationError(
            "clock_period", f"{n_clocks} clock periods need a register longer than 32 bits"
        )
    return order


def prbs(
    fs: float,
    duration: float,
    *,
    clock_period: float,
    seed: SeedLike,
    levels: tuple[float, float] = (0.0, 1.0),
    order: int | None = None,
) -> np.ndarray:
    """Two-level pseudo-random binary sequence on the grid ``t = k / fs``.

    Each bit of an m-sequence is held for one clock period; bit 0 maps to ``levels[0]`` and bit 1
    to ``levels[1]``.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s]; the signal has ``round(duration * fs)`` samples.
    clock_period : float
        Time each bit is held [s]; rounded to a whole number of samples (at least one).
    seed : int or numpy.random.SeedSequence
        Initial register state.
    levels : (float, float)
        Values for bit 0 and bit 1, in the unit of the quantity (e.g. [A]).
    order : int, optional
        Register order 2..32. Default: the smallest order whose period covers the record, so
        the sequence does not repeat within it.

    Returns
    -------
    ndarray
        The signal, one value per sample.

    Examples
    --------
    >>> i = prbs(1000.0, 2.0, clock_period=0.05, levels=(0.0, 1.0), seed=3)
    >>> i.shape, sorted(set(i.tolist()))
    ((2000,), [0.0, 1.0])
    """
    n, fs = sample_grid(fs, duration)
    hold = hold_samples("clock_period", clock_period, fs)
    lo, hi = (float(levels[0]), float(levels[1]))
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo == hi:
        raise DataValidationError("levels", f"expected two different finite values, got {levels!r}")
    n_clocks = -(-n // hold)
    order = prbs_order_for(n_clocks) if order is None else _check_order(order)
    bits = mls(order, seed=seed, n_bits=n_clocks)
    return np.where(np.repeat(bits, hold)[:n] == 1, hi, lo)
