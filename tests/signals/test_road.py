"""ISO 8608 road profiles: spectrum slope, band limit, physical level and stroke scaling."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from mrdamper.errors import DataValidationError
from mrdamper.signals import (
    ISO_8608_CLASSES,
    band_variance,
    long_road_profile,
    road_profile,
    spatial_psd,
    temporal_psd,
)

FS = 1000.0


def _slope(x: np.ndarray, fmin: float, fmax: float, nperseg: int) -> float:
    f, P = welch(x, fs=FS, nperseg=nperseg)
    band = (f >= fmin) & (f <= fmax)
    return float(np.polyfit(np.log(f[band]), np.log(P[band]), 1)[0])


def test_class_table_matches_iso_8608() -> None:
    # ISO 8608 geometric means of Gd(n0) [1e-6 m^3]: A 16, B 64, C 256, D 1024, E 4096 ... H 262144
    expected = {
        "A": 16,
        "B": 64,
        "C": 256,
        "D": 1024,
        "E": 4096,
        "F": 16384,
        "G": 65536,
        "H": 262144,
    }
    assert {k: round(v * 1e6) for k, v in ISO_8608_CLASSES.items()} == expected
    assert float(spatial_psd(0.2, "A")) == pytest.approx(16e-6 / 4)
    # temporal PSD: G(f) = Gd(f/V)/V
    assert float(temporal_psd(2.0, "B", 20.0)) == pytest.approx(float(spatial_psd(0.1, "B")) / 20.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("fmax", [4.2, 5.5])
def test_road_profile_spectrum_slope_and_band_limit(seed: int, fmax: float) -> None:
    # a 300 s record gives Welch enough segments for a stable slope estimate
    x = road_profile(FS, 300.0, seed=seed, max_frequency=fmax, min_frequency=0.2)
    assert _slope(x, 0.5, 0.8 * fmax, nperseg=2**14) == pytest.approx(-2.0, abs=0.1)
    f, P = welch(x, fs=FS, nperseg=2**13)
    in_band = P[(f >= 0.5) & (f <= fmax)].sum()
    above = P[f >= 1.15 * fmax].sum()
    assert above / in_band < 1e-6


def test_table_ii_length_profiles_have_slope_minus_2_on_average() -> None:
    # one 30 s record is too short for a precise Welch slope; the ensemble mean of 12 is not
    Ps = []
    for seed in range(12):
        f, P = welch(road_profile(FS, 30.0, seed=seed, max_frequency=5.5), fs=FS, nperseg=2**13)
        Ps.append(P)
    P = np.mean(Ps, axis=0)
    band = (f >= 0.5) & (f <= 4.4)
    slope = np.polyfit(np.log(f[band]), np.log(P[band]), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.2)


def test_long_road_profile_spectrum_and_amplitude_changes() -> None:
    x = long_road_profile(FS, 600.0, seed=3, max_frequency=4.5, section_duration=30.0)
    assert x.size == 600_000
    assert _slope(x, 0.4, 3.6, nperseg=2**15) == pytest.approx(-2.0, abs=0.1)
    f, P = welch(x, fs=FS, nperseg=2**15)
    # the 2 s cross-fades modulate the sections, which leaks about 1e-6 of the power just above
    # the band; nothing is synthesised there
    assert P[f >= 5.2].sum() / P[(f >= 0.4) & (f <= 4.5)].sum() < 1e-5
    # sections of different class / speed: section RMS varies across the drive
    rms = np.sqrt((x[: 20 * 30000].reshape(20, 30000) ** 2).mean(axis=1))
    assert rms.max() / rms.min() > 1.5


def test_physical_amplitude_matches_iso_band_integral() -> None:
    x = road_profile(
        FS,
        60.0,
        seed=5,
        road_class="A",
        speed=10.0,
        max_frequency=5.0,
        min_frequency=0.5,
        fill=None,
        taper=0.0,
    )
    # random-phase method with deterministic amplitudes: variance is the Riemann sum of G(f) df
    expected = band_variance("A", 10.0, 0.5, 5.0)
    assert np.var(x) == pytest.approx(expected, rel=0.05)


def test_scaling_to_stroke_and_taper() -> None:
    stroke = 0.04
    x = road_profile(FS, 30.0, seed=8, road_class="H", stroke=stroke, fill=0.9, taper=0.5)
    assert np.max(np.abs(x)) == pytest.approx(0.9 * stroke / 2, rel=1e-12)
    assert x[0] == 0.0 and abs(x[-1]) < 1e-6
    assert abs(np.mean(x)) < 0.1 * np.std(x)
    # fill=None keeps the physical level and refuses a profile that leaves the stroke
    with pytest.raises(DataValidationError, match="fill"):
        road_profile(FS, 30.0, seed=8, road_class="H", fill=None)
    y = long_road_profile(FS, 90.0, seed=2, stroke=0.02, fill=0.5)
    assert np.max(np.abs(y)) == pytest.approx(0.5 * 0.02 / 2, rel=1e-12)


def test_same_seed_same_bytes() -> None:
    a = long_road_profile(FS, 70.0, seed=12)
    assert a.tobytes() == long_road_profile(FS, 70.0, seed=12).tobytes()
    assert a.tobytes() != long_road_profile(FS, 70.0, seed=13).tobytes()


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"road_class": "Z"}, "road_class"),
        ({"max_frequency": 600.0}, "max_frequency"),
        ({"min_frequency": 6.0, "max_frequency": 5.0}, "min_frequency"),
        ({"speed": 0.0}, "speed"),
        ({"fill": 1.5}, "fill"),
        ({"taper": 20.0}, "taper"),
    ],
)
def test_road_profile_rejects(kwargs: dict, field: str) -> None:
    with pytest.raises(DataValidationError) as info:
        road_profile(FS, 30.0, seed=0, **kwargs)
    assert info.value.field == field


def test_band_without_bins_is_reported() -> None:
    with pytest.raises(DataValidationError, match="no frequency bin"):
        road_profile(FS, 1.0, seed=0, min_frequency=0.2, max_frequency=0.5, taper=0.0)
