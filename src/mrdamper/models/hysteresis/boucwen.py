"""Classic Bouc-Wen model of an MR damper (no internal mass-spring), current dependent.

Equations (the Bouc-Wen model of Spencer, Dyke, Sain & Carlson, "Phenomenological model of a
magnetorheological damper", J. Eng. Mech. 123(3):230-238, 1997, section "Bouc-Wen model", before
their modified model adds the internal dashpot and spring), with the evolutionary coefficient and
the damping linear in the electrical input and an optional first-order drive lag::

    F     = c0(u) v + k0 x + alpha(u) z + f0
    dz/dt = -gamma |v| z |z|**(n-1) - beta v |z|**n + A v
    du/dt = -eta (u - e)            (eta = 0: u = e)
    c0(u) = c0a + c0b u,  alpha(u) = alpha_a + alpha_b u

The published ``k0 (x - x0)`` is written ``k0 x + f0`` (``f0 = -k0 x0``, plus any load-cell
offset). x [m], v the record's velocity [m/s], e its electrical input; z starts at 0 (rest).

Identified by output error (:mod:`.fit`) with ``beta`` and ``gamma`` in the unknowns
``z_max > 0`` and ``shape`` in [0, 1]::

    beta + gamma = A / z_max**n,   beta - gamma = shape (beta + gamma)

so that ``|gamma| <= beta``: with ``A > 0`` the evolutionary variable stays within ``z_max`` for
any motion, and every model inside the bounds is stable. ``z_max`` also keeps the saturation of
z apart from the exponent ``n`` (``beta + gamma`` alone would tie them). ``A`` is fixed at 1 by
default (redundant with the scale of z).
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

__all__ = ["IDENTIFIED", "BoucWenEstimator", "BoucWenModel"]

_INF = np.inf
#: Bouc-Wen exponent of the first start [-].
N_START = 2.0

#: Identified parameters (names of ``start``, ``fixed`` and ``bounds``).
IDENTIFIED: tuple[str, ...] = (
    "c0a",
    "c0b",
    "k0",
    "alpha_a",
    "alpha_b",
    "z_max",
    "shape",
    "A",
    "n",
    "f0",
)


@dataclass(frozen=True, kw_only=True)
class BoucWenModel(HysteresisModel):
    """Identified classic Bouc-Wen model; an immutable value.

    Parameters
    ----------
    c0a, c0b : float
        Viscous damping ``c0 = c0a + c0b u`` [N s/m], [N s/(m U)] (U: A or V).
    k0 : float
        Stiffness [N/m].
    alpha_a, alpha_b : float
        Evolutionary coefficient ``alpha = alpha_a + alpha_b u`` [N/m], [N/(m U)] (z in metres
        when ``A`` is dimensionless).
    gamma, beta : float
        Hysteresis shape parameters [m^-n].
    A : float
        Scale of the evolutionary variable [-].
    n : float
        Exponent [-], at least 1.
    eta, f0, substeps
        Drive-lag rate [1/s] (0: none), force offset [N], RK4 sub-steps (0: automatic).
    """

    kind: ClassVar[str] = "boucwen"
    family: ClassVar[str] = "boucwen"

    c0a: float
    c0b: float
    k0: float
    alpha_a: float
    alpha_b: float
    gamma: float
    beta: float
    A: float
    n: float

    def _check(self) -> None:
        if self.n < 1.0:
            raise DataValidationError("n", f"expected a Bouc-Wen exponent >= 1, got {self.n!r}")


def _start(reg: np.ndarray, yield_disp: float, s: Scales) -> dict[str, float]:
    fa, fb, ca, cb, k, f0 = (float(c) for c in reg)
    # z saturates at the yield displacement (A = 1)
    return {
        "c0a": max(ca, 1e-2 * s.force / s.v),
        "c0b": max(cb, 0.0),
        "k0": k,
        "alpha_a": max(fa, 1e-2 * s.force) / yield_disp,
        "alpha_b": max(fb, 0.0) / yield_disp,
        "z_max": yield_disp,
        "shape": 0.2,
        "A": 1.0,
        "n": N_START,
        "f0": f0,
    }


def _published(theta: Mapping[str, float]) -> dict[str, float]:
    out = {k: v for k, v in theta.items() if k not in ("z_max", "shape")}
    total = theta["A"] / theta["z_max"] ** theta["n"]
    out["beta"] = 0.5 * total * (1.0 + theta["shape"])
    out["gamma"] = 0.5 * total * (1.0 - theta["shape"])
    return out


SPEC = FitSpec(
    family="boucwen",
    unknowns=IDENTIFIED,
    bounds={
        "c0a": (0.0, _INF),
        "c0b": (0.0, _INF),
        "k0": (-_INF, _INF),
        "alpha_a": (0.0, _INF),
        "alpha_b": (0.0, _INF),
        "z_max": (0.0, _INF),
        "shape": (0.0, 1.0),
        "A": (0.0, _INF),
        "n": (1.0, 4.0),
        "f0": (-_INF, _INF),
    },
    start=_start,
    floors=unit_floors(
        {
            "c0a": "damp",
            "c0b": "damp/e",
            "k0": "stiff",
            "alpha_a": "stiff",
            "alpha_b": "stiff/e",
            "z_max": "x",
            "shape": "one",
            "A": "one",
            "n": "one",
            "f0": "force",
        }
    ),
    to_params=_published,
    single_fixed=lambda start: {"c0b": 0.0, "alpha_b": 0.0},
    default_fixed={"A": 1.0},
    jitter_skip=("f0", "k0", "n", "A"),
)


@dataclass
class BoucWenEstimator(HysteresisEstimator):
    """Identify a :class:`BoucWenModel` by output error (settings: see
    :class:`~mrdamper.models.hysteresis.model.HysteresisEstimator`; parameter names:
    :data:`IDENTIFIED`; ``A`` fixed at 1 unless ``fixed`` says otherwise). At a single input
    level ``c0b`` and ``alpha_b`` are fixed at 0."""

    kind: ClassVar[str] = "boucwen"
    model_class: ClassVar[type[FittedModel]] = BoucWenModel
    spec: ClassVar[FitSpec] = SPEC
