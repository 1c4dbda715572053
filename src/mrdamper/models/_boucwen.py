"""The Bouc-Wen evolution law, compiled once for every family that has it (private).

``dz/dt = -gamma |w| sign(z) |z|^n - beta w |z|^n + A w`` with ``w`` the relative velocity that
drives the evolutionary variable ``z`` [m/s]: the Spencer model (``w`` the velocity across its
Bouc-Wen element) and the classic Bouc-Wen family (``w`` the damper velocity) both call
:func:`boucwen_rate`; Spencer's sensitivities read :func:`powers` too. The C renderers write the
same arithmetic (``exp((n - 1) log|z|) |z|``, ``|z| |z|`` when ``n == 2``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["boucwen_rate", "powers", "sign"]


@njit(cache=True)
def sign(a: float) -> float:
    """-1, 0 or 1 by the sign of ``a``."""
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    return 0.0


@njit(cache=True)
def powers(z: float, n: float) -> tuple[float, float, float]:
    """Return (|z|**n, |z|**(n-1), log|z|), with the z == 0 values (0, 0, 0)."""
    az = abs(z)
    if az > 0.0:
        if n == 2.0:  # the common case, without transcendental functions
            return az * az, az, 0.0
        lz = np.log(az)
        zn1 = np.exp((n - 1.0) * lz)
        return zn1 * az, zn1, lz
    return 0.0, 0.0, 0.0


@njit(cache=True)
def boucwen_rate(w: float, z: float, gamma: float, beta: float, A: float, n: float) -> float:
    """dz/dt of the Bouc-Wen variable ``z`` driven by the velocity ``w`` [m/s]."""
    zn, _, _ = powers(z, n)
    rate: float = -gamma * abs(w) * sign(z) * zn - beta * w * zn + A * w
    return rate
