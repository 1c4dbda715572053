"""Compiled kernels of the one-state hysteresis families (private): hyperbolic tangent (Kwok et
al. 2006), classic Bouc-Wen, modified Dahl (Zhou et al. 2006) and LuGre (Jiménez and
Álvarez-Icaza 2005).

The four families share one state layout ``s = (z, u)`` and one integrator, so the integrator,
the free run and the per-sample step are written once here and the family only chooses the
equations (a branch on the ``family`` code). ``z`` is the family's evolutionary
(bristle, Dahl, Bouc-Wen) variable, unused by the static ``tanh`` family; ``u`` is the electrical
input after the optional first-order drive lag ``du/dt = -eta (u - e)``. With ``eta = 0`` there
is no lag: the laws read the record's input ``e`` itself (linear within an interval) and ``u``
follows it.

Every parameter vector ``p`` starts with ``(eta, f0)``; the family's own parameters follow in the
order of :data:`PARAM_NAMES`. The input-dependent laws are linear in ``u`` (``a + b u``).
Records are sampled; within an interval the inputs are linear and it is integrated with ``nsub``
classical Runge-Kutta (RK4) sub-steps (:func:`auto_substeps` chooses them).

Status codes: 0 ok, 1 the state became non-finite or left its bound.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models._boucwen import boucwen_rate, sign
from mrdamper.models._interval import allowed_interval
from mrdamper.models._substeps import (
    MAX_AUTO_SUBSTEPS,
    SUBSTEP_RATE_PRODUCT,
    interval_substeps,
    substeps_for_rate,
)

__all__ = [
    "BOUCWEN",
    "DAHL",
    "FAMILIES",
    "LUGRE",
    "MAX_AUTO_SUBSTEPS",
    "PARAM_NAMES",
    "STATUS_DIVERGED",
    "STATUS_OK",
    "SUBSTEP_RATE_PRODUCT",
    "TANH",
    "HysteresisForm",
    "auto_substeps",
    "inverse_run",
    "inverse_step",
    "simulate",
    "step_advance",
    "step_force",
]

FloatArray = npt.NDArray[np.float64]

TANH, BOUCWEN, DAHL, LUGRE = 0, 1, 2, 3
#: family name -> code of the compiled branch.
FAMILIES: dict[str, int] = {"tanh": TANH, "boucwen": BOUCWEN, "dahl": DAHL, "lugre": LUGRE}

#: Parameter order of ``p`` per family (SI; see the family modules for the units).
PARAM_NAMES: dict[str, tuple[str, ...]] = {
    "tanh": ("eta", "f0", "ca", "cb", "k", "alpha_a", "alpha_b", "beta", "delta"),
    "boucwen": (
        "eta",
        "f0",
        "c0a",
        "c0b",
        "k0",
        "alpha_a",
        "alpha_b",
        "gamma",
        "beta",
        "A",
        "n",
    ),
    "dahl": ("eta", "f0", "c0a", "c0b", "k0", "Fda", "Fdb", "sigma"),
    "lugre": ("eta", "f0", "sigma_a", "sigma_0", "sigma_1", "sigma_2", "sigma_b", "a0"),
}

STATUS_OK = 0
STATUS_DIVERGED = 1
#: |z| beyond this bound counts as divergence (every family keeps z far below it).
Z_LIMIT = 1.0e6

ETA, F0 = 0, 1


@njit(cache=True)
def _zdot(fam: int, p: FloatArray, v: float, z: float) -> float:
    """dz/dt of the family's evolutionary variable at velocity ``v`` [m/s]."""
    if fam == BOUCWEN:
        return boucwen_rate(v, z, p[7], p[8], p[9], p[10])
    if fam == DAHL:
        dahl: float = p[7] * (v - abs(v) * z)
        return dahl
    if fam == LUGRE:
        lugre: float = v - p[3] * p[7] * abs(v) * z
        return lugre
    return 0.0


@njit(cache=True)
def _force(fam: int, p: FloatArray, x: float, v: float, z: float, u: float) -> float:
    """Force [N] at displacement ``x`` [m], velocity ``v`` [m/s], state ``z`` and input ``u``."""
    if fam == TANH:
        c = p[2] + p[3] * u
        al = p[5] + p[6] * u
        f_tanh: float = c * v + p[4] * x + al * math.tanh(p[7] * v + p[8] * sign(x)) + p[F0]
        return f_tanh
    if fam == LUGRE:
        zd = _zdot(fam, p, v, z)
        f_lugre: float = (p[2] + p[3] * u) * z + p[4] * zd + (p[5] + p[6] * u) * v + p[F0]
        return f_lugre
    # Bouc-Wen and Dahl: c0(u) v + k0 x + a(u) z + f0
    f_bw: float = (p[2] + p[3] * u) * v + p[4] * x + (p[5] + p[6] * u) * z + p[F0]
    return f_bw


@njit(cache=True)
def _interval(
    fam: int,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
    p: FloatArray,
    nsub: int,
) -> int:
    """Integrate ``s = (z, u)`` in place over one interval of ``dt`` [s] (inputs linear in
    between, ``nsub`` RK4 sub-steps); returns a status code."""
    z, u = s[0], s[1]
    eta = p[ETA]
    hf = 1.0 / nsub
    h = dt * hf
    dv = v1 - v0
    de = e1 - e0
    if fam != TANH:
        for j in range(nsub):
            t0 = j * hf
            va = v0 + t0 * dv
            vm = va + 0.5 * hf * dv
            vb = va + hf * dv
            k1 = _zdot(fam, p, va, z)
            k2 = _zdot(fam, p, vm, z + 0.5 * h * k1)
            k3 = _zdot(fam, p, vm, z + 0.5 * h * k2)
            k4 = _zdot(fam, p, vb, z + h * k3)
            z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    if eta > 0.0:
        # the lag does not depend on z: its own RK4 sub-steps on the linear input
        for j in range(nsub):
            t0 = j * hf
            ea = e0 + t0 * de
            em = ea + 0.5 * hf * de
            eb = ea + hf * de
            g1 = -eta * (u - ea)
            g2 = -eta * (u + 0.5 * h * g1 - em)
            g3 = -eta * (u + 0.5 * h * g2 - em)
            g4 = -eta * (u + h * g3 - eb)
            u += h / 6.0 * (g1 + 2.0 * g2 + 2.0 * g3 + g4)
    else:
        u = e1
    s[0], s[1] = z, u
    if not (np.isfinite(z) and np.isfinite(u)) or abs(z) > Z_LIMIT:
        return STATUS_DIVERGED
    return STATUS_OK


@njit(cache=True)
def simulate(
    fam: int,
    x: FloatArray,
    v: FloatArray,
    e: FloatArray,
    dt: float,
    p: FloatArray,
    nsub: int,
) -> tuple[FloatArray, int, int]:
    """Free-run force of one record from rest (``z = 0``, ``u = e[0]``).

    Parameters
    ----------
    fam : int
        Family code (:data:`FAMILIES`).
    x, v, e : ndarray
        Displacement [m], velocity [m/s], electrical input [A] or [V], one value a sample.
    dt : float
        Sampling interval [s].
    p : ndarray
        Parameters in the family's :data:`PARAM_NAMES` order (SI).
    nsub : int
        RK4 sub-steps per sampling interval.

    Returns
    -------
    F : ndarray
        Force [N] (valid before the failing sample when status != 0).
    status, sample : int
        Status code and first failing sample (-1 when ok).
    """
    n = x.size
    F = np.zeros(n)
    s = np.array([0.0, e[0]])
    for k in range(n):
        F[k] = _force(fam, p, x[k], v[k], s[0], s[1])
        if k == n - 1:
            break
        status = _interval(fam, s, x[k], v[k], e[k], x[k + 1], v[k + 1], e[k + 1], dt, p, nsub)
        if status != STATUS_OK:
            return F, status, k + 1
    return F, STATUS_OK, -1


class HysteresisForm(NamedTuple):
    """One of the four families as the per-sample step reads it.

    Attributes
    ----------
    family : int
        Family code (:data:`FAMILIES`).
    p : ndarray
        Parameters in the family's :data:`PARAM_NAMES` order (SI).
    max_h : float
        Largest RK4 sub-step [s]; an interval of ``dt`` takes ``ceil(dt / max_h)`` sub-steps.
    """

    family: int
    p: FloatArray
    max_h: float


@njit(cache=True)
def step_force(form: HysteresisForm, s: FloatArray, x: float, v: float, e: float) -> float:
    """Force [N] at the state ``s = (z, u)`` and the present motion (see :mod:`..step`)."""
    u = s[1] if form.p[ETA] > 0.0 else e
    return _force(form.family, form.p, x, v, s[0], u)


@njit(cache=True)
def step_advance(
    form: HysteresisForm,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """Advance ``s`` over one interval of ``dt`` [s] (RK4, inputs linear in between)."""
    nsub = interval_substeps(dt, form.max_h)
    return _interval(form.family, s, x0, v0, e0, x1, v1, e1, dt, form.p, nsub)


# ----------------------------------------------------------------------------- inverse
@njit(cache=True)
def inverse_step(
    form: HysteresisForm,
    s: FloatArray,
    x: float,
    v: float,
    F_desired: float,
    lo: float,
    hi: float,
    prev: float,
    lam2: float,
) -> tuple[float, bool]:
    """The input ``u`` in ``[lo, hi]`` closest to ``F_desired`` at the state ``s``, in closed form.

    The force of every family is affine in the input ``u`` its laws read (``a + b u``) at a given
    evolutionary state ``z`` and motion: without a drive lag ``u`` is the present input, with one
    the lagged input. So with ``F(u) = _force(z, u)``, ``F(u) = F(lo) + g (u - lo)`` with
    ``g = (F(hi) - F(lo)) / (hi - lo)``, and the minimiser of
    ``(F(u) - F_desired)^2 + lam2 (u - prev)^2`` over ``[lo, hi]`` is the unconstrained one,
    ``lo + (g (F_desired - F(lo)) + lam2 (prev - lo)) / (g^2 + lam2)``, clipped (the objective is a
    convex quadratic). ``lam2 = 0`` gives the exact solution of ``F(u) = F_desired`` where it is in
    reach; without authority (``g = 0``) and regularisation the input is ``lo``.

    Parameters
    ----------
    form : HysteresisForm
        The step's form.
    s : ndarray
        State ``(z, u)`` at the present sample (only ``z`` is read; not changed).
    x, v : float
        Displacement [m] and velocity [m/s] at the present sample.
    F_desired : float
        Desired force [N].
    lo, hi : float
        Admissible interval of ``u`` [A] or [V].
    prev : float
        Input the regularisation pulls towards (the previous one) [A] or [V].
    lam2 : float
        Squared regularisation weight [N^2 per input unit^2].

    Returns
    -------
    u : float
        The input [A] or [V].
    saturated : bool
        True when no input in ``[lo, hi]`` gives ``F_desired`` (to rounding).
    """
    f_lo = _force(form.family, form.p, x, v, s[0], lo)
    if not hi > lo:
        return lo, abs(f_lo - F_desired) > 1e-12 * (abs(f_lo) + abs(F_desired))
    f_hi = _force(form.family, form.p, x, v, s[0], hi)
    g = (f_hi - f_lo) / (hi - lo)
    den = g * g + lam2
    e = lo if den == 0.0 else lo + (g * (F_desired - f_lo) + lam2 * (prev - lo)) / den
    e = min(max(e, lo), hi)
    slack = 1e-12 * (abs(f_lo) + abs(f_hi) + abs(F_desired))
    reach = min(f_lo, f_hi) - slack <= F_desired <= max(f_lo, f_hi) + slack
    return e, not reach


@njit(cache=True)
def inverse_run(
    form: HysteresisForm,
    x: FloatArray,
    v: FloatArray,
    F_desired: FloatArray,
    dt: float,
    lo: float,
    hi: float,
    lam2: float,
    max_change: float,
) -> tuple[FloatArray, npt.NDArray[np.bool_], int, int]:
    """Causal inverse along a record: :func:`inverse_step` at every sample, the state advanced by
    :func:`step_advance` with the motion and the input found (held over the interval).

    ``z`` depends on the motion only, so the inverse solves for the input the laws read, ``u``.
    Without a drive lag that is the input itself. With one (``eta > 0``) it is the lagged input,
    which a command held over each interval within ``[lo, hi]`` moves as
    ``u[k] = c u[k-1] + (1 - c) w[k-1]``, ``c = exp(-eta dt)``: from the third sample on ``u[k]``
    is confined to ``[c u[k-1] + (1 - c) lo, c u[k-1] + (1 - c) hi]``, and the lag starts at rest,
    ``u[1] = u[0]`` (the command is the lead filter of ``u``,
    :func:`mrdamper.control.inverse.current.driver_command`).

    The input at sample ``k`` is confined to ``[lo, hi]`` and, from the second sample on, to
    ``max_change`` of the previous input; the regularisation pulls towards the previous input
    (towards ``lo`` at the first sample). The state starts at rest, ``(0, u[0])``.

    Returns
    -------
    u : ndarray
        Input [A] or [V] at every sample (with a drive lag: the lagged input).
    saturated : ndarray of bool
        Samples where no admissible input gives the desired force.
    status, sample : int
        Status of the step (0 ok) and the first failing sample (-1 when ok).
    """
    n = x.size
    e = np.zeros(n)
    sat = np.zeros(n, dtype=np.bool_)
    s = np.zeros(2)
    prev = lo
    eta = form.p[ETA]
    c = math.exp(-eta * dt)
    lag = c if eta > 0.0 else -1.0
    for k in range(n):
        a, b = allowed_interval(k, lo, hi, lag, prev, prev, max_change)
        e[k], sat[k] = inverse_step(form, s, x[k], v[k], F_desired[k], a, b, prev, lam2)
        prev = e[k]
        if k == n - 1:
            break
        s[1] = e[k]  # with a lag only z is read: u is the one chosen
        status = step_advance(form, s, x[k], v[k], e[k], x[k + 1], v[k + 1], e[k], dt)
        if status != STATUS_OK:
            return e, sat, status, k + 1
    return e, sat, STATUS_OK, -1


# ----------------------------------------------------------------------------- step size


def fastest_rate(family: str, p: np.ndarray, vmax: float) -> float:
    """Upper estimate of the fastest rate of the state equations [1/s] at speeds up to ``vmax``.

    Parameters
    ----------
    family : str
        Family name.
    p : ndarray
        Parameters in the family's :data:`PARAM_NAMES` order.
    vmax : float
        Largest absolute velocity [m/s].
    """
    rate = abs(float(p[ETA]))
    if family == "dahl":
        rate += abs(float(p[7])) * vmax
    elif family == "lugre":
        rate += abs(float(p[3] * p[7])) * vmax
    elif family == "boucwen":
        gamma, beta, A, n = (float(a) for a in p[7:11])
        shape = beta + gamma
        zmax = (abs(A) / shape) ** (1.0 / n) if shape > 0.0 and A != 0.0 else 1.0
        rate += n * (abs(beta) + abs(gamma)) * zmax ** (n - 1.0) * vmax
    return rate


def auto_substeps(family: str, p: np.ndarray, dt: float, vmax: float) -> int:
    """RK4 sub-steps per sampling interval of ``dt`` [s]: the product of the sub-step and
    :func:`fastest_rate` stays at most :data:`SUBSTEP_RATE_PRODUCT` (at most
    :data:`MAX_AUTO_SUBSTEPS`)."""
    rate = fastest_rate(family, p, vmax)
    return substeps_for_rate(dt, rate)
