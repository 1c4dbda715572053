"""Replicate-to-replicate variation of the damper: a seeded, temperature-like drift.

Repeating a test on a real rig never gives the same force twice: the fluid warms up, the
load-cell zero wanders, the damper settles. The rig reproduces this generically, for any
:class:`~mrdamper.models.FittedModel`, by scaling the model's force with a slowly varying gain and
adding an offset, all drawn per run from the run's seed::

    F_true(t) = (1 + g0 + g1 * t / T) * F_model(t) + f_offset

with ``g0 ~ N(0, gain_std)`` (run-to-run level, e.g. fluid temperature), ``g1 ~ N(0, drift_std)``
(warming or cooling within the run of length T) and ``f_offset ~ N(0, offset_std)`` [N].

Optionally, named scalar parameters of the damper (e.g. ``{"c0a": 0.03, "alpha_a": 0.03}`` for
:class:`~mrdamper.models.spencer.SpencerModel`) are multiplied by ``1 + N(0, std)`` per run, giving
a physically shaped variation for models that expose their parameters.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel

__all__ = ["DrawnVariation", "ReplicateVariation"]


@dataclass(frozen=True)
class DrawnVariation:
    """The variation drawn for one run.

    Attributes
    ----------
    damper : FittedModel
        The damper with its parameters perturbed (the original if no parameter drift).
    gain : float
        Run-level force gain offset g0 [-].
    drift : float
        Gain change over the run g1 [-].
    offset : float
        Force offset [N].
    parameters : dict
        Relative change applied to each perturbed parameter [-].
    """

    damper: FittedModel
    gain: float
    drift: float
    offset: float
    parameters: dict[str, float]

    def apply(self, F: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Force after gain, drift and offset [N]."""
        span = float(t[-1] - t[0]) or 1.0
        return (1.0 + self.gain + self.drift * (t - t[0]) / span) * F + self.offset

    def to_metadata(self) -> dict[str, Any]:
        """Flat metadata entries describing the drawn variation."""
        out: dict[str, Any] = {
            "force_gain": self.gain,
            "force_drift": self.drift,
            "force_offset": self.offset,
        }
        out.update({f"drift_{k}": v for k, v in self.parameters.items()})
        return out


@dataclass(frozen=True)
class ReplicateVariation:
    """Settings of the per-run damper variation (all standard deviations).

    Parameters
    ----------
    gain_std : float
        Run-to-run force gain [-] (default 0.02, i.e. 2 %).
    drift_std : float
        Gain change within a run [-] (default 0.01).
    offset_std : float
        Force offset [N] (default 5 N).
    parameter_std : mapping of str to float
        Relative standard deviation per named damper parameter (default none).
    """

    gain_std: float = 0.02
    drift_std: float = 0.01
    offset_std: float = 5.0
    parameter_std: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("gain_std", "drift_std", "offset_std"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0):
                raise DataValidationError(
                    name, f"expected a finite standard deviation >= 0, got {value!r}"
                )
            object.__setattr__(self, name, value)
        clean = {}
        for k, v in dict(self.parameter_std).items():
            fv = float(v)
            if not (math.isfinite(fv) and fv >= 0):
                raise DataValidationError(
                    "parameter_std", f"{k}: expected a relative std >= 0, got {v!r}"
                )
            clean[str(k)] = fv
        object.__setattr__(self, "parameter_std", clean)

    @classmethod
    def none(cls) -> ReplicateVariation:
        """No variation at all: every run uses the damper as given."""
        return cls(gain_std=0.0, drift_std=0.0, offset_std=0.0)

    def draw(self, damper: FittedModel, rng: np.random.Generator) -> DrawnVariation:
        """Draw one run's variation (always consumes the same number of random values)."""
        g0, g1, off = rng.standard_normal(3) * (self.gain_std, self.drift_std, self.offset_std)
        changes: dict[str, Any] = {}
        rel: dict[str, float] = {}
        params = damper.parameters
        for name in sorted(self.parameter_std):
            if (
                name not in params
                or isinstance(params[name], bool)
                or not isinstance(params[name], (int, float, np.floating, np.integer))
            ):
                scalars = sorted(
                    k for k, p in params.items() if isinstance(p, (float, np.floating))
                )
                raise DataValidationError(
                    "parameter_std",
                    f"{name!r} is not a scalar parameter of {damper.kind!r}; expected one of "
                    f"{scalars}",
                )
            r = float(rng.standard_normal() * self.parameter_std[name])
            rel[name] = r
            changes[name] = float(params[name]) * (1.0 + r)
        perturbed = dataclasses.replace(damper, **changes) if changes else damper
        return DrawnVariation(perturbed, float(g0), float(g1), float(off), rel)
