"""The per-sample step of a fitted model: the one definition every tool runs.

A fitted model has two faces: an open-loop predictor (:meth:`FittedModel.predict`, often a fused
compiled kernel over a whole record) and a per-sample step, the model written as a discrete-time
system::

    F[k]       = force(form, s[k], x[k], v[k], e[k])
    s[k + 1]   = advance(form, s[k], x[k], v[k], e[k], x[k+1], v[k+1], e[k+1], dt)

with ``s`` the model's state (a float64 vector updated in place by ``advance``), ``x`` the damper
displacement [m], ``v`` its velocity [m/s] and ``e`` the electrical input (coil current [A] or
drive command [V]). ``force`` does not change the state. ``advance`` may use the motion at both
ends of the interval (continuous-time families integrate over it with the inputs linear in between,
as their ``predict`` does); in a closed loop, where the next motion is not known yet, the caller
passes the motion at the end of its own integration step. Discrete-time families (LPV, LTI,
NARX) read only the present sample and must be stepped at their own sample time ``dt``
(:attr:`Step.dt`).

The form is a family's typed container (a :class:`typing.NamedTuple` of floats and float64 /
int64 arrays) holding everything the two compiled functions need; it is built from the model by
:meth:`FittedModel.step`. Every kind has one (forms and steps beside the family's kernels):

=============  ==================  ================================================  ==========
kind           form                state                                             ``dt``
=============  ==================  ================================================  ==========
spencer        ``SpencerForm``     ``(y, z, u)``, RK4 sub-steps <= ``max_h``         any
p15            ``P15Form``         ``(F, F', rho)``, SDIRK steps <= ``max_step``     any
sp1..sp4       ``StaticStepForm``  ``(rho,)``: the map's input (drive lag)           any
bingham        ``StaticStepForm``  ``(rho,)``                                        any
lpv, lti       ``LPVForm``         ``rho``, Dahl ``z``, past outputs and inputs      ``1/fs``
narx           ``NARXForm``        samples seen, last ``max_lag`` scaled samples     ``1/fs``
tanh..lugre    ``HysteresisForm``  ``(z, u)``, RK4 sub-steps <= ``max_h``            any
=============  ==================  ================================================  ==========

(``tanh..lugre``: the one-state hysteresis families ``tanh``, ``boucwen``, ``dahl``, ``lugre``.)

The simulation loop (:func:`run`) calls ``force`` and ``advance`` and never re-implements them;
the per-sample pieces the inverse and the quarter car of :mod:`mrdamper.control` need (the LPV
output step, the zone-law input, the Dahl step, the static map) are the same compiled functions,
public in :mod:`mrdamper.models.kernels`. A family's fused ``predict`` kernel is an optimisation
that shares the inner per-sample functions with the step (Spencer, P-15, SP, NARX) or, where it
is restructured for speed (the LPV recursions), is tested sample by sample against :func:`run`
(``tests/models/test_conformance.py``: equal to 1e-9 of the force scale for every kind).
The step uses the electrical input as given: the model's range policy is not applied.

``advance`` returns a status code: :data:`STATUS_OK`, :data:`STATUS_DIVERGED` (a state became
non-finite or left its bound) or :data:`STATUS_INVALID` (parameters invalid for the input seen,
e.g. a non-positive damping).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

__all__ = [
    "STATUS_DIVERGED",
    "STATUS_INVALID",
    "STATUS_OK",
    "Step",
    "run",
    "run_step",
]

STATUS_OK = 0
STATUS_DIVERGED = 1
STATUS_INVALID = 2

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Step:
    """A fitted model as a per-sample step (see the module docstring).

    Attributes
    ----------
    kind : str
        Model kind.
    form : tuple
        The family's form: a NamedTuple of floats and arrays, the only argument besides the state
        and the signals that ``force`` and ``advance`` take.
    force : compiled function
        ``force(form, state, x, v, e) -> F`` [N]; does not change ``state``.
    advance : compiled function
        ``advance(form, state, x0, v0, e0, x1, v1, e1, dt) -> status``; updates ``state`` in place
        from the start of an interval of ``dt`` [s] to its end.
    initial_state : callable
        ``initial_state(x0, v0, e0) -> state``: the state at rest at the first sample (a new
        float64 array each call).
    dt : float or None
        The step's own sample time [s] for discrete-time families (they must be advanced with it),
        None where any interval is allowed (static maps, continuous-time families).
    feedthrough : bool
        True when ``force`` reads the present electrical input ``e[k]`` (static maps and the LPV
        model without drive lag, NARX with a present-input term); False when the force at a
        sample is fixed by the state (Spencer and P-15, whose input acts through their state;
        the LTI model; any family with a drive lag): such a step cannot be inverted at the
        present sample.
    """

    kind: str
    form: Any
    force: Callable[..., float]
    advance: Callable[..., int]
    initial_state: Callable[[float, float, float], FloatArray]
    dt: float | None = None
    feedthrough: bool = True


@njit(cache=False)
def run(
    force: Callable[..., float],
    advance: Callable[..., int],
    form: Any,
    state: FloatArray,
    x: FloatArray,
    v: FloatArray,
    e: FloatArray,
    dt: float,
) -> tuple[FloatArray, int, int]:  # pragma: no cover - numba
    """Free run of a step over sampled signals (compiled once per family and process).

    Returns
    -------
    F : float64[:]
        Force [N] at every sample (valid before ``sample`` when ``status != 0``).
    status : int
        0 ok, else the status ``advance`` returned.
    sample : int
        First failing sample (-1 when ok).
    """
    n = x.size
    F = np.zeros(n)
    for k in range(n):
        F[k] = force(form, state, x[k], v[k], e[k])
        if k == n - 1:
            break
        status = advance(form, state, x[k], v[k], e[k], x[k + 1], v[k + 1], e[k + 1], dt)
        if status != 0:
            return F, status, k + 1
    return F, 0, -1


def run_step(
    step: Step, x: FloatArray, v: FloatArray, e: FloatArray, dt: float
) -> tuple[FloatArray, int, int]:
    """Free run of ``step`` from rest over sampled displacement, velocity and electrical input.

    Parameters
    ----------
    step : Step
        The model's per-sample step.
    x, v, e : ndarray
        Displacement [m], velocity [m/s] and electrical input [A] or [V], one value a sample.
    dt : float
        Sampling interval [s]; must equal ``step.dt`` for a discrete-time family.

    Returns
    -------
    F : ndarray
        Force [N] at every sample.
    status, sample : int
        Status code (``STATUS_*``) and first failing sample (-1 when ok).
    """
    if step.dt is not None and not np.isclose(dt, step.dt, rtol=1e-9, atol=0.0):
        raise ValueError(
            f"dt: the {step.kind} step runs at its own sample time {step.dt!r} s, got {dt!r} s"
        )
    x = np.ascontiguousarray(x, dtype=np.float64)
    v = np.ascontiguousarray(v, dtype=np.float64)
    e = np.ascontiguousarray(e, dtype=np.float64)
    state = step.initial_state(float(x[0]), float(v[0]), float(e[0]))
    F, status, sample = run(step.force, step.advance, step.form, state, x, v, e, float(dt))
    return np.asarray(F), int(status), int(sample)
