"""APRBS, ICPS, stepped current, constant and sine generators."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrdamper.errors import DataValidationError
from mrdamper.signals import (
    aprbs,
    constant,
    icps,
    n_samples,
    ramped_sine,
    sine,
    stepped_current,
    time_grid,
)
from mrdamper.signals.aprbs import run_starts


def _run_lengths(x: np.ndarray) -> np.ndarray:
    return np.diff(np.append(run_starts(x), x.size))


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    low=st.floats(0.0, 1.0),
    width=st.floats(0.1, 3.0),
    min_hold=st.sampled_from([0.01, 0.05, 0.2]),
)
def test_aprbs_levels_in_range_and_min_hold(
    seed: int, low: float, width: float, min_hold: float
) -> None:
    x = aprbs(1000.0, 4.0, low=low, high=low + width, min_hold=min_hold, seed=seed)
    assert x.size == 4000
    assert x.min() >= low and x.max() <= low + width
    hold = round(min_hold * 1000)
    lengths = _run_lengths(x)
    assert np.all(lengths[:-1] >= hold)
    assert np.all(lengths[:-1] % hold == 0)


def test_aprbs_levels_spread_over_range() -> None:
    x = aprbs(1000.0, 60.0, low=0.0, high=1.0, min_hold=0.1, seed=3)
    levels = x[run_starts(x)]
    assert levels.size > 100
    # uniform draws: every tenth of the range is visited
    assert np.all(np.histogram(levels, bins=10, range=(0, 1))[0] > 0)
    assert np.array_equal(x, aprbs(1000.0, 60.0, low=0.0, high=1.0, min_hold=0.1, seed=3))
    assert not np.array_equal(x, aprbs(1000.0, 60.0, low=0.0, high=1.0, min_hold=0.1, seed=4))


def test_seed_sequence_is_not_consumed() -> None:
    ss = np.random.SeedSequence(11)
    a = aprbs(1000.0, 5.0, low=0.0, high=1.0, min_hold=0.2, seed=ss)
    b = aprbs(1000.0, 5.0, low=0.0, high=1.0, min_hold=0.2, seed=ss)
    assert a.tobytes() == b.tobytes()


def test_icps_binary_has_long_dwell() -> None:
    x = icps(1000.0, 30.0, low=0.0, high=1.0, clock_period=1.5, seed=0)
    assert set(np.unique(x).tolist()) == {0.0, 1.0}
    lengths = _run_lengths(x)
    assert np.all(lengths[:-1] % 1500 == 0) and lengths.min() >= 1 and lengths[:-1].min() >= 1500


def test_icps_multilevel() -> None:
    x = icps(1000.0, 100.0, low=0.0, high=2.0, clock_period=1.0, n_levels=5, seed=9)
    assert set(np.unique(x).tolist()) == {0.0, 0.5, 1.0, 1.5, 2.0}
    # values change only on clock boundaries
    assert np.all(run_starts(x) % 1000 == 0)


def test_icps_rejects_bad_levels() -> None:
    with pytest.raises(DataValidationError, match="n_levels"):
        icps(1000.0, 5.0, low=0.0, high=1.0, n_levels=1, seed=0)
    with pytest.raises(DataValidationError, match="low/high"):
        icps(1000.0, 5.0, low=1.0, high=0.0, seed=0)


@pytest.mark.parametrize(
    "direction, expected",
    [
        ("up", [0.0, 0.5, 1.0]),
        ("down", [1.0, 0.5, 0.0]),
        ("up-down", [0.0, 0.5, 1.0, 0.5, 0.0]),
    ],
)
def test_stepped_current_levels_and_dwell(direction: str, expected: list[float]) -> None:
    x = stepped_current(1000.0, 30.0, low=0.0, high=1.0, n_levels=3, direction=direction)
    starts = run_starts(x)
    assert x[starts].tolist() == expected
    lengths = _run_lengths(x)
    assert lengths.max() - lengths.min() <= 1
    assert lengths.sum() == 30000


def test_stepped_current_rejects() -> None:
    with pytest.raises(DataValidationError, match="direction"):
        stepped_current(1000.0, 3.0, low=0.0, high=1.0, direction="sideways")  # type: ignore[arg-type]
    with pytest.raises(DataValidationError, match="n_levels"):
        stepped_current(10.0, 0.3, low=0.0, high=1.0, n_levels=5)


def test_constant_and_sine() -> None:
    assert np.all(constant(1000.0, 2.0, value=0.75) == 0.75)
    t = time_grid(1000.0, 2.0)
    x = sine(1000.0, 2.0, amplitude=0.005, frequency=3.0, offset=0.001, phase=0.3)
    np.testing.assert_allclose(x, 0.001 + 0.005 * np.sin(2 * np.pi * 3.0 * t + 0.3))
    assert n_samples(1000.0, 30.0) == 30000 == t.size * 15
    with pytest.raises(DataValidationError, match="frequency"):
        sine(100.0, 1.0, amplitude=1.0, frequency=60.0)
    with pytest.raises(DataValidationError, match="amplitude"):
        sine(100.0, 1.0, amplitude=-1.0, frequency=1.0)
    with pytest.raises(DataValidationError, match="value"):
        constant(100.0, 1.0, value=float("inf"))


def test_ramped_sine_rests_at_both_ends_and_holds_full_amplitude_between() -> None:
    fs, f, a = 1000.0, 2.0, 0.018
    x = ramped_sine(fs, amplitude=a, frequency=f, cycles=3)
    assert x.size == round(4 / f * fs) and x[0] == 0.0 and abs(x[-1]) < 1e-3 * a
    t = np.arange(x.size) / fs
    steady = (t >= 0.5 / f) & (t <= t[-1] - 0.5 / f)  # between the half-period ramps
    np.testing.assert_allclose(x[steady], a * np.sin(2 * np.pi * f * t[steady]), atol=1e-12)
    assert np.max(np.abs(x[t < 0.25 / f])) < 0.5 * a  # the ramp: well below full amplitude
    for bad in ({"cycles": 0}, {"cycles": 2.5}, {"frequency": 600.0}, {"amplitude": -1.0}):
        kw = {"amplitude": a, "frequency": f, "cycles": 2, **bad}
        with pytest.raises(DataValidationError, match=next(iter(bad))) as err:
            ramped_sine(fs, **kw)  # type: ignore[arg-type]
        assert "\n" not in str(err.value)
