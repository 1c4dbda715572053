"""The LPV input variable ``u(k) = sigma(i) v(k) + psi(i)`` (paper eqs. 19-22).

Two readings of eq. (22) are available (reading notes, items 5-6; zone labels of eq. 17):

``reading="continuous"`` (default)
    Each outer zone is mapped onto the central line, ``m2 u + c2 = m_j v + c_j``, with the
    intercept implied by continuity at the breakpoint ``v_b`` (``v_low`` for zone I, ``v_high``
    for zone III)::

        u = v_b + (m_j / m2) (v - v_b)      (= (m_j v + c_j - c2) / m2 on a continuous fit)

    so ``sigma = m_j / m2`` and ``psi = (1 - sigma) v_b``. ``u`` equals ``v`` at both limits and,
    whenever ``v_low <= 0 <= v_high`` and ``0 <= m_j / m2 <= 1`` (eq. 20), ``|u| <= |v|``.
``reading="literal"``
    Eq. (22) as printed: ``u = (m_j v + c_j) / m2`` in the outer zones. It is discontinuous at the
    limits unless ``c2 = 0`` and does not guarantee ``|u| <= |v|``.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["Reading", "scheduling_input_arrays"]

Reading = Literal["continuous", "literal"]


def scheduling_input_arrays(
    v: Any,
    m: np.ndarray,
    c: np.ndarray,
    v_low: Any,
    v_high: Any,
    reading: Reading = "continuous",
) -> np.ndarray:
    """Compute ``u`` [m/s] from velocity and per-sample zone parameters.

    Parameters
    ----------
    v : array_like, shape (n,)
        Velocity [m/s].
    m : ndarray, shape (n, 3)
        Slopes ``m1, m2, m3`` at each sample [N s/m].
    c : ndarray, shape (n, 3)
        Intercepts ``c1, c2, c3`` at each sample [N] (used by the literal reading only).
    v_low, v_high : array_like, shape (n,) or scalar
        Zone limits at each sample [m/s].
    reading : {"continuous", "literal"}
        See the module docstring.

    Returns
    -------
    ndarray, shape (n,)
        The LPV input ``u`` [m/s].
    """
    v = np.asarray(v, dtype=float)
    m = np.asarray(m, dtype=float)
    c = np.asarray(c, dtype=float)
    lo = np.broadcast_to(np.asarray(v_low, dtype=float), v.shape)
    hi = np.broadcast_to(np.asarray(v_high, dtype=float), v.shape)
    if m.shape != v.shape + (3,) or c.shape != v.shape + (3,):
        raise DataValidationError(
            "m", f"expected shape {v.shape + (3,)} for m and c, got {m.shape}, {c.shape}"
        )
    m2 = m[..., 1]
    if np.any(m2 == 0.0):
        raise DataValidationError(
            "m2", "central slope is zero; the input u = sigma v + psi is undefined"
        )
    below, above = v < lo, v > hi
    u = v.copy()
    if reading == "continuous":
        u = np.where(below, lo + m[..., 0] / m2 * (v - lo), u)
        u = np.where(above, hi + m[..., 2] / m2 * (v - hi), u)
    elif reading == "literal":
        u = np.where(below, (m[..., 0] * v + c[..., 0]) / m2, u)
        u = np.where(above, (m[..., 2] * v + c[..., 2]) / m2, u)
    else:
        raise DataValidationError("reading", f"expected 'continuous' or 'literal', got {reading!r}")
    return u
