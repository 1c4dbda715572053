"""Numba kernels of the virtual rig: discrete-time actuator and driver recursions."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["first_order_lag", "second_order_track"]


@numba.njit(cache=True)
def second_order_track(
    command: np.ndarray, phi: np.ndarray, gamma: np.ndarray, x0: float, v0: float
) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold recursion of a second-order servo loop.

    State ``s = [x, v]``; ``s[k+1] = phi @ s[k] + gamma * command[k]``.

    Parameters
    ----------
    command : ndarray
        Position command per sample [m].
    phi : ndarray, shape (2, 2)
        State transition matrix over one sampling interval.
    gamma : ndarray, shape (2,)
        Input vector over one sampling interval.
    x0, v0 : float
        Initial position [m] and velocity [m/s].

    Returns
    -------
    x, v : ndarray
        Position [m] and velocity [m/s] at each sample.
    """
    n = command.size
    x = np.empty(n)
    v = np.empty(n)
    a, b, c, d = phi[0, 0], phi[0, 1], phi[1, 0], phi[1, 1]
    g0, g1 = gamma[0], gamma[1]
    xk, vk = x0, v0
    for k in range(n):
        x[k] = xk
        v[k] = vk
        u = command[k]
        xk, vk = a * xk + b * vk + g0 * u, c * xk + d * vk + g1 * u
    return x, v


@numba.njit(cache=True)
def first_order_lag(command: np.ndarray, alpha: float, y0: float) -> np.ndarray:
    """``y[k+1] = alpha * y[k] + (1 - alpha) * command[k]`` with ``y[0] = y0``.

    With ``0 <= alpha < 1`` every output lies between the extremes of ``y0`` and the command.
    """
    n = command.size
    y = np.empty(n)
    yk = y0
    beta = 1.0 - alpha
    for k in range(n):
        y[k] = yk
        yk = alpha * yk + beta * command[k]
    return y
