"""Hyperbolic-tangent hysteresis model of an MR damper (Kwok et al. 2006), current dependent.

Equations (Kwok, Ha, Nguyen, Li & Samali, "A novel hysteretic model for magnetorheological fluid
dampers and parameter identification using particle swarm optimization", Sensors and Actuators
A 132(2):441-451, 2006), with the yield force and the damping linear in the electrical input::

    F = c(u) v + k x + alpha(u) tanh(beta v + delta sign(x)) + f0
    c(u) = ca + cb u,  alpha(u) = alpha_a + alpha_b u
    du/dt = -eta (u - e)        (optional drive lag; eta = 0: u = e)

x [m] is the damper displacement, v the record's velocity [m/s] and e its electrical input
(``i`` [A] or ``voltage`` [V]). The model is a static map of (x, v, u); with a drive lag its only
state is u. Identified by output error (:mod:`.fit`): the damping ``c(u)`` and the yield
force ``alpha(u)`` are non-negative over any non-negative input by their bounds.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.hysteresis.fit import FitSpec, Scales, unit_floors
from mrdamper.models.hysteresis.model import HysteresisEstimator, HysteresisModel

__all__ = ["IDENTIFIED", "TanhEstimator", "TanhModel"]

_INF = np.inf

#: Identified parameters (names of ``start``, ``fixed`` and ``bounds``).
IDENTIFIED: tuple[str, ...] = ("ca", "cb", "k", "alpha_a", "alpha_b", "beta", "delta", "f0")


@dataclass(frozen=True, kw_only=True)
class TanhModel(HysteresisModel):
    """Identified hyperbolic-tangent model (Kwok et al. 2006); an immutable value.

    Parameters
    ----------
    ca, cb : float
        Viscous damping ``c = ca + cb u`` [N s/m], [N s/(m U)] (U: A or V).
    k : float
        Stiffness [N/m].
    alpha_a, alpha_b : float
        Hysteretic (yield) force ``alpha = alpha_a + alpha_b u`` [N], [N/U].
    beta : float
        Velocity scale of the hyperbolic tangent [s/m], positive.
    delta : float
        Hysteretic shift of the tangent with the sign of the displacement [-].
    eta, f0, substeps
        Drive-lag rate [1/s] (0: none), force offset [N], RK4 sub-steps (0: automatic).

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.data import Experiment
    >>> t = np.arange(200) * 1e-3
    >>> e = Experiment(t=t, x=0 * t + 0.01, v=0 * t + 0.1, F=0 * t, i=0 * t + 1.0, name="demo")
    >>> m = TanhModel(ca=1000.0, cb=0.0, k=0.0, alpha_a=100.0, alpha_b=0.0, beta=1e3, delta=0.0,
    ...               input_range=(1.0, 1.0))
    >>> round(float(m.predict(e)[0]), 6)  # 1000 N s/m * 0.1 m/s + 100 N * tanh(100)
    200.0
    """

    kind: ClassVar[str] = "tanh"
    family: ClassVar[str] = "tanh"

    ca: float
    cb: float
    k: float
    alpha_a: float
    alpha_b: float
    beta: float
    delta: float

    def _check(self) -> None:
        if not self.beta > 0.0:
            raise DataValidationError(
                "beta", f"expected a positive velocity scale, got {self.beta!r}"
            )


def _start(reg: np.ndarray, yield_disp: float, s: Scales) -> dict[str, float]:
    fa, fb, ca, cb, k, f0 = (float(c) for c in reg)
    return {
        "ca": max(ca, 1e-2 * s.force / s.v),
        "cb": max(cb, 0.0),
        "k": k,
        "alpha_a": max(fa, 1e-2 * s.force),
        "alpha_b": max(fb, 0.0),
        # the tangent saturates within the yield displacement at the largest velocity
        "beta": s.amplitude / (yield_disp * s.v),
        "delta": 0.0,
        "f0": f0,
    }


def _identity(theta: Mapping[str, float]) -> dict[str, float]:
    return dict(theta)


SPEC = FitSpec(
    family="tanh",
    unknowns=IDENTIFIED,
    bounds={
        "ca": (0.0, _INF),
        "cb": (0.0, _INF),
        "k": (-_INF, _INF),
        "alpha_a": (0.0, _INF),
        "alpha_b": (0.0, _INF),
        "beta": (0.0, _INF),
        "delta": (-10.0, 10.0),
        "f0": (-_INF, _INF),
    },
    start=_start,
    floors=unit_floors(
        {
            "ca": "damp",
            "cb": "damp/e",
            "k": "stiff",
            "alpha_a": "force",
            "alpha_b": "force/e",
            "beta": "1/v",
            "delta": "one",
            "f0": "force",
        }
    ),
    to_params=_identity,
    single_fixed=lambda start: {"cb": 0.0, "alpha_b": 0.0},
    jitter_skip=("f0", "k", "delta"),
)


@dataclass
class TanhEstimator(HysteresisEstimator):
    """Identify a :class:`TanhModel` by output error (settings: see
    :class:`~mrdamper.models.hysteresis.model.HysteresisEstimator`; parameter names:
    :data:`IDENTIFIED`). At a single input level ``cb`` and ``alpha_b`` are fixed at 0."""

    kind: ClassVar[str] = "tanh"
    model_class: ClassVar[type[FittedModel]] = TanhModel
    spec: ClassVar[FitSpec] = SPEC
