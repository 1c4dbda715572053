"""The scheduled-stroke diagnosis's Dahl state and input against the project's."""

from __future__ import annotations

import numpy as np

from mrdamper.analysis.hysteretic import dahl_state
from mrdamper.models.lpv import inputs as lpv_inputs
from tests.conftest import load_benchmark
from tests.control.test_export import LAWS


def test_a_constant_stroke_is_the_projects_dahl_state_and_a_larger_one_saturates_later() -> None:
    bench = load_benchmark("scheduled_stroke")
    t = np.arange(4000) * 1e-3
    v = 0.02 * np.sin(2 * np.pi * 2.0 * t)  # 1.6 mm amplitude at 2 Hz
    same = bench.dahl_scheduled(v, 1e-3, np.full(v.size, 1e-4))
    np.testing.assert_array_equal(same, dahl_state(v, 1e-3, 1e-4))
    first_rise = slice(1, 100)  # the first 0.1 s: the displacement grows from rest
    wider = bench.dahl_scheduled(v, 1e-3, np.full(v.size, 3e-4))
    assert np.all(wider[first_rise] < same[first_rise])


def test_the_input_with_k_zero_is_the_projects_input() -> None:
    bench = load_benchmark("scheduled_stroke")
    hyst = lpv_inputs.HystereticInput(LAWS, "continuous", 1e-4, 0.5)
    rng = np.random.default_rng(3)
    v = np.convolve(rng.normal(scale=0.05, size=3000), np.ones(20) / 20, mode="same")
    rho = np.clip(np.cumsum(rng.normal(scale=0.02, size=3000)), 0.0, 2.0)
    project = hyst.signal(v, rho, 1e-3)
    np.testing.assert_allclose(bench.scheduled_signal(0.0)(hyst, v, rho, 1e-3), project, rtol=1e-14)
    changed = bench.scheduled_signal(5.0)(hyst, v, rho, 1e-3)
    assert np.max(np.abs(changed - project)) > 1e-3 * np.max(np.abs(project))
