"""Energy per displacement cycle against closed-form loop areas."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.analysis import cycle_starts, energy_per_cycle
from mrdamper.errors import DataValidationError

X, f = 0.012, 1.5  # amplitude [m], frequency [Hz]
w = 2 * np.pi * f
t = np.arange(0.0, 4.0, 1e-4)
x = X * np.sin(w * t)
v = X * w * np.cos(w * t)


def test_viscous_loop_area_is_pi_c_w_x2() -> None:
    c = 1500.0  # N s/m; an ellipse of area pi c w X^2 (textbook viscous damping)
    W = energy_per_cycle(t, x, v, c * v)
    assert (
        len(W) == 4
    )  # starts (upward crossings) at 2/3, 4/3, 2, 8/3, 10/3 s: four complete cycles
    # cycles start at the first sample past a crossing: up to 2 dt / T = 3e-4 of a period off
    np.testing.assert_allclose(W, np.pi * c * w * X**2, rtol=5e-4)


def test_friction_loop_area_is_4_f0_x() -> None:
    F0 = 800.0  # N; a rectangle 2X wide and 2 F0 high
    W = energy_per_cycle(t, x, v, F0 * np.sign(v))
    np.testing.assert_allclose(W, 4 * F0 * X, rtol=1e-3)


def test_an_elastic_force_dissipates_nothing() -> None:
    W = energy_per_cycle(t, x, v, 2e4 * x)
    assert np.all(np.abs(W) < 1e-5 * 0.5 * 2e4 * X**2)  # vs the stored energy at full stroke


def test_noise_near_the_mid_range_does_not_split_cycles() -> None:
    noisy = x + 0.02 * X * np.random.default_rng(0).standard_normal(t.size)
    assert (
        len(cycle_starts(noisy)) == len(cycle_starts(x)) == 5
    )  # upward crossings after t = 0 in 4 s
    with pytest.raises(DataValidationError, match="band"):
        cycle_starts(x, band=1.5)
    with pytest.raises(DataValidationError, match="F"):
        energy_per_cycle(t, x, v, np.full(t.size, np.nan))
