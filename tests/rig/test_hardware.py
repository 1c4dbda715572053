"""Actuator, current driver and sensors of the virtual rig."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrdamper.errors import DataValidationError
from mrdamper.rig import CurrentDriver, Sensor, ServoActuator

FS = 1000.0


def _gain_phase(y: np.ndarray, u: np.ndarray, f: float, t: np.ndarray) -> tuple[float, float]:
    basis = np.exp(-2j * np.pi * f * t)
    H = (y @ basis) / (u @ basis)
    return float(abs(H)), float(np.angle(H))


def test_actuator_tracks_slow_motion_and_matches_second_order_response() -> None:
    act = ServoActuator(bandwidth=20.0, damping=0.7)
    t = np.arange(20000) / FS
    wn = 2 * np.pi * 20.0
    for f in (0.5, 5.0, 20.0):
        u = 0.01 * np.sin(2 * np.pi * f * t)
        x, v = act.track(u, FS)
        keep = t >= 2.0  # past the start transient; whole periods
        g, p = _gain_phase(x[keep], u[keep], f, t[keep])
        w = 2 * np.pi * f
        H = wn**2 / (
            wn**2 - w**2 + 2j * 0.7 * wn * w
        )  # continuous loop; at wn: 1/(2 zeta), -90 deg
        # the zero-order hold of the command adds about half a sample of delay
        assert g == pytest.approx(abs(H), rel=0.005)
        assert p == pytest.approx(np.angle(H) - w / (2 * FS), abs=0.005)
    # velocity is the derivative of position
    u = 0.01 * np.sin(2 * np.pi * 2.0 * t)
    x, v = act.track(u, FS)
    np.testing.assert_allclose(v[100:-1], np.gradient(x, 1 / FS)[100:-1], atol=1e-3)


def test_actuator_refuses_to_leave_the_stroke() -> None:
    act = ServoActuator(stroke=0.04)
    with pytest.raises(DataValidationError, match="x_command"):
        act.track(np.full(100, 0.021), FS)
    # a step to just inside the stroke overshoots it (zeta = 0.3) and is refused, not clipped
    step = np.r_[np.zeros(50), np.full(500, 0.0195)]
    with pytest.raises(DataValidationError, match="overshoots"):
        ServoActuator(damping=0.3).track(step, FS)


def test_driver_lag_and_limits() -> None:
    drv = CurrentDriver(time_constant=0.02, limits=(0.0, 4.0))
    cmd = np.r_[np.zeros(10), np.ones(200)]
    i = drv.drive(cmd, FS)
    # first-order step response: i[10 + m] = 1 - exp(-m dt / tau) for a command step at sample 10
    k = 10 + 20
    assert i[k] == pytest.approx(1 - math.exp(-1.0), rel=1e-9)
    assert np.all((i >= 0) & (i <= 1))
    with pytest.raises(DataValidationError, match="i_command"):
        drv.drive(np.array([0.0, 4.5]), FS)
    with pytest.raises(DataValidationError, match="limits"):
        CurrentDriver(limits=(1.0, 0.0))
    np.testing.assert_array_equal(CurrentDriver(time_constant=0.0).drive(cmd, FS)[1:], cmd[:-1])


def test_sensor_noise_quantisation_and_range() -> None:
    s = Sensor("F", noise_std=2.0, resolution=0.25, range=(-100.0, 100.0))
    rng = np.random.default_rng(0)
    true = np.linspace(-50, 50, 200_000)
    y = s.measure(true, rng)
    assert np.std(y - true) == pytest.approx(math.sqrt(2.0**2 + 0.25**2 / 12), rel=0.02)
    np.testing.assert_allclose((y + 100.0) / 0.25, np.rint((y + 100.0) / 0.25), atol=1e-9)
    # readings near the range end saturate like a converter, true overloads raise
    edge = s.measure(np.full(1000, 99.9), rng)
    assert edge.max() == 100.0
    with pytest.raises(DataValidationError, match="overloads"):
        s.measure(np.array([0.0, 150.0]), rng)
    with pytest.raises(DataValidationError, match="noise_std"):
        Sensor("x", noise_std=-1.0, resolution=0.0, range=(0, 1))
