"""Current driver of the damper coil: a first-order lag with a limited output range."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.rig._rig_kernels import first_order_lag

__all__ = ["CurrentDriver"]


@dataclass(frozen=True)
class CurrentDriver:
    """Amplifier driving the damper's electrical input.

    The output follows the command through a first-order lag ``tau di/dt = i_cmd - i``,
    discretised exactly for a command held over each sampling interval, starting at the first
    command value. Commands outside ``limits`` are refused (a real driver would saturate; the rig
    reports it instead of silently clipping).

    Parameters
    ----------
    time_constant : float
        Lag tau [s] of the driver and coil inductance (default 0.01 s).
    limits : (float, float)
        Output range [A] (default 0-4 A, the paper's rig). For a damper whose input is the command
        voltage the same limits apply in [V].
    """

    time_constant: float = 0.01
    limits: tuple[float, float] = (0.0, 4.0)

    def __post_init__(self) -> None:
        tau = float(self.time_constant)
        if isinstance(self.time_constant, bool) or not (math.isfinite(tau) and tau >= 0):
            raise DataValidationError(
                "time_constant", f"expected a finite value >= 0 [s], got {self.time_constant!r}"
            )
        lo, hi = (float(b) for b in self.limits)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise DataValidationError(
                "limits", f"expected finite (low, high) with low < high, got {self.limits!r}"
            )
        object.__setattr__(self, "time_constant", tau)
        object.__setattr__(self, "limits", (lo, hi))

    def drive(self, i_command: np.ndarray, fs: float) -> np.ndarray:
        """Output current [A] for a command sampled at ``fs`` [Hz]."""
        cmd = np.ascontiguousarray(i_command, dtype=np.float64)
        lo, hi = self.limits
        bad = np.flatnonzero((cmd < lo) | (cmd > hi))
        if bad.size:
            k = int(bad[0])
            raise DataValidationError(
                "i_command",
                f"value {cmd[k]:.6g} at sample {k} is outside the driver range [{lo:g}, {hi:g}]",
            )
        alpha = math.exp(-1.0 / (fs * self.time_constant)) if self.time_constant > 0 else 0.0
        return first_order_lag(cmd, alpha, float(cmd[0]))
