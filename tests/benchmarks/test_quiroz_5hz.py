"""The Quiroz 5 Hz diagnosis's two measures: the steady cycles of a ramped sine and the floor of
a periodic fit, on records whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import load_benchmark


def _ramped(fs: float = 200.0, f: float = 5.1, cycles: int = 10) -> tuple[np.ndarray, np.ndarray]:
    half = 0.5 / f
    t = np.arange(round((cycles / f + 2 * half) * fs)) / fs
    env = np.clip(np.minimum(t, t[-1] - t) / half, 0.0, 1.0)
    return t, 0.002 * np.sin(2 * np.pi * f * t) * (0.5 - 0.5 * np.cos(np.pi * env))


def test_the_steady_cycles_leave_out_the_ramps_and_keep_full_amplitude() -> None:
    bench = load_benchmark("quiroz_5hz")
    t, x = _ramped()
    s = bench.steady(x, 200.0, 5.0)
    period = 200.0 / 5.1
    assert t[s.start] > 0.5 / 5.1 and t[-1] - t[s.stop] > 0.5 / 5.1  # the ramps are out
    assert s.stop - s.start > 6 * period  # most of the ten cycles are in
    assert np.abs(x[s]).max() == pytest.approx(np.abs(x).max())


def test_the_periodic_floor_is_the_share_of_what_no_periodic_force_explains() -> None:
    bench = load_benchmark("quiroz_5hz")
    rng = np.random.default_rng(0)
    t, x = _ramped()
    s = bench.steady(x, 200.0, 5.0)  # nominal 5 Hz, true 5.1 Hz: the fit finds the frequency
    v = np.gradient(x, t)
    periodic = 1000.0 * np.tanh(v[s] / 0.02) + 200.0 * np.sin(2 * np.pi * 3 * 5.1 * t[s])
    noise = rng.normal(0.0, 100.0, periodic.size)
    floor = bench.periodic_floor(t[s], x[s], periodic + noise, 5.0)
    share = np.var(noise) / np.var(periodic + noise)
    assert floor == pytest.approx(share, rel=0.25)  # the noise, less what 61 columns absorb
    assert bench.periodic_floor(t[s], x[s], periodic, 5.0) < 0.01 * share
