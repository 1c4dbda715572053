"""Capabilities of fitted models, as protocols: what a caller may do with a model, not its class.

A model that can be inverted (the electrical input that makes a desired force, sample by sample:
:func:`mrdamper.control.inverse_current`), put in a closed loop (the quarter car) or exported to C
implements :class:`InvertibleModel`: its :meth:`~InvertibleModel.inverse_form` gives the model
in one of two plain-array forms that the control kernels step through:

* :class:`StaticMapForm`: ``F = sum_k theta_k g_k(x, v, rho)`` as the component / power layout of
  the SP maps (SP-1..SP-4, Bingham);
* :class:`ScheduledForm`: the LPV input-output model, whose force at sample ``k`` is a
  polynomial in the present ``rho[k]`` (LPV; the LTI model is not invertible, its force does not
  depend on the present input).

Spencer, P-15 and NARX have no such form yet; every kind has a per-sample step
(:meth:`~mrdamper.models.base.FittedModel.step`, :mod:`mrdamper.models.step`).

A model whose per-sample step can be solved for the present input in closed form (the force is
affine in it at the present state: ``tanh``, ``boucwen``, ``dahl``, ``lugre``; with a drive lag
the input solved for is the lagged one) implements :class:`StepInvertibleModel`:
:func:`mrdamper.control.inverse_current` runs its :meth:`~StepInvertibleModel.invert_record`
(and, with a drive lag, the command through the lag's inverse).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from mrdamper.data import Experiment

__all__ = [
    "InvertibleModel",
    "ScheduledForm",
    "StaticMapForm",
    "StepInvertibleModel",
    "scheduled_form",
]


@dataclass(frozen=True, eq=False)
class StaticMapForm:
    """A static force map as plain arrays (the SP component layout).

    ``F = A tanh(a v + b x) + c v + d x + f0`` where each of the components ``A, a, b, c, d``
    (index 0..4) is ``sum theta_k rho**power_k`` over the coefficients ``k`` with ``comp_k`` equal
    to that index.

    Attributes
    ----------
    comp, power : ndarray of int64
        Component index (0..4) and input exponent of each coefficient.
    theta : ndarray
        Coefficients (SI; units per component, see :mod:`mrdamper.models.sp.model`).
    f0 : float
        Force offset [N].
    eta : float or None
        Drive-lag rate [1/s] between the electrical input and ``rho``; None: ``rho`` is the input.
    """

    comp: np.ndarray
    power: np.ndarray
    theta: np.ndarray
    f0: float
    eta: float | None = None


@dataclass(frozen=True, eq=False)
class ScheduledForm:
    """The LPV input-output model as plain arrays (see :mod:`mrdamper.models.lpv`).

    Attributes
    ----------
    alpha, beta : ndarray, shape (n_m, n_rho + 1)
        Denominator / numerator coefficients, column ``p`` multiplying ``rho**p``.
    offset : float
        Output force offset [N].
    fs : float
        Model rate [Hz].
    eta : float or None
        Drive-lag rate [1/s] of ``rho``; None: ``rho`` is the electrical input.
    input_signal : {"u", "v", "hysteretic"}
        LPV input: the zone-law scheduling input, the velocity, or the zone-law input with a
        hysteretic pre-yield state (:mod:`mrdamper.analysis.hysteretic`).
    reading : {"continuous", "literal"}
        Reading of eq. (22).
    gamma_m, gamma_c : ndarray, shape (3, degree + 1)
        Zone-law coefficients (slopes and intercepts in ``rho``); zeros for ``input_signal="v"``.
    mu_high, mu_low : ndarray, shape (2,)
        Breakpoint laws; zeros for ``input_signal="v"``.
    blend : float
        Share ``lambda`` [-] of the Dahl state in the pre-yield part of the input; 0 for the
        static inputs ``"u"`` and ``"v"``.
    stroke : float
        Stroke scale ``x_y`` [m] of the Dahl state ``z``; 0 for the static inputs. ``z`` depends
        only on the motion (``z[k] = s + (z[k-1] - s) exp(-|dx| / x_y)``, ``dx`` the trapezoidal
        displacement step, ``s = sign(dx)``, ``z = 0`` at rest), so at each sample the input is
        still a static map of ``(v, z, rho)``.
    stiffness : float
        Parallel stiffness ``k_x`` [N/m]: the force is the filtered output plus
        ``offset + k_x x`` (0: none).
    """

    alpha: np.ndarray
    beta: np.ndarray
    offset: float
    fs: float
    eta: float | None
    input_signal: Literal["u", "v", "hysteretic"]
    reading: Literal["continuous", "literal"]
    gamma_m: np.ndarray
    gamma_c: np.ndarray
    mu_high: np.ndarray
    mu_low: np.ndarray
    blend: float = 0.0
    stroke: float = 0.0
    stiffness: float = 0.0


@runtime_checkable
class InvertibleModel(Protocol):
    """A fitted model whose force can be solved for the present electrical input.

    Implemented by :class:`~mrdamper.models.lpv.LPVModel`, the SP-1..SP-4 models and
    :class:`~mrdamper.models.bingham.BinghamModel`.
    """

    kind: Any
    input: Any
    input_range: tuple[float, float]
    provenance: Mapping[str, Any]

    def inverse_form(self) -> StaticMapForm | ScheduledForm:
        """The model as the plain arrays the control kernels step through."""
        ...

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] of a record."""
        ...

    def with_range_policy(self, policy: Any) -> Any:
        """Copy of the model with another out-of-range policy."""
        ...


@runtime_checkable
class StepInvertibleModel(Protocol):
    """A fitted model inverted sample by sample through its own step (see the module docstring).

    Implemented by the ``tanh``, ``boucwen``, ``dahl`` and ``lugre`` models
    (:class:`~mrdamper.models.hysteresis.model.HysteresisModel`). ``eta`` is the drive-lag rate
    [1/s] (0: none); with a lag :meth:`invert_record` returns the lagged input.
    """

    kind: Any
    input: Any
    input_range: tuple[float, float]
    eta: float

    def invert_record(
        self,
        x: np.ndarray,
        v: np.ndarray,
        F_desired: np.ndarray,
        dt: float,
        lo: float,
        hi: float,
        *,
        reg: float = 0.0,
        max_change: float = ...,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Input the force reads [A] or [V] (with a drive lag, the lagged input) and saturation
        flags of the causal per-sample inverse."""
        ...

    def force_authority(self, v_ref: float) -> float:
        """Steady force range per input unit at the velocity ``v_ref`` [m/s]."""
        ...


def scheduled_form(model: object) -> ScheduledForm | None:
    """The :class:`ScheduledForm` of an invertible LPV-type model, None for any other model.

    Parameters
    ----------
    model : object
        Any model.
    """
    if isinstance(model, InvertibleModel):
        form = model.inverse_form()
        if isinstance(form, ScheduledForm):
            return form
    return None
