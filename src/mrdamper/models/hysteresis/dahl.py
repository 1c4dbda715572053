"""Modified Dahl model of an MR damper (Zhou et al. 2006), current dependent.

Equations (Zhou, Nielsen & Qu, "Semi-active control of three-dimensional vibrations of an
inclined sag cable with magnetorheological dampers", J. Sound Vib. 296(1-2):1-22, 2006), with an
optional first-order drive lag::

    F     = c0(u) v + k0 x + Fd(u) z + f0
    dz/dt = sigma (v - |v| z)
    du/dt = -eta (u - e)            (eta = 0: u = e)
    c0(u) = c0a + c0b u,  Fd(u) = Fda + Fdb u

x [m] is the damper displacement, v the record's velocity [m/s], e its electrical input; the
dimensionless Dahl variable z starts at 0 (rest) and, for ``sigma > 0``, stays in [-1, 1] for any
motion: every model inside the identification bounds is stable. Identified by output error
(:mod:`.fit`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.hysteresis.fit import FitSpec, Scales, unit_floors
from mrdamper.models.hysteresis.model import HysteresisEstimator, HysteresisModel

__all__ = ["IDENTIFIED", "DahlEstimator", "DahlModel"]

_INF = np.inf

#: Identified parameters (names of ``start``, ``fixed`` and ``bounds``).
IDENTIFIED: tuple[str, ...] = ("c0a", "c0b", "k0", "Fda", "Fdb", "sigma", "f0")


@dataclass(frozen=True, kw_only=True)
class DahlModel(HysteresisModel):
    """Identified modified Dahl model; an immutable value.

    Parameters
    ----------
    c0a, c0b : float
        Viscous damping ``c0 = c0a + c0b u`` [N s/m], [N s/(m U)] (U: A or V).
    k0 : float
        Stiffness [N/m].
    Fda, Fdb : float
        Dahl (friction) force ``Fd = Fda + Fdb u`` [N], [N/U].
    sigma : float
        Rate of the Dahl variable per metre of travel [1/m], non-negative.
    eta, f0, substeps
        Drive-lag rate [1/s] (0: none), force offset [N], RK4 sub-steps (0: automatic).
    """

    kind: ClassVar[str] = "dahl"
    family: ClassVar[str] = "dahl"

    c0a: float
    c0b: float
    k0: float
    Fda: float
    Fdb: float
    sigma: float

    def _check(self) -> None:
        if self.sigma < 0.0:
            raise DataValidationError("sigma", f"expected a rate >= 0 [1/m], got {self.sigma!r}")


def _start(reg: np.ndarray, yield_disp: float, s: Scales) -> dict[str, float]:
    fa, fb, ca, cb, k, f0 = (float(c) for c in reg)
    return {
        "c0a": max(ca, 1e-2 * s.force / s.v),
        "c0b": max(cb, 0.0),
        "k0": k,
        "Fda": max(fa, 1e-2 * s.force),
        "Fdb": max(fb, 0.0),
        "sigma": 2.0 / yield_disp,  # z at 86 % of its bound after the yield displacement
        "f0": f0,
    }


SPEC = FitSpec(
    family="dahl",
    unknowns=IDENTIFIED,
    bounds={
        "c0a": (0.0, _INF),
        "c0b": (0.0, _INF),
        "k0": (-_INF, _INF),
        "Fda": (0.0, _INF),
        "Fdb": (0.0, _INF),
        "sigma": (0.0, _INF),
        "f0": (-_INF, _INF),
    },
    start=_start,
    floors=unit_floors(
        {
            "c0a": "damp",
            "c0b": "damp/e",
            "k0": "stiff",
            "Fda": "force",
            "Fdb": "force/e",
            "sigma": "1/x",
            "f0": "force",
        }
    ),
    to_params=dict,
    single_fixed=lambda start: {"c0b": 0.0, "Fdb": 0.0},
    jitter_skip=("f0", "k0"),
)


@dataclass
class DahlEstimator(HysteresisEstimator):
    """Identify a :class:`DahlModel` by output error (settings: see
    :class:`~mrdamper.models.hysteresis.model.HysteresisEstimator`; parameter names:
    :data:`IDENTIFIED`). At a single input level ``c0b`` and ``Fdb`` are fixed at 0."""

    kind: ClassVar[str] = "dahl"
    model_class: ClassVar[type[FittedModel]] = DahlModel
    spec: ClassVar[FitSpec] = SPEC
