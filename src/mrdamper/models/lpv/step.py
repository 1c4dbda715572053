"""The per-sample step of the LPV input-output model (and of the LTI model), on plain values.

One sample of the model of :mod:`mrdamper.models.lpv`, written once: every tool that steps an LPV
model (its per-sample step :func:`step_force` / :func:`step_advance`, the causal inverse and the
quarter car of :mod:`mrdamper.control`) calls these functions. The fused free-run kernels of
:mod:`mrdamper.models.lpv.kernels` are a fast path tested against this step sample by sample.

* the force is ``F[k] = y[k] + F0 + k_x x[k]``: the filtered output, the offset and the parallel
  stiffness ``k_x`` [N/m] (0 for the paper's structure), which does not enter the recursion;
* :func:`lpv_coefficients`: the force at sample ``k`` (without ``k_x x``) as a polynomial in the
  present scheduling value ``rho[k]`` once the past outputs and inputs are fixed (``b_0 = 0``)::

      F(rho) = F0 + sum_p c_p rho^p,   c_p = sum_j beta[j-1, p] u[k-j] - alpha[j-1, p] y[k-j]

* :func:`poly` / :func:`dpoly`: that polynomial and its derivative (Horner);
* :func:`zone_input`: the LPV input ``u`` [m/s] from ``(v, rho)`` and the zone laws (eqs. 19-22),
  static or with the Dahl state ``z`` of the hysteretic input (:mod:`mrdamper.analysis.hysteretic`);
* :func:`lag_step`: one sample of the drive lag ``d rho/dt = -eta (rho - w)`` (exact zero-order
  hold, ``E = exp(-eta dt)``).

The step's state is ``s = [rho, z, y[k-n_m] .. y[k-1], u[k-n_m] .. u[k-1]]`` (the lagged input,
used only with a drive lag; the Dahl state, used only by the hysteretic input; past outputs and
inputs, oldest first), all zero at rest except ``rho = e[0]``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.analysis.hysteretic import dahl_step
from mrdamper.models._lag import lag_step
from mrdamper.models.step import STATUS_DIVERGED, STATUS_OK, Step

__all__ = [
    "MODE_CONTINUOUS",
    "MODE_LITERAL",
    "MODE_V",
    "LPVForm",
    "dpoly",
    "lag_step",
    "lpv_coefficients",
    "make_step",
    "poly",
    "step_advance",
    "step_force",
    "zone_input",
]

#: LPV input modes: u = v, continuous reading of eq. 22, literal reading.
MODE_V, MODE_CONTINUOUS, MODE_LITERAL = 0, 1, 2
#: State entries before the past outputs: the lagged input ``rho`` and the Dahl state ``z``.
N_HEAD = 2

FloatArray = npt.NDArray[np.float64]


@njit(cache=True)
def poly(c: FloatArray, r: float) -> float:  # pragma: no cover - numba
    """``sum_p c[p] r^p`` (Horner)."""
    acc = 0.0
    for p in range(c.size - 1, -1, -1):
        acc = acc * r + c[p]
    return acc


@njit(cache=True)
def dpoly(c: FloatArray, r: float) -> float:  # pragma: no cover - numba
    """Derivative of :func:`poly` with respect to ``r``."""
    acc = 0.0
    for p in range(c.size - 1, 0, -1):
        acc = acc * r + p * c[p]
    return acc


@njit(cache=True)
def lpv_coefficients(
    cf: FloatArray,
    y: FloatArray,
    u: FloatArray,
    k: int,
    alpha: FloatArray,
    beta: FloatArray,
    offset: float,
) -> None:  # pragma: no cover - numba
    """Coefficients (in ``rho``) of the force at sample ``k`` given the past ``y``, ``u``.

    Written into ``cf`` (length ``n_rho + 1``); ``y[q]``, ``u[q]`` for ``q < 0`` count as zero.
    """
    n_m, n_p = alpha.shape
    for p in range(n_p):
        acc = 0.0
        for j in range(n_m):
            q = k - 1 - j
            if q >= 0:
                acc += beta[j, p] * u[q] - alpha[j, p] * y[q]
        cf[p] = acc
    cf[0] += offset


@njit(cache=True)
def zone_input(
    v: float,
    r: float,
    mode: int,
    gm: FloatArray,
    gc: FloatArray,
    mu_high: FloatArray,
    mu_low: FloatArray,
    z: float,
    blend: float,
) -> float:  # pragma: no cover - numba
    """LPV input ``u`` [m/s] from ``v`` and ``rho`` (zone laws, eqs. 19-22).

    With ``blend > 0`` (continuous reading only) the hysteretic input of
    :func:`mrdamper.analysis.hysteretic.hysteretic_input` with the Dahl state ``z`` [-];
    ``blend = 0`` is the static input.
    """
    if mode == MODE_V:
        return v
    hi: float = mu_high[0] * r + mu_high[1]
    lo: float = mu_low[0] * r + mu_low[1]
    m1 = poly(gm[0], r)
    m2 = poly(gm[1], r)
    m3 = poly(gm[2], r)
    if blend != 0.0:
        ratio = (m3 if v >= 0.0 else m1) / m2
        level = hi if z >= 0.0 else -lo
        pre = (1.0 - blend) * min(max(v, lo), hi) + blend * level * z
        return (1.0 - ratio) * pre + ratio * v
    if v < lo:
        if mode == MODE_CONTINUOUS:
            return lo + m1 / m2 * (v - lo)
        return (m1 * v + poly(gc[0], r)) / m2
    if v > hi:
        if mode == MODE_CONTINUOUS:
            return hi + m3 / m2 * (v - hi)
        return (m3 * v + poly(gc[2], r)) / m2
    return v


class LPVForm(NamedTuple):
    """The LPV (or LTI) model as its per-sample step reads it.

    Attributes
    ----------
    alpha, beta : ndarray, shape (n_m, n_rho + 1)
        Denominator / numerator coefficients, column ``p`` multiplying ``rho**p``.
    offset : float
        Output force offset ``F0`` [N].
    bound : float
        Largest accepted ``|y|`` [N] (divergence).
    eta : float
        Drive-lag rate [1/s]; negative: no lag (``rho`` is the electrical input).
    mode : int
        ``MODE_V`` (``u = v``), ``MODE_CONTINUOUS`` or ``MODE_LITERAL`` (reading of eq. 22).
    gamma_m, gamma_c : ndarray, shape (3, degree + 1)
        Zone-law slopes and intercepts (polynomials in ``rho``).
    mu_high, mu_low : ndarray, shape (2,)
        Breakpoint laws ``v_high = mu_high[0] rho + mu_high[1]`` (and ``v_low``) [m/s].
    blend : float
        Share of the Dahl state in the pre-yield input (0: static input).
    stroke : float
        Stroke scale of the Dahl state [m] (unused when ``blend = 0``).
    stiffness : float
        Parallel stiffness ``k_x`` [N/m]: the force is the filtered output plus ``F0 + k_x x``
        (0: none, the paper's structure).
    """

    alpha: FloatArray
    beta: FloatArray
    offset: float
    bound: float
    eta: float
    mode: int
    gamma_m: FloatArray
    gamma_c: FloatArray
    mu_high: FloatArray
    mu_low: FloatArray
    blend: float
    stroke: float
    stiffness: float


@njit(cache=True)
def _force(
    form: LPVForm, s: FloatArray, e: float
) -> tuple[float, float]:  # pragma: no cover - numba
    """Force [N] at the state ``s`` for the present input ``e``; also ``rho`` it used."""
    n_m, n_p = form.alpha.shape
    cf = np.empty(n_p)
    lpv_coefficients(
        cf, s[N_HEAD : N_HEAD + n_m], s[N_HEAD + n_m :], n_m, form.alpha, form.beta, form.offset
    )
    r: float = s[0] if form.eta >= 0.0 else e
    return poly(cf, r), r


@njit(cache=True)
def step_force(
    form: LPVForm, s: FloatArray, x: float, v: float, e: float
) -> float:  # pragma: no cover - numba
    """Force [N] at sample ``k`` (see :mod:`mrdamper.models.step`)."""
    F, _ = _force(form, s, e)
    return F + form.stiffness * x


@njit(cache=True)
def step_advance(  # pragma: no cover - numba
    form: LPVForm,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """Advance ``s`` from sample ``k`` to ``k + 1`` (``dt`` is the model's sample time)."""
    n_m = form.alpha.shape[0]
    F, r = _force(form, s, e0)
    y = F - form.offset
    if not (abs(y) <= form.bound):
        return STATUS_DIVERGED
    u = zone_input(
        v0, r, form.mode, form.gamma_m, form.gamma_c, form.mu_high, form.mu_low, s[1], form.blend
    )
    a = N_HEAD
    b = N_HEAD + n_m
    for j in range(n_m - 1):
        s[a + j] = s[a + j + 1]
        s[b + j] = s[b + j + 1]
    s[a + n_m - 1] = y
    s[b + n_m - 1] = u
    if form.eta >= 0.0:
        s[0] = lag_step(r, e0, math.exp(-form.eta * dt))
    if form.blend != 0.0:
        s[1] = dahl_step(s[1], v0, v1, dt, form.stroke)
    return STATUS_OK


def make_step(kind: str, form: LPVForm, fs: float, feedthrough: bool) -> Step:
    """The per-sample step of an LPV or LTI model of ``form`` at the model rate ``fs`` [Hz]."""
    size = N_HEAD + 2 * form.alpha.shape[0]

    def initial_state(x0: float, v0: float, e0: float) -> FloatArray:
        s = np.zeros(size)
        s[0] = e0
        return s

    return Step(
        kind,
        form,
        step_force,
        step_advance,
        initial_state,
        dt=1.0 / fs,
        feedthrough=feedthrough,
    )
