"""Numba kernels of the signal generators (plain arrays in, plain arrays out)."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["lfsr_bits"]


@numba.njit(cache=True)
def lfsr_bits(order: int, shifts: np.ndarray, state: int, n_bits: int) -> np.ndarray:
    """Output of a Fibonacci linear-feedback shift register.

    Parameters
    ----------
    order : int
        Register length n (2..32).
    shifts : ndarray of int64
        For each tap t of the feedback polynomial, the right shift ``n - t`` that brings bit t
        to position 0.
    state : int
        Initial register content, 1 .. 2**n - 1.
    n_bits : int
        Number of output bits.

    Returns
    -------
    ndarray of uint8
        The bits (0 or 1), the register's least significant bit before each shift.
    """
    out = np.empty(n_bits, dtype=np.uint8)
    s = np.int64(state)
    top = np.int64(order - 1)
    for k in range(n_bits):
        out[k] = s & 1
        fb = np.int64(0)
        for j in range(shifts.size):
            fb ^= (s >> shifts[j]) & 1
        s = (s >> 1) | (fb << top)
    return out
