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

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models._arrays import readonly
from mrdamper.models._lag import lag_step
from mrdamper.models.step import STATUS_OK, Step

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.models.protocols import StaticMapForm

#: Argument types of the kernels (numba types the values passed; these are for mypy).
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

__all__ = [
    "COMPONENTS",
    "N_COMPONENTS",
    "StaticStepForm",
    "make_static_step",
    "sp_dforce1",
    "sp_force",
    "sp_force1",
    "sp_force_jacobian",
    "step_advance",
    "step_force",
]

#: Number of components of the SP map (A, a, b, c, d).
N_COMPONENTS = 5
#: Names of the five components of the SP map, in kernel order.
COMPONENTS = ("A", "a", "b", "c", "d")


@njit(cache=True)
def _ipow(x: float, n: int) -> float:
    """``x ** n`` for an integer ``n >= 0`` by repeated multiplication (the C export does the
    same; equal to numba's ``x ** n`` for ``n <= 3``)."""
    r = 1.0
    for _ in range(n):
        r *= x
    return r


@njit(cache=True)
def sp_force1(
    x: float,
    v: float,
    i: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
) -> float:
    """One sample of the map ``A(i) tanh(a(i) v + b(i) x) + c(i) v + d(i) x + f0`` [N].

    The one definition of the SP static map: the fused kernel, the per-sample step, the inverse
    and the quarter car evaluate it. Component ``comp[k]`` (0 = A, 1 = a, 2 = b, 3 = c, 4 = d)
    gains ``theta[k] * i**power[k]``.
    """
    A = 0.0
    a = 0.0
    b = 0.0
    c = 0.0
    d = 0.0
    for k in range(theta.size):
        term = theta[k] * _ipow(i, power[k])
        m = comp[k]
        if m == 0:
            A += term
        elif m == 1:
            a += term
        elif m == 2:
            b += term
        elif m == 3:
            c += term
        else:
            d += term
    F: float = A * np.tanh(a * v + b * x) + c * v + d * x + f0
    return F


@njit(cache=True)
def sp_dforce1(
    x: float, v: float, i: float, comp: IntArray, power: IntArray, theta: FloatArray
) -> float:
    """``dF/di`` of :func:`sp_force1` at one sample [N per input unit]."""
    A = 0.0
    a = 0.0
    b = 0.0
    dA = 0.0
    da = 0.0
    db = 0.0
    dc = 0.0
    dd = 0.0
    for k in range(theta.size):
        pw = power[k]
        term = theta[k] * _ipow(i, pw)
        dterm = pw * theta[k] * _ipow(i, pw - 1) if pw > 0 else 0.0
        m = comp[k]
        if m == 0:
            A += term
            dA += dterm
        elif m == 1:
            a += term
            da += dterm
        elif m == 2:
            b += term
            db += dterm
        elif m == 3:
            dc += dterm
        else:
            dd += dterm
    th = np.tanh(a * v + b * x)
    dF: float = dA * th + A * (1.0 - th * th) * (da * v + db * x) + dc * v + dd * x
    return dF


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
    for s in range(n):
        F[s] = sp_force1(x[s], v[s], i[s], comp, power, theta, f0)
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


# ----------------------------------------------------------------------------- per-sample step
class StaticStepForm(NamedTuple):
    """A static map (SP-1..SP-4, Bingham) as its per-sample step reads it.

    Attributes
    ----------
    comp, power : ndarray of int64
        Component index (0..4) and input exponent of each coefficient (see :func:`sp_force1`).
    theta : ndarray
        Coefficients (SI).
    f0 : float
        Force offset [N].
    eta : float
        Drive-lag rate [1/s] between the electrical input and the map's input ``rho``; negative:
        no lag (the map sees the input itself).
    """

    comp: IntArray
    power: IntArray
    theta: FloatArray
    f0: float
    eta: float


@njit(cache=True)
def step_force(form: StaticStepForm, s: FloatArray, x: float, v: float, e: float) -> float:
    """Force [N] of the map at the present motion; the input is ``e``, or the lag state ``s[0]``."""
    r = s[0] if form.eta >= 0.0 else e
    F: float = sp_force1(x, v, r, form.comp, form.power, form.theta, form.f0)
    return F


@njit(cache=True)
def step_advance(
    form: StaticStepForm,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """The drive lag over one interval of ``dt`` [s] (the command ``e0`` held); without a lag
    the state follows the input (``s[0] = e1``)."""
    if form.eta >= 0.0:
        s[0] = lag_step(s[0], e0, math.exp(-form.eta * dt))
    else:
        s[0] = e1
    return STATUS_OK


def make_static_step(kind: str, form: StaticMapForm) -> Step:
    """The per-sample step of a static map given as a :class:`StaticMapForm`.

    The state is the map's input ``rho`` (the lagged input with a drive lag, else the input
    itself), at rest the first input. Any interval is allowed (``dt`` None); the force depends on
    the present input unless a drive lag sits between them (``feedthrough``).
    """
    sform = StaticStepForm(
        np.ascontiguousarray(form.comp, dtype=np.int64),
        np.ascontiguousarray(form.power, dtype=np.int64),
        np.ascontiguousarray(form.theta, dtype=np.float64),
        float(form.f0),
        -1.0 if form.eta is None else float(form.eta),
    )

    def initial_state(x0: float, v0: float, e0: float) -> FloatArray:
        return np.array([e0])

    return Step(kind, sform, step_force, step_advance, initial_state, feedthrough=form.eta is None)
