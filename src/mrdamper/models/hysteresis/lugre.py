"""LuGre friction model adapted to MR dampers (Jiménez and Álvarez-Icaza 2005).

Equations (Jiménez & Álvarez-Icaza, "LuGre friction model for a magnetorheological damper",
Structural Control and Health Monitoring 12(1):91-116, 2005), with the electrical input u in
place of their voltage, a force offset and an optional first-order drive lag::

    F     = sigma_a z + sigma_0 z u + sigma_1 dz/dt + sigma_2 v + sigma_b v u + f0
    dz/dt = v - sigma_0 a0 |v| z
    du/dt = -eta (u - e)            (eta = 0: u = e)

x [m] is the damper displacement (unused by the force), v the record's velocity [m/s], e its
electrical input; the bristle deflection z [m] starts at 0 (rest) and, for ``sigma_0 a0 > 0``,
stays within ``1 / (sigma_0 a0)`` for any motion. The bristle stiffness ``sigma_a + sigma_0 u``
and the viscous damping ``sigma_2 + sigma_b u`` grow with the input.

Identified by output error (:mod:`.fit`) with ``a0`` in the unknown ``rate = sigma_0 a0``
[1/m] (so that the bristle bound ``1 / rate`` has its own scale); every unknown is bounded
non-negative (``rate`` positive), so every model inside the bounds is stable.
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

__all__ = ["IDENTIFIED", "LuGreEstimator", "LuGreModel"]

_INF = np.inf
#: Share of the yield force carried by ``sigma_0 u z`` in the first start when the regression
#: finds none (``sigma_0`` must be positive: it sets the bristle rate with ``a0``).
SIGMA0_SHARE = 0.05

#: Identified parameters (names of ``start``, ``fixed`` and ``bounds``).
IDENTIFIED: tuple[str, ...] = (
    "sigma_a",
    "sigma_0",
    "rate",
    "sigma_1",
    "sigma_2",
    "sigma_b",
    "f0",
)


@dataclass(frozen=True, kw_only=True)
class LuGreModel(HysteresisModel):
    """Identified LuGre model of an MR damper; an immutable value.

    Parameters
    ----------
    sigma_a : float
        Bristle stiffness at zero input [N/m].
    sigma_0 : float
        Input-dependent bristle stiffness [N/(m U)] (U: A or V); with ``a0`` it also sets the
        bristle rate.
    sigma_1 : float
        Bristle damping [N s/m].
    sigma_2, sigma_b : float
        Viscous damping ``sigma_2 + sigma_b u`` [N s/m], [N s/(m U)].
    a0 : float
        Bristle rate per unit of ``sigma_0`` [m U/N]: ``sigma_0 a0`` [1/m].
    eta, f0, substeps
        Drive-lag rate [1/s] (0: none), force offset [N], RK4 sub-steps (0: automatic).
    """

    kind: ClassVar[str] = "lugre"
    family: ClassVar[str] = "lugre"

    sigma_a: float
    sigma_0: float
    sigma_1: float
    sigma_2: float
    sigma_b: float
    a0: float

    def _check(self) -> None:
        if self.sigma_0 < 0.0:
            raise DataValidationError("sigma_0", f"expected a value >= 0, got {self.sigma_0!r}")
        if self.a0 < 0.0:
            raise DataValidationError("a0", f"expected a value >= 0, got {self.a0!r}")


def _start(reg: np.ndarray, yield_disp: float, s: Scales) -> dict[str, float]:
    fa, fb, ca, cb, _, f0 = (float(c) for c in reg)
    fa = max(fa, 1e-2 * s.force)
    # z saturates at the yield displacement 1 / rate, where sigma(u) z carries the yield force
    return {
        "sigma_a": fa / yield_disp,
        "sigma_0": max(fb, SIGMA0_SHARE * fa / s.e) / yield_disp,
        "rate": 1.0 / yield_disp,
        "sigma_1": 0.1 * max(ca, 1e-2 * s.force / s.v),
        "sigma_2": max(ca, 1e-2 * s.force / s.v),
        "sigma_b": max(cb, 0.0),
        "f0": f0,
    }


def _published(theta: Mapping[str, float]) -> dict[str, float]:
    out = {k: v for k, v in theta.items() if k != "rate"}
    out["a0"] = theta["rate"] / theta["sigma_0"]
    return out


SPEC = FitSpec(
    family="lugre",
    unknowns=IDENTIFIED,
    bounds={
        "sigma_a": (0.0, _INF),
        "sigma_0": (0.0, _INF),
        "rate": (0.0, _INF),
        "sigma_1": (0.0, _INF),
        "sigma_2": (0.0, _INF),
        "sigma_b": (0.0, _INF),
        "f0": (-_INF, _INF),
    },
    start=_start,
    floors=unit_floors(
        {
            "sigma_a": "stiff",
            "sigma_0": "stiff/e",
            "rate": "1/x",
            "sigma_1": "damp",
            "sigma_2": "damp",
            "sigma_b": "damp/e",
            "f0": "force",
        }
    ),
    to_params=_published,
    # one level: sigma_0 u z is a constant share of the bristle stiffness, redundant with sigma_a
    single_fixed=lambda start: {"sigma_b": 0.0, "sigma_0": start["sigma_0"]},
    jitter_skip=("f0",),
)


@dataclass
class LuGreEstimator(HysteresisEstimator):
    """Identify a :class:`LuGreModel` by output error (settings: see
    :class:`~mrdamper.models.hysteresis.model.HysteresisEstimator`; parameter names:
    :data:`IDENTIFIED`). At a single input level ``sigma_b`` is fixed at 0 and ``sigma_0`` at its
    start value (its force term is then a constant, redundant with ``sigma_a``)."""

    kind: ClassVar[str] = "lugre"
    model_class: ClassVar[type[FittedModel]] = LuGreModel
    spec: ClassVar[FitSpec] = SPEC
