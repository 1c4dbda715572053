"""The loop-replay diagnosis's measures on signals whose answers are known: the cross-spectral
magnitude and phase of a force against the velocity, and a frozen transfer function."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.models.lpv import LTIModel
from tests.conftest import load_benchmark


def test_a_viscous_force_has_its_coefficient_and_a_delayed_one_lags() -> None:
    bench = load_benchmark("loop_replay")
    rng = np.random.default_rng(1)
    fs = 1000.0
    v = np.convolve(rng.normal(size=40_000), np.ones(5) / 5, mode="same")  # broadband to 100 Hz
    viscous = bench.spectra(v, 1500.0 * v, fs)
    for magnitude, phase in viscous:
        assert magnitude == pytest.approx(1500.0, rel=1e-9) and abs(phase) < 1e-6
    delay = 5  # samples: 5 ms, -18 deg at 10 Hz
    lagged = bench.spectra(v[delay:], 1500.0 * v[:-delay], fs)
    phases = [p for _, p in lagged]
    assert phases == sorted(phases, reverse=True)  # the lag grows with frequency
    assert phases[-1] == pytest.approx(-360.0 * 15.0 * delay / fs, abs=4.0)  # 10-20 Hz band


def test_the_frozen_response_of_a_one_sample_delay() -> None:
    bench = load_benchmark("loop_replay")
    delay = LTIModel(
        alpha=np.zeros((1, 1)),
        beta=np.array([[2000.0]]),
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )
    table = bench.frozen_response(delay, (0.0,))
    np.testing.assert_allclose(table["gain"], 1.0, atol=1e-12)
    np.testing.assert_allclose(table["phase_deg"], -360.0 * table["f_Hz"] / 1000.0, atol=1e-9)
