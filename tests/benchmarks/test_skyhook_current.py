"""The skyhook-current diagnosis's measures on inputs whose answers are known."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from tests.conftest import load_benchmark
from tests.control.test_export import LAWS


def test_only_the_post_yield_slopes_are_scaled() -> None:
    bench = load_benchmark("skyhook_current")
    before = LAWS.gamma_m.copy()
    scaled = bench.scaled_outer_slopes(LAWS, 0.9)
    rho = np.array([0.0, 0.7, 2.0])
    m, m_scaled = LAWS.m(rho), scaled.m(rho)
    np.testing.assert_allclose(m_scaled[:, [0, 2]], 0.9 * m[:, [0, 2]], rtol=1e-12)
    np.testing.assert_array_equal(m_scaled[:, 1], m[:, 1])
    np.testing.assert_array_equal(scaled.gamma_c, LAWS.gamma_c)
    np.testing.assert_array_equal(LAWS.gamma_m, before)  # the laws given are not changed


def test_what_the_controller_saw() -> None:
    bench = load_benchmark("skyhook_current")
    n = 1000
    t = np.arange(n) * 1e-3
    run = SimpleNamespace(
        v_s=0.2 * np.sin(2 * np.pi * 5 * t),  # RMS 0.2 / sqrt(2)
        v_u=np.zeros(n),
        F_desired=np.where(np.arange(n) % 2 == 0, np.nan, -300.0),  # NaN: no force asked
        saturated=np.arange(n) % 4 == 0,
        i=np.full(n, 0.015),
    )
    seen = bench.demand(run)
    assert seen["rms_v_body"] == pytest.approx(0.2 / np.sqrt(2), rel=1e-9)
    assert seen["rms_v_damper"] == pytest.approx(seen["rms_v_body"], rel=1e-12)
    assert seen["mean_F_desired"] == pytest.approx(150.0)
    assert seen["out_of_reach"] == pytest.approx(0.25)
    assert seen["mean_input_milli"] == pytest.approx(15.0)


def test_the_summary_names_the_worst_other_cell() -> None:
    bench = load_benchmark("skyhook_current")
    table = pd.DataFrame(
        {
            "controller": ["skyhook", "skyhook", "hard", "soft"],
            "metric": ["mean_current", "a_w", "rms_travel", "mean_current"],
            "error_pct": [-7.5, 1.0, -3.0, np.nan],
        }
    )
    out = bench.summary(table)
    assert out["skyhook mean current [%]"] == -7.5
    assert out["worst other [%]"] == 3.0
    assert out["where"] == "['hard', 'rms_travel']"


def test_the_stiffened_car_adds_to_the_spring_only() -> None:
    bench = load_benchmark("skyhook_current")
    from mrdamper.control.loop.car import QuarterCar

    car = QuarterCar()
    stiff = bench.stiffened(car, 693.0)
    assert stiff.k_s == car.k_s + 693.0
    assert (stiff.m_s, stiff.m_u, stiff.k_t) == (car.m_s, car.m_u, car.k_t)


def test_the_stiffness_table_pairs_each_run_with_the_plants() -> None:
    """The true damper as its own model: the default car's errors are zero, and a stiffer car
    moves them (the table compares the right runs)."""
    bench = load_benchmark("skyhook_current")
    from mrdamper.rig.reference import reference_damper

    truth = reference_damper("quiroz2022")
    table = bench.stiffness_table(truth, truth, 2000.0, [0], duration=2.0, substeps=8)
    assert set(table.controller) == {"soft", "hard", "skyhook", "groundhook", "hybrid"}
    errors = table.error_pct.dropna()
    assert len(errors) >= 5 * 5 and np.all(errors == 0.0)
    stiff = table[table.metric == "rms_travel"].error_pct_stiffened
    assert np.all(stiff < 0.0)  # a stiffer spring: less travel on every controller
