"""A hysteretic LPV input: the zone-law input with a rate-independent pre-yield state.

The static input ``u(v, rho)`` of :mod:`mrdamper.analysis.scheduling` (continuous reading) can be
written ``u = (1 - r) sat(v) + r v`` with ``sat(v) = clip(v, v_low, v_high)`` and the post-yield
slope ratio ``r = m3 / m2`` (``m1 / m2`` for ``v < 0``). It is a function of the velocity only, so
the force it implies at a given velocity does not depend on the stroke. A real MR damper's
pre-yield force follows the displacement: at small strokes it is stiffness-like and does not
reach the yield force, at large strokes it saturates. The hysteretic input replaces part of
``sat(v)`` by a normalised Dahl state ``z`` driven by the displacement::

    dz/dx = (sign(dx) - z) / x_y        (|z| <= 1)

    u = (1 - r) [(1 - lambda) sat(v) + lambda y(z) z] + r v
    y(z) = v_high (z >= 0),  -v_low (z < 0)

``x_y`` [m] (``stroke``) is the stroke over which ``z`` moves a fraction ``1 - 1/e`` of the way to
``sign(v)`` after a reversal; ``lambda`` [-] (``blend``) the share of the hysteretic state in the
pre-yield part. Limits: for a stroke much smaller than ``x_y`` the state grows like ``x / x_y``
(a stiffness); for a stroke much larger it is ``sign(v)`` away from reversals, and the input is
the static one with ``sat(v)`` replaced by its sign-level ``v_high`` / ``v_low``. ``lambda = 0``
gives the static input exactly.

The state is integrated exactly for a velocity that is linear between samples and keeps its sign
within each step (trapezoidal displacement increments), so it is stable for any step:
``z[k] = s + (z[k-1] - s) exp(-|dx| / x_y)`` with ``dx = (v[k-1] + v[k]) dt / 2``, ``s = sign(dx)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from mrdamper.analysis.laws import in_blocks
from mrdamper.errors import DataValidationError

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.analysis.laws import ZoneLaws

__all__ = ["dahl_state", "dahl_step", "hysteretic_input"]


@njit(cache=True)
def dahl_step(z, v_prev, v, dt, stroke):  # pragma: no cover - numba
    """One exact step of the Dahl state: ``z[k]`` [-] from ``z[k-1]`` for the trapezoidal
    displacement ``(v[k-1] + v[k]) dt / 2`` [m] (module docstring); the one definition, used by
    :func:`dahl_state` and by the per-sample step of the LPV model."""
    dx = 0.5 * (v_prev + v) * dt
    if dx > 0.0:
        return 1.0 + (z - 1.0) * np.exp(-dx / stroke)
    if dx < 0.0:
        return -1.0 + (z + 1.0) * np.exp(dx / stroke)
    return z


@njit(cache=True)
def _dahl(v, dt, stroke, z0):  # pragma: no cover - numba
    n = v.size
    z = np.empty(n)
    zk = z0
    if n > 0:
        z[0] = zk
    for k in range(1, n):
        zk = dahl_step(zk, v[k - 1], v[k], dt, stroke)
        z[k] = zk
    return z


def _check(stroke: float, dt: float) -> None:
    if isinstance(stroke, bool) or not (np.isfinite(stroke) and stroke > 0):
        raise DataValidationError("stroke", f"expected a positive stroke scale [m], got {stroke!r}")
    if not (np.isfinite(dt) and dt > 0):
        raise DataValidationError("dt", f"expected a positive sample time [s], got {dt!r}")


def dahl_state(v: Any, dt: float, stroke: float, z0: float = 0.0) -> np.ndarray:
    """Normalised Dahl state ``z`` [-] driven by the displacement of a velocity record.

    Parameters
    ----------
    v : array_like, shape (n,)
        Velocity [m/s] at uniform samples.
    dt : float
        Sample time [s].
    stroke : float
        Stroke scale ``x_y`` [m] of ``dz/dx = (sign(dx) - z) / x_y``.
    z0 : float
        State at the first sample [-], ``|z0| <= 1`` (0: from rest).

    Returns
    -------
    ndarray, shape (n,)
        ``z`` at every sample; ``|z| <= 1``.

    Examples
    --------
    >>> import numpy as np
    >>> z = dahl_state(np.full(1001, 0.01), 1e-3, 1e-4)  # 10 mm at 10 mm/s, x_y = 0.1 mm
    >>> bool(abs(z[-1] - 1.0) < 1e-12)
    True
    """
    _check(stroke, dt)
    if not (np.isfinite(z0) and abs(z0) <= 1.0):
        raise DataValidationError("z0", f"expected |z0| <= 1, got {z0!r}")
    arr = np.ascontiguousarray(v, dtype=np.float64)
    if arr.ndim != 1:
        raise DataValidationError("v", f"expected a 1-D velocity array, got shape {arr.shape}")
    return np.asarray(_dahl(arr, float(dt), float(stroke), float(z0)))


def hysteretic_input(
    laws: ZoneLaws, v: Any, rho: Any, dt: float, stroke: float, blend: float
) -> np.ndarray:
    """Hysteretic LPV input ``u`` [m/s] from velocity and scheduling variable (module docstring).

    Parameters
    ----------
    laws : ZoneLaws
        Zone laws giving ``m1, m2, m3`` [N s/m] and the zone limits [m/s] at ``rho``.
    v : array_like, shape (n,)
        Velocity [m/s] at uniform samples (from rest).
    rho : array_like, shape (n,)
        Scheduling variable [A] or [V] at the same samples.
    dt : float
        Sample time [s].
    stroke : float
        Stroke scale ``x_y`` [m] of the Dahl state.
    blend : float
        Share ``lambda`` in [0, 1] of the hysteretic state in the pre-yield part (0: the static
        input of the continuous reading).

    Returns
    -------
    ndarray, shape (n,)
        The LPV input ``u`` [m/s].
    """
    if isinstance(blend, bool) or not (np.isfinite(blend) and 0.0 <= blend <= 1.0):
        raise DataValidationError("blend", f"expected a share in [0, 1], got {blend!r}")
    v = np.ascontiguousarray(v, dtype=np.float64)
    rho = np.broadcast_to(np.asarray(rho, dtype=float), v.shape)
    z = dahl_state(v, dt, stroke)
    return in_blocks(lambda vb, rb, zb: _blend(laws, vb, rb, zb, blend), v, rho, z)


def _blend(laws: ZoneLaws, v: np.ndarray, rho: np.ndarray, z: np.ndarray, blend: float) -> Any:
    """``u`` from velocity, level and Dahl state, sample by sample (module docstring)."""
    m = laws.m(rho)
    if np.any(m[..., 1] == 0.0):
        raise DataValidationError(
            "m2", "central slope is zero; the input u = sigma v + psi is undefined"
        )
    hi, lo = laws.v_high(rho), laws.v_low(rho)
    r = np.where(v >= 0.0, m[..., 2], m[..., 0]) / m[..., 1]
    level = np.where(z >= 0.0, hi, -lo)
    pre = (1.0 - blend) * np.clip(v, lo, hi) + blend * level * z
    return np.asarray((1.0 - r) * pre + r * v)
