"""Preprocessing steps: known answers on synthetic signals, invariants, and input errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrdamper.data import Experiment
from mrdamper.data.preprocessing import (
    apply_drive_lag,
    decimate,
    dominant_frequency,
    estimate_velocity_cutoff,
    remove_offsets,
    trim,
    velocity_from_displacement,
)
from mrdamper.errors import DataValidationError

FS = 1000.0


def _sine(
    f: float = 3.0, amp: float = 0.005, n: int = 5000, seed: int = 1, **meta: float
) -> Experiment:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    x = amp * np.sin(2 * np.pi * f * t) + 2e-6 * rng.standard_normal(n)  # 2 um sensor noise
    F = 500 * np.sin(2 * np.pi * f * t + 0.3)
    return Experiment(t=t, x=x, v=np.zeros(n), F=F, i=np.full(n, 0.5), name="s", metadata=meta)


def test_velocity_known_answer_with_noise() -> None:
    f, amp = 3.0, 0.005
    e = _sine(f, amp, frequency=f)
    out = velocity_from_displacement(e)
    v_true = amp * 2 * np.pi * f * np.cos(2 * np.pi * f * e.t)
    inner = slice(200, -200)
    err = np.abs(out.v[inner] - v_true[inner]).max()
    assert err < 0.005 * np.abs(v_true).max()
    # The unfiltered central difference is far worse with the same noise: the filter matters.
    raw = np.gradient(e.x, e.t)
    assert np.abs(raw[inner] - v_true[inner]).max() > 5 * err
    assert out.metadata["velocity_cutoff"] == 30.0  # max(10 f, 20 Hz)
    assert "v = central difference" in out.metadata["processing"][-1]
    np.testing.assert_array_equal(out.x, e.x)
    assert "processing" not in e.metadata and np.all(e.v == 0)  # input untouched


def test_cutoff_estimation_rules() -> None:
    assert estimate_velocity_cutoff(_sine(frequency=0.5)) == 20.0  # floor of 20 Hz
    assert estimate_velocity_cutoff(_sine(frequency=100.0)) == pytest.approx(0.45 * FS)  # cap
    # Broadband: 2 x the frequency holding 99 % of the power of x.
    rng = np.random.default_rng(0)
    from scipy.signal import butter, sosfiltfilt

    x = sosfiltfilt(butter(8, 40, fs=FS, output="sos"), rng.standard_normal(20000))
    t = np.arange(x.size) / FS
    e = Experiment(t=t, x=x, v=0 * t, F=0 * t, i=0 * t)
    cut = estimate_velocity_cutoff(e)
    assert 70.0 < cut < 100.0
    with pytest.raises(DataValidationError, match="Nyquist") as info:
        velocity_from_displacement(e, cutoff=600.0)
    assert info.value.field == "cutoff"
    with pytest.raises(DataValidationError) as info:
        velocity_from_displacement(e, cutoff=-1.0)
    assert info.value.field == "cutoff"
    with pytest.raises(DataValidationError) as info:
        velocity_from_displacement(e, order=0)
    assert info.value.field == "order"


def test_decimate_keeps_band_and_rejects_aliases() -> None:
    n = 8000
    t = np.arange(n) / FS
    low = np.sin(2 * np.pi * 5 * t)
    high = np.sin(2 * np.pi * 200 * t)  # above the new Nyquist (125 Hz): would alias to 50 Hz
    e = Experiment(t=t, x=low, v=low + high, F=high, i=np.full(n, 1.0), name="d")
    d = decimate(e, 4)
    assert d.fs == pytest.approx(250.0)
    assert d.n == n // 4
    inner = slice(50, -50)
    np.testing.assert_allclose(d.x[inner], np.sin(2 * np.pi * 5 * d.t[inner]), atol=1e-3)
    assert np.abs(d.F[inner]).max() < 1e-3  # the 200 Hz tone is removed, not folded
    np.testing.assert_allclose(d.i, 1.0, atol=1e-12)
    assert decimate(e, 1).n == n
    for bad in (0, 2.5, True):
        with pytest.raises(DataValidationError) as info:
            decimate(e, bad)  # type: ignore[arg-type]
        assert info.value.field == "factor"


def test_remove_offsets_over_whole_cycles() -> None:
    f = 2.0
    n = int(3.3 * FS / f)  # 3.3 cycles: a plain mean would be biased by the partial cycle
    t = np.arange(n) / FS
    x = 0.01 * np.sin(2 * np.pi * f * t) + 0.0012
    F = 700 * np.cos(2 * np.pi * f * t) - 35.0
    e = Experiment(t=t, x=x, v=0 * t, F=F, i=0 * t, name="o")
    assert abs(np.mean(F) - (-35.0)) > 1.0
    for out in (remove_offsets(e, period=1 / f), remove_offsets(e)):  # given, and from the spectrum
        assert out.metadata["offsets"]["x"] == pytest.approx(0.0012, abs=2e-5)
        assert out.metadata["offsets"]["F"] == pytest.approx(-35.0, abs=1.5)
        np.testing.assert_allclose(out.x + out.metadata["offsets"]["x"], x)
    # A nominal frequency that is slightly off does not move the window: x is measured.
    out = remove_offsets(e.replace(metadata={"frequency": 1.02 * f}), channels="F")
    assert out.metadata["offsets"] == {"F": pytest.approx(-35.0, abs=1.5)}
    assert "spectrum of x, 2 Hz" in out.metadata["processing"][-1]
    np.testing.assert_array_equal(out.x, e.x)
    # Without a dominant frequency in x, the metadata frequency is used.
    flat = e.replace(x=np.random.default_rng(2).standard_normal(n), metadata={"frequency": f})
    out = remove_offsets(flat, channels="F")
    assert "x has no dominant frequency" in out.metadata["processing"][-1]
    assert out.metadata["offsets"]["F"] == pytest.approx(-35.0, abs=1e-6)
    assert dominant_frequency(x, FS) == pytest.approx(f, rel=0.01)


def test_remove_offsets_errors() -> None:
    e = _sine()
    with pytest.raises(DataValidationError, match="longer than") as info:
        remove_offsets(e, period=10.0)
    assert info.value.field == "period"
    with pytest.raises(DataValidationError) as info:
        remove_offsets(e, channels=("t",))
    assert info.value.field == "channels"
    with pytest.raises(DataValidationError) as info:
        remove_offsets(e, channels=("voltage",))
    assert info.value.field == "voltage"
    rng = np.random.default_rng(3)
    noisy = e.replace(x=rng.standard_normal(e.n))
    with pytest.raises(DataValidationError, match="no dominant frequency") as info:
        remove_offsets(noisy)
    assert info.value.field == "x"


def test_trim() -> None:
    e = _sine(n=1000)
    out = trim(e, 0.1, 0.2)
    assert out.t[0] == pytest.approx(0.1) and out.t[-1] == pytest.approx(0.2)
    assert out.n == 101
    np.testing.assert_array_equal(out.F, e.F[100:201])
    assert trim(e, t_start=0.5).n == 500
    with pytest.raises(DataValidationError) as info:
        trim(e, 0.3, 0.2)
    assert info.value.field == "t_stop"
    with pytest.raises(DataValidationError, match="keeps 0") as info:
        trim(e, 5.0, 6.0)
    assert info.value.field == "t_start"
    with pytest.raises(DataValidationError) as info:
        trim(e, float("nan"), 0.2)
    assert info.value.field == "t_start"


def test_drive_lag_matches_the_exact_ode_solution() -> None:
    # Random on/off command held on a 10 ms grid; between samples the command is constant, so
    # the ODE du/dt = -eta (u - w) has the closed form u(t) = w + (u0 - w) exp(-eta (t - t0)).
    rng = np.random.default_rng(7)
    fs, eta = 3004.8, 120.0
    n = 6000
    t = np.arange(n) / fs
    w = np.where(rng.random(n // 30 + 1)[(t / 0.01).astype(int)] > 0.5, 2.25, 0.0)
    e = Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, voltage=w, name="dyke-like")
    out = apply_drive_lag(e, eta)
    u = np.empty(n)
    u[0] = w[0]
    for k in range(n - 1):
        u[k + 1] = w[k] + (u[k] - w[k]) * np.exp(-eta * (t[k + 1] - t[k]))
    np.testing.assert_allclose(out.voltage, u, rtol=0, atol=1e-12)
    assert out.metadata["drive_lag_eta"] == eta
    assert out.metadata["drive_lag_source"] == "voltage"
    np.testing.assert_array_equal(e.voltage, w)
    with pytest.raises(DataValidationError, match="already") as info:
        apply_drive_lag(out, eta)
    assert info.value.field == "drive_lag_eta"


def test_drive_lag_errors() -> None:
    e = _sine()
    with pytest.raises(DataValidationError, match="no 'voltage' channel"):
        apply_drive_lag(e, 100.0)
    assert apply_drive_lag(e, 100.0, source="i").metadata["drive_lag_source"] == "i"
    for bad in (0.0, -5.0, float("inf"), "fast"):
        with pytest.raises(DataValidationError) as info:
            apply_drive_lag(e, bad, source="i")  # type: ignore[arg-type]
        assert info.value.field == "eta"
    with pytest.raises(DataValidationError) as info:
        apply_drive_lag(e, 10.0, source="F")
    assert info.value.field == "source"


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-3, 3, allow_nan=False), min_size=2, max_size=60),
    st.floats(0.1, 1e5),
)
def test_drive_lag_stays_within_command_range(command: list[float], eta: float) -> None:
    w = np.asarray(command)
    t = np.arange(w.size) * 1e-3
    e = Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, voltage=w)
    u = apply_drive_lag(e, eta).voltage
    assert u.min() >= w.min() - 1e-12 and u.max() <= w.max() + 1e-12
    assert u[0] == w[0]
