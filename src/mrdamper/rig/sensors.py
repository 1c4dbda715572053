"""Rig sensors: additive noise, quantisation and a finite measurement range.

Each :class:`Sensor` adds white Gaussian noise (seeded), rounds to its resolution (the ADC step)
and saturates at its range like a real converter. A *true* value outside the range is a sensor
overload and raises an error: the rig never hands out silently clipped data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["Sensor", "SensorSuite"]


@dataclass(frozen=True)
class Sensor:
    """One measurement channel.

    Parameters
    ----------
    name : str
        Channel name used in messages (``"x"``, ``"F"``, ``"i"``).
    noise_std : float
        Standard deviation of the additive white noise, in the channel's SI unit.
    resolution : float
        Quantisation step, in the channel's SI unit (0 for none).
    range : (float, float)
        Measurement range; readings saturate at its ends.
    """

    name: str
    noise_std: float
    resolution: float
    range: tuple[float, float]

    def __post_init__(self) -> None:
        for fld in ("noise_std", "resolution"):
            value = float(getattr(self, fld))
            if not (math.isfinite(value) and value >= 0):
                raise DataValidationError(
                    fld, f"{self.name}: expected a finite value >= 0, got {value!r}"
                )
            object.__setattr__(self, fld, value)
        lo, hi = (float(b) for b in self.range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise DataValidationError(
                "range", f"{self.name}: expected (low, high) with low < high, got {self.range!r}"
            )
        object.__setattr__(self, "range", (lo, hi))

    def measure(self, true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Reading of ``true`` values: noise, quantisation, saturation at the range.

        Raises
        ------
        DataValidationError
            If a true value lies outside the sensor's range (overload).
        """
        lo, hi = self.range
        bad = np.flatnonzero((true < lo) | (true > hi))
        if bad.size:
            k = int(bad[0])
            raise DataValidationError(
                self.name,
                f"true value {true[k]:.6g} at sample {k} overloads the sensor range [{lo:g}, "
                f"{hi:g}]",
            )
        y = (
            true + self.noise_std * rng.standard_normal(true.size)
            if self.noise_std > 0
            else true.copy()
        )
        if self.resolution > 0:
            y = lo + np.rint((y - lo) / self.resolution) * self.resolution
        return np.clip(y, lo, hi)


def _lvdt() -> Sensor:
    return Sensor("x", noise_std=5e-6, resolution=0.05 / 2**16, range=(-0.025, 0.025))


def _load_cell() -> Sensor:
    return Sensor("F", noise_std=2.0, resolution=10_000.0 / 2**16, range=(-5_000.0, 5_000.0))


def _current() -> Sensor:
    return Sensor("i", noise_std=2e-3, resolution=5.0 / 2**16, range=(0.0, 5.0))


@dataclass(frozen=True)
class SensorSuite:
    """The rig's three transducers (defaults: typical laboratory hardware, 16-bit converters).

    Parameters
    ----------
    displacement : Sensor
        Displacement transducer; default an LVDT, +-25 mm range, noise 5 um RMS, step 0.76 um.
    force : Sensor
        Load cell; default +-5 kN range, noise 2 N RMS, step 0.15 N.
    electrical : Sensor
        Current transducer; default 0-5 A range, noise 2 mA RMS, step 76 uA (for a damper
        driven by command voltage the same channel reads volts).
    """

    displacement: Sensor = field(default_factory=_lvdt)
    force: Sensor = field(default_factory=_load_cell)
    electrical: Sensor = field(default_factory=_current)

    @classmethod
    def ideal(cls) -> SensorSuite:
        """Noise-free sensors without quantisation (for checks against the damper model)."""
        return cls(
            displacement=Sensor("x", 0.0, 0.0, (-1.0, 1.0)),
            force=Sensor("F", 0.0, 0.0, (-1e9, 1e9)),
            electrical=Sensor("i", 0.0, 0.0, (-1e9, 1e9)),
        )
