"""Numba kernels of the polynomial NARX model, on plain arrays.

Layout shared by every kernel (one record at a time; records are never concatenated):

* ``S`` float64 ``(n_signals, N)``: the record's scaled signals, row 0 the force ``f = F / F_s``
  (the other rows are x, v, the electrical input and tanh(v / v0), already scaled).
* ``base`` int64 ``(n_base, 2)``: base variable ``b`` is ``S[base[b, 0], k - base[b, 1]]`` at
  sample ``k`` (signal row, lag >= 0; force rows always have lag >= 1).
* ``slots`` int64 ``(n_terms, D)``: monomial ``t`` is the product of the base variables listed in
  ``slots[t]``; ``-1`` marks an empty slot (the constant term has only empty slots).
* Model: ``f[k] = sum_t theta[t] * prod_s b[slots[t, s]]`` for ``k >= p`` (``p`` the largest lag);
  samples ``0 .. p-1`` are initial conditions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models._arrays import readonly
from mrdamper.models.step import STATUS_DIVERGED, STATUS_OK

__all__ = [
    "NARXForm",
    "fill_candidates",
    "free_run",
    "free_run_sensitivity",
    "step_advance",
    "step_force",
]

#: Argument types of the kernels (numba types the values passed; these are for mypy).
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def fill_candidates(
    S: np.ndarray, base: np.ndarray, slots: np.ndarray, k0: int, k1: int, out: np.ndarray
) -> None:
    """Rows ``k0 .. k1-1`` of the regression matrix into ``out[: k1 - k0]`` (terms as columns).

    ``base`` and ``slots`` are passed read-only so each kernel has one signature."""
    _fill_candidates(S, _ri(base), _ri(slots), int(k0), int(k1), out)


def free_run(
    S: np.ndarray, base: np.ndarray, slots: np.ndarray, theta: np.ndarray, p: int, bound: float
) -> int:
    """Simulate ``S[0, p:]`` in place from ``S[0, :p]``; first diverging sample or -1.

    A sample diverges when its scaled force is not finite or exceeds ``bound`` in magnitude;
    the simulation stops there (later samples are left untouched).
    """
    return int(_free_run(S, _ri(base), _ri(slots), readonly(theta), int(p), float(bound)))


def free_run_sensitivity(
    S: np.ndarray, base: np.ndarray, slots: np.ndarray, theta: np.ndarray, p: int, bound: float
) -> tuple[np.ndarray, int]:
    """Free run as :func:`free_run` plus ``J[k, j] = d f[k] / d theta[j]`` (see
    :func:`_free_run_sensitivity`); returns ``(J, bad)``."""
    J, bad = _free_run_sensitivity(S, _ri(base), _ri(slots), readonly(theta), int(p), float(bound))
    return J, int(bad)


def _ri(a: np.ndarray) -> np.ndarray:
    return readonly(a, np.int64)


@njit(cache=True)
def _base_values(
    S: FloatArray, base: IntArray, k: int, out: FloatArray
) -> None:  # pragma: no cover - numba
    for b in range(base.shape[0]):
        out[b] = S[base[b, 0], k - base[b, 1]]


@njit(cache=True)
def _term(bv: FloatArray, slots: IntArray, t: int) -> float:  # pragma: no cover - numba
    val = 1.0
    for s in range(slots.shape[1]):
        j = slots[t, s]
        if j >= 0:
            val *= bv[j]
    return val


@njit(cache=True)
def _output(bv: FloatArray, slots: IntArray, theta: FloatArray) -> float:  # pragma: no cover
    """The scaled force of one sample from its base-variable values: ``sum_t theta[t] * term_t``
    (the one definition, run by the free run and by the per-sample step)."""
    acc = 0.0
    for t in range(slots.shape[0]):
        acc += theta[t] * _term(bv, slots, t)
    return acc


@njit(cache=True)
def _fill_candidates(
    S: FloatArray, base: IntArray, slots: IntArray, k0: int, k1: int, out: FloatArray
) -> None:  # pragma: no cover - numba
    """Rows ``k0 .. k1-1`` of the regression matrix into ``out[: k1 - k0]`` (terms as columns)."""
    bv = np.empty(base.shape[0])
    for q in range(k1 - k0):
        _base_values(S, base, k0 + q, bv)
        for t in range(slots.shape[0]):
            out[q, t] = _term(bv, slots, t)


@njit(cache=True)
def _free_run(
    S: FloatArray, base: IntArray, slots: IntArray, theta: FloatArray, p: int, bound: float
) -> int:  # pragma: no cover - numba
    """Simulate ``S[0, p:]`` in place from ``S[0, :p]``; first diverging sample or -1.

    A sample diverges when its scaled force is not finite or exceeds ``bound`` in magnitude;
    the simulation stops there (later samples are left untouched).
    """
    bv = np.empty(base.shape[0])
    n = S.shape[1]
    for k in range(p, n):
        _base_values(S, base, k, bv)
        acc = _output(bv, slots, theta)
        if not np.isfinite(acc) or abs(acc) > bound:
            return k
        S[0, k] = acc
    return -1


@njit(cache=True)
def _free_run_sensitivity(
    S: FloatArray, base: IntArray, slots: IntArray, theta: FloatArray, p: int, bound: float
) -> tuple[FloatArray, int]:  # pragma: no cover - numba
    """Free run as :func:`free_run` plus ``J[k, j] = d f[k] / d theta[j]``.

    The sensitivity obeys ``J[k] = phi(k) + sum_t theta_t sum_{s: force slot}
    (prod_{s' != s} b_{s'}) J[k - lag_s]`` (the chain rule through the fed-back force).
    Returns ``(J, bad)``; rows from ``bad`` on are zero when the run diverged.
    """
    n = S.shape[1]
    T = slots.shape[0]
    D = slots.shape[1]
    J = np.zeros((n, T))
    bv = np.empty(base.shape[0])
    for k in range(p, n):
        _base_values(S, base, k, bv)
        acc = 0.0
        for t in range(T):
            phi = _term(bv, slots, t)
            acc += theta[t] * phi
            J[k, t] += phi
            for s in range(D):
                j = slots[t, s]
                if j < 0 or base[j, 0] != 0:
                    continue
                partial = theta[t]
                for s2 in range(D):
                    j2 = slots[t, s2]
                    if s2 != s and j2 >= 0:
                        partial *= bv[j2]
                lag = base[j, 1]
                for c in range(T):
                    J[k, c] += partial * J[k - lag, c]
        if not np.isfinite(acc) or abs(acc) > bound:
            for kk in range(k, n):
                for c in range(T):
                    J[kk, c] = 0.0
            return J, k
        S[0, k] = acc
    return J, -1


# ----------------------------------------------------------------------------- per-sample step
class NARXForm(NamedTuple):
    """The NARX model as its per-sample step reads it (layout of the module docstring).

    The step's state is ``[k, S[r, k - l] for r in rows, l = 1 .. p]``: the samples seen so far
    (capped at ``p``) and the last ``p`` scaled values of every signal row, row-major.

    Attributes
    ----------
    base, slots, theta : ndarray
        Base variables, monomials and coefficients (scaled units).
    scales : ndarray, shape (5,)
        Scale of each signal row (F [N], x [m], v [m/s], e, tanh_v [-]).
    v0 : float
        Velocity of the ``tanh(v / v0)`` feature [m/s].
    bound : float
        Largest accepted scaled ``|f|``.
    p : int
        Initial-condition samples (the largest lag).
    f_initial : float
        Force [N] of the first ``p`` samples (the free run's initial conditions).
    x_lo, x_hi, v_limit : float
        The displacement [m] and velocity magnitude [m/s] the regressors are clipped to (the
        training envelope; infinite: no clipping). ``tanh(v / v0)`` reads the clipped velocity.
    """

    base: IntArray
    slots: IntArray
    theta: FloatArray
    scales: FloatArray
    v0: float
    bound: float
    p: int
    f_initial: float
    x_lo: float
    x_hi: float
    v_limit: float


@njit(cache=True)
def _present(form: NARXForm, r: int, x: float, v: float, e: float) -> float:  # pragma: no cover
    """Scaled value of signal row ``r`` (not the force) at the present sample (x and v clipped
    to the form's limits)."""
    vc = min(max(v, -form.v_limit), form.v_limit)
    if r == 1:
        val = min(max(x, form.x_lo), form.x_hi)
    elif r == 2:
        val = vc
    elif r == 3:
        val = e
    else:
        val = np.tanh(vc / form.v0)
    out: float = val / form.scales[r]
    return out


@njit(cache=True)
def _scaled_force(
    form: NARXForm, s: FloatArray, x: float, v: float, e: float
) -> float:  # pragma: no cover - numba
    """Scaled force at the present sample: the initial condition for the first ``p`` samples."""
    p = form.p
    if s[0] < p:
        out: float = form.f_initial / form.scales[0]
        return out
    bv = np.empty(form.base.shape[0])
    for b in range(form.base.shape[0]):
        r, lag = form.base[b, 0], form.base[b, 1]
        bv[b] = _present(form, r, x, v, e) if lag == 0 else s[1 + r * p + lag - 1]
    return _output(bv, form.slots, form.theta)


@njit(cache=True)
def step_force(
    form: NARXForm, s: FloatArray, x: float, v: float, e: float
) -> float:  # pragma: no cover - numba
    """Force [N] at the present sample (see :mod:`mrdamper.models.step`)."""
    out: float = _scaled_force(form, s, x, v, e) * form.scales[0]
    return out


@njit(cache=True)
def step_advance(
    form: NARXForm,
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:  # pragma: no cover - numba
    """Push the present sample into the history (``dt`` is the model's sample time)."""
    f = _scaled_force(form, s, x0, v0, e0)
    if not np.isfinite(f) or abs(f) > form.bound:
        return STATUS_DIVERGED
    p = form.p
    for r in range(form.scales.size):
        a = 1 + r * p
        for lag in range(p - 1, 0, -1):
            s[a + lag] = s[a + lag - 1]
        s[a] = f if r == 0 else _present(form, r, x0, v0, e0)
    s[0] = min(s[0] + 1.0, float(p))
    return STATUS_OK
