"""The built-in families' steps behind one pair of compiled functions (private).

A kernel that takes a step's ``force`` / ``advance`` as arguments is specialised on those
functions and cannot be cached on disk (numba does not cache a signature holding dispatchers), so
every process would compile it again for every family (tens of seconds for the quarter-car loop).
For the families this version defines, :func:`pack` puts the form in a *packed form*: the tuple
``(code, spencer, p15, static, lpv, narx, hysteresis)`` holding the family's form at its place and
a small placeholder form elsewhere. :func:`family_force` and :func:`family_advance` take a packed
form and call the family's own ``step_force`` / ``step_advance`` on a runtime branch of ``code``: a
kernel that reaches them as globals (not arguments) has a signature of arrays and tuples only and
is compiled once and cached on disk. The step functions are the families' own: nothing is
re-implemented. A step whose functions are not a built-in family's (a family added at run time)
gives None: its callers keep the path that takes the functions as arguments.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.models.hysteresis import kernels as H
from mrdamper.models.lpv import step as L
from mrdamper.models.narx import kernels as N
from mrdamper.models.p15 import kernels as P
from mrdamper.models.sp import kernels as S
from mrdamper.models.spencer import kernels as SP
from mrdamper.models.step import Step

FloatArray = npt.NDArray[np.float64]

__all__ = ["FAMILIES", "family_advance", "family_force", "pack", "placeholder"]

_F = np.zeros(1)
_F2 = np.zeros((1, 1))
_I = np.zeros(1, np.int64)
_I2 = np.zeros((1, 2), np.int64)

#: Family code -> (form class, placeholder form, step_force, step_advance).
FAMILIES: tuple[tuple[type, Any, Any, Any], ...] = (
    (SP.SpencerForm, SP.SpencerForm(_F, 1.0), SP.step_force, SP.step_advance),
    (
        P.P15Form,
        P.P15Form(np.zeros((5, 3)), 0.0, 0, 0.0, 1.0, 1.0, 1.0, -1.0),
        P.step_force,
        P.step_advance,
    ),
    (S.StaticStepForm, S.StaticStepForm(_I, _I, _F, 0.0, -1.0), S.step_force, S.step_advance),
    (
        L.LPVForm,
        L.LPVForm(_F2, _F2, 0.0, 1.0, -1.0, 0, _F2, _F2, _F, _F, 0.0, 1.0, 0.0),
        L.step_force,
        L.step_advance,
    ),
    (
        N.NARXForm,
        N.NARXForm(_I2, _I2, _F, _F, 1.0, 1.0, 1, 0.0, -np.inf, np.inf, np.inf),
        N.step_force,
        N.step_advance,
    ),
    (H.HysteresisForm, H.HysteresisForm(0, _F, 1.0), H.step_force, H.step_advance),
)


def _like(value: Any, template: Any) -> Any:
    """``value`` with the numba type of ``template`` (None when it cannot have it)."""
    if isinstance(template, np.ndarray):
        a = np.asarray(value)
        if a.ndim != template.ndim or a.dtype != template.dtype:
            return None
        return np.array(a, order="C", copy=True)  # writable and C-contiguous, as the template
    if isinstance(template, int):
        return int(value) if float(value) == int(value) else None
    return float(value)


def placeholder() -> tuple[Any, ...]:
    """A packed form with code -1 (no family: calling it is an error of the caller)."""
    return (np.int64(-1), *(f[1] for f in FAMILIES))


def pack(step: Step) -> tuple[Any, ...] | None:
    """The packed form of ``step`` (see the module docstring), or None when its functions are not
    a built-in family's."""
    for code, (cls, template, force, advance) in enumerate(FAMILIES):
        if type(step.form) is cls and step.force is force and step.advance is advance:
            fields = [_like(getattr(step.form, n), getattr(template, n)) for n in cls._fields]
            if any(f is None for f in fields):
                return None
            out = list(placeholder())
            out[0] = np.int64(code)
            out[1 + code] = cls(*fields)
            return tuple(out)
    return None


@njit(cache=True)
def family_force(
    pk: tuple[Any, ...], s: FloatArray, x: float, v: float, e: float
) -> float:  # pragma: no cover - numba
    """``step_force`` of the family ``pk[0]`` on its form (NaN for code -1)."""
    code = pk[0]
    if code == 0:
        return SP.step_force(pk[1], s, x, v, e)
    if code == 1:
        return P.step_force(pk[2], s, x, v, e)
    if code == 2:
        return S.step_force(pk[3], s, x, v, e)
    if code == 3:
        return L.step_force(pk[4], s, x, v, e)
    if code == 4:
        return N.step_force(pk[5], s, x, v, e)
    if code == 5:
        return H.step_force(pk[6], s, x, v, e)
    return np.nan


@njit(cache=True)
def family_advance(  # pragma: no cover - numba
    pk: tuple[Any, ...],
    s: FloatArray,
    x0: float,
    v0: float,
    e0: float,
    x1: float,
    v1: float,
    e1: float,
    dt: float,
) -> int:
    """``step_advance`` of the family ``pk[0]`` on its form (status 2, invalid, for code -1)."""
    code = pk[0]
    if code == 0:
        return SP.step_advance(pk[1], s, x0, v0, e0, x1, v1, e1, dt)
    if code == 1:
        return P.step_advance(pk[2], s, x0, v0, e0, x1, v1, e1, dt)
    if code == 2:
        return S.step_advance(pk[3], s, x0, v0, e0, x1, v1, e1, dt)
    if code == 3:
        return L.step_advance(pk[4], s, x0, v0, e0, x1, v1, e1, dt)
    if code == 4:
        return N.step_advance(pk[5], s, x0, v0, e0, x1, v1, e1, dt)
    if code == 5:
        return H.step_advance(pk[6], s, x0, v0, e0, x1, v1, e1, dt)
    return 2
