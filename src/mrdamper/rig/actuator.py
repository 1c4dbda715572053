"""Servo-hydraulic displacement actuator: a second-order position loop of limited bandwidth."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from mrdamper.errors import DataValidationError
from mrdamper.rig._rig_kernels import second_order_track
from mrdamper.signals.road import DEFAULT_STROKE

__all__ = ["ServoActuator"]


@functools.lru_cache(maxsize=32)
def _zoh(bandwidth: float, damping: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation of the servo loop (cached: the DoE reuses one rig)."""
    wn = 2.0 * math.pi * bandwidth
    M = np.zeros((3, 3))
    M[:2, :2] = [[0.0, 1.0], [-wn * wn, -2.0 * damping * wn]]
    M[1, 2] = wn * wn
    E = expm(M / fs)
    return np.ascontiguousarray(E[:2, :2]), np.ascontiguousarray(E[:2, 2])


@dataclass(frozen=True)
class ServoActuator:
    """Closed-loop hydraulic actuator tracking a displacement command.

    The loop is modelled as ``x'' = wn^2 (x_cmd - x) - 2 zeta wn x'`` with ``wn = 2 pi bandwidth``,
    discretised exactly for a command held constant over each sampling interval (zero-order hold).
    It starts at rest at the first command value. Tracking is unity-gain at low frequency, with
    phase lag and amplitude change near ``bandwidth``.

    Parameters
    ----------
    bandwidth : float
        Natural frequency of the position loop [Hz] (default 30 Hz; well above the 4.2-5.5 Hz of
        the paper's excitation).
    damping : float
        Damping ratio zeta [-] (default 0.7).
    stroke : float
        Total stroke [m]; positions are about mid-stroke and must stay within ``+-stroke / 2``.
    """

    bandwidth: float = 30.0
    damping: float = 0.7
    stroke: float = DEFAULT_STROKE

    def __post_init__(self) -> None:
        for name, value, unit in (
            ("bandwidth", self.bandwidth, "Hz"),
            ("damping", self.damping, "-"),
            ("stroke", self.stroke, "m"),
        ):
            if isinstance(value, bool) or not (math.isfinite(float(value)) and float(value) > 0):
                raise DataValidationError(
                    name, f"expected a finite value > 0 [{unit}], got {value!r}"
                )
            object.__setattr__(self, name, float(value))

    def discretise(self, fs: float) -> tuple[np.ndarray, np.ndarray]:
        """State transition matrix ``phi`` and input vector ``gamma`` for sampling rate ``fs``
        [Hz]."""
        if self.bandwidth >= fs / 2:
            raise DataValidationError(
                "bandwidth",
                f"{self.bandwidth:g} Hz is not below the Nyquist frequency {fs / 2:g} Hz",
            )
        phi, gamma = _zoh(self.bandwidth, self.damping, float(fs))
        return phi.copy(), gamma.copy()

    def track(self, x_command: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
        """Actuator position [m] and velocity [m/s] for a command sampled at ``fs`` [Hz].

        Raises
        ------
        DataValidationError
            If the command or the resulting motion (overshoot included) leaves ``+-stroke / 2``.
        """
        half = self.stroke / 2.0
        cmd = np.ascontiguousarray(x_command, dtype=np.float64)
        peak = float(np.max(np.abs(cmd)))
        if peak > half:
            k = int(np.argmax(np.abs(cmd)))
            raise DataValidationError(
                "x_command",
                f"reaches {cmd[k]:.5g} m at sample {k}, outside +-stroke/2 = {half:g} m about "
                "mid-stroke",
            )
        phi, gamma = self.discretise(fs)
        x, v = second_order_track(cmd, phi, gamma, float(cmd[0]), 0.0)
        over = np.flatnonzero(np.abs(x) > half)
        if over.size:
            k = int(over[0])
            raise DataValidationError(
                "x_command",
                f"the actuator overshoots to {x[k]:.5g} m at sample {k}, outside "
                f"+-stroke/2 = {half:g} m; reduce the command amplitude",
            )
        return x, v
