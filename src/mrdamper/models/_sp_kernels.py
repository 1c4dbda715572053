"""Compiled kernels of the semi-phenomenological (SP-k) force maps, on plain arrays.

Every SP variant is one static map

``F = A(i) * tanh(a(i) * v + b(i) * x) + c(i) * v + d(i) * x + f0``

where each of the five components ``A, a, b, c, d`` is a polynomial in the electrical input ``i``.
A model is described by two integer arrays over its coefficients ``theta``: ``comp[k]`` (0 = A,
1 = a, 2 = b, 3 = c, 4 = d) and ``power[k]`` (exponent of ``i``), so that component ``m`` equals
``sum(theta[k] * i**power[k] for k with comp[k] == m)``. The kernels evaluate the force and its
analytic Jacobian with respect to ``theta`` (and ``f0``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mrdamper.models._arrays import readonly

__all__ = ["COMPONENTS", "N_COMPONENTS", "sp_force", "sp_force_jacobian"]

#: Number of components of the SP map (A, a, b, c, d).
N_COMPONENTS = 5
#: Names of the five components of the SP map, in kernel order.
COMPONENTS = ("A", "a", "b", "c", "d")


@njit(cache=True)
def _components(
    ii: float, comp: np.ndarray, power: np.ndarray, theta: np.ndarray, out: np.ndarray
) -> None:
    for m in range(N_COMPONENTS):
        out[m] = 0.0
    for k in range(theta.size):
        out[comp[k]] += theta[k] * ii ** power[k]


def sp_force(
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    theta: np.ndarray,
    f0: float,
) -> np.ndarray:
    """Evaluate the SP force map sample by sample (see :func:`_sp_force`; arrays are passed
    read-only so the kernel has one signature)."""
    return _sp_force(*_args(x, v, i, comp, power, theta), float(f0))


def sp_force_jacobian(
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    theta: np.ndarray,
    f0: float,
    with_offset: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Force map and its analytic Jacobian (see :func:`_sp_force_jacobian`)."""
    return _sp_force_jacobian(*_args(x, v, i, comp, power, theta), float(f0), bool(with_offset))


def _args(
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    theta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Read-only float64 views of ``x, v, i, theta`` and int64 views of ``comp, power``."""
    f, n = np.float64, np.int64
    return (
        readonly(x, f),
        readonly(v, f),
        readonly(i, f),
        readonly(comp, n),
        readonly(power, n),
        readonly(theta, f),
    )


@njit(cache=True)
def _sp_force(
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    theta: np.ndarray,
    f0: float,
) -> np.ndarray:
    """Evaluate the SP force map sample by sample.

    Parameters
    ----------
    x, v, i : ndarray
        Displacement [m], velocity [m/s] and electrical input [A or V] (same length).
    comp, power : ndarray of int64
        Component index and exponent of ``i`` of each coefficient.
    theta : ndarray
        Coefficients (units follow the component and exponent).
    f0 : float
        Force offset [N].

    Returns
    -------
    ndarray
        Force [N].
    """
    n = x.size
    F = np.empty(n)
    C = np.empty(N_COMPONENTS)
    for s in range(n):
        _components(i[s], comp, power, theta, C)
        F[s] = C[0] * np.tanh(C[1] * v[s] + C[2] * x[s]) + C[3] * v[s] + C[4] * x[s] + f0
    return F


@njit(cache=True)
def _sp_force_jacobian(
    x: np.ndarray,
    v: np.ndarray,
    i: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    theta: np.ndarray,
    f0: float,
    with_offset: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Force map and its analytic Jacobian with respect to ``theta`` (then ``f0``).

    Returns
    -------
    F : ndarray, shape (n,)
        Force [N].
    J : ndarray, shape (n, theta.size + with_offset)
        ``dF / dtheta_k``; the last column is ``dF / df0 = 1`` when ``with_offset``.
    """
    n = x.size
    p = theta.size
    F = np.empty(n)
    J = np.empty((n, p + (1 if with_offset else 0)))
    C = np.empty(N_COMPONENTS)
    for s in range(n):
        ii = i[s]
        _components(ii, comp, power, theta, C)
        th = np.tanh(C[1] * v[s] + C[2] * x[s])
        sech2 = 1.0 - th * th
        F[s] = C[0] * th + C[3] * v[s] + C[4] * x[s] + f0
        for k in range(p):
            ip = ii ** power[k]
            m = comp[k]
            if m == 0:
                J[s, k] = th * ip
            elif m == 1:
                J[s, k] = C[0] * sech2 * v[s] * ip
            elif m == 2:
                J[s, k] = C[0] * sech2 * x[s] * ip
            elif m == 3:
                J[s, k] = v[s] * ip
            else:
                J[s, k] = x[s] * ip
        if with_offset:
            J[s, p] = 1.0
    return F, J
