"""Three-zone regression, laws across current and the scheduling input.

Known answers come from synthetic data generated with chosen breakpoints, slopes and laws."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrdamper import DataValidationError, Experiment, IdentificationError
from mrdamper.analysis import (
    ZoneFit,
    ZoneLaws,
    ZoneLawWarning,
    fit_zone_laws,
    fit_zones,
    segment_plateaus,
)

GM = np.array([[500.0, 3000.0, -800.0], [15000.0, 60000.0, -9000.0], [600.0, 2800.0, -700.0]])
MU = (0.01, 0.006)


def _piecewise(v, lo, hi, m, c2):
    """Continuous three-zone law with central line m2 v + c2."""
    m1, m2, m3 = m
    return np.where(
        v < lo,
        m2 * lo + c2 + m1 * (v - lo),
        np.where(v > hi, m2 * hi + c2 + m3 * (v - hi), m2 * v + c2),
    )


def _laws_data(levels, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    exps = []
    for lev in levels:
        t = np.arange(4000) * 1e-3
        v = 0.1 * np.sin(2 * np.pi * 1.0 * t)
        m = GM[:, 0] + GM[:, 1] * lev + GM[:, 2] * lev**2
        vh = MU[0] * lev + MU[1]
        F = _piecewise(v, -vh, vh, m, 0.0) + noise * rng.standard_normal(t.size)
        exps.append(
            Experiment(
                t=t,
                x=0 * t,
                v=v,
                F=F,
                i=np.full(t.size, lev),
                name=f"l{lev}",
                metadata={"current": lev},
            )
        )
    return exps


def test_fit_zones_recovers_asymmetric_breakpoints_and_slopes() -> None:
    v = np.linspace(-0.2, 0.25, 9001)
    F = _piecewise(v, -0.03, 0.05, (1000.0, 20000.0, 1500.0), 40.0)
    fz = fit_zones(v, F, symmetric=False)
    assert fz.v_low == pytest.approx(-0.03, abs=2e-5)
    assert fz.v_high == pytest.approx(0.05, abs=2e-5)
    np.testing.assert_allclose(fz.m, (1000.0, 20000.0, 1500.0), rtol=2e-3)
    assert fz.c[1] == pytest.approx(40.0, abs=1.0)
    assert fz.r2 > 0.999999
    assert fz.central_is_steepest
    # continuity at the breakpoints, in the fit itself
    for b in (fz.v_low, fz.v_high):
        assert fz.predict(b - 1e-12) == pytest.approx(fz.predict(b + 1e-12), rel=1e-6)


def test_fit_zones_symmetric_with_noise() -> None:
    rng = np.random.default_rng(1)
    v = rng.uniform(-0.15, 0.15, 20000)
    F = _piecewise(v, -0.02, 0.02, (800.0, 30000.0, 800.0), 0.0) + 5.0 * rng.standard_normal(v.size)
    fz = fit_zones(v, F, symmetric=True, level=0.5)
    assert fz.v_high == pytest.approx(0.02, rel=0.02)
    assert fz.v_low == -fz.v_high
    np.testing.assert_allclose(fz.m, (800.0, 30000.0, 800.0), rtol=0.03)
    assert fz.resid_std == pytest.approx(5.0, rel=0.05)
    df = fz.to_frame()
    assert list(df["level"]) == [0.5] and df.shape[0] == 1
    assert fz.plot() is not None


@pytest.mark.parametrize(
    ("v", "F", "field"),
    [
        (np.ones(100), np.ones(99), "F"),
        (np.r_[np.nan, np.linspace(-1, 1, 99)], np.ones(100), "v"),
        (np.linspace(0.1, 1, 100), np.ones(100), "v"),  # no negative velocities
    ],
)
def test_fit_zones_bad_input(v, F, field) -> None:
    with pytest.raises(DataValidationError, match=field):
        fit_zones(v, F)


def test_laws_recover_known_gamma_and_mu() -> None:
    laws = fit_zone_laws(_laws_data([0.0, 0.25, 0.5, 0.75, 1.0]))
    np.testing.assert_allclose(laws.gamma_m, GM, rtol=1e-3, atol=20.0)
    np.testing.assert_allclose(laws.mu_high, MU, rtol=1e-3, atol=2e-6)
    np.testing.assert_allclose(laws.mu_low, (-MU[0], -MU[1]), rtol=1e-3, atol=2e-6)
    df = laws.to_frame()
    assert np.max(np.abs(df["m2_resid"])) < 50.0
    assert laws.problems() == []
    # JSON-able and exact through to_dict / from_dict
    again = ZoneLaws.from_dict(laws.to_dict())
    np.testing.assert_array_equal(again.gamma_m, laws.gamma_m)
    assert laws.plot() is not None


def test_laws_from_stepped_plateaus_equal_laws_from_metadata() -> None:
    exps = _laws_data([0.0, 0.5, 1.0])
    t = np.arange(3 * 4000) * 1e-3
    stepped = Experiment(
        t=t,
        x=0 * t,
        v=np.concatenate([e.v for e in exps]),
        F=np.concatenate([e.F for e in exps]),
        i=np.concatenate([e.i for e in exps]),
        name="sc",
    )
    plates = segment_plateaus(stepped.i, stepped.dt, tolerance=0.01, min_duration=1.0, settle=0.0)
    assert [round(p[2], 6) for p in plates] == [0.0, 0.5, 1.0]
    a = fit_zone_laws(exps)
    b = fit_zone_laws([stepped], by="plateaus", settle=0.0)
    np.testing.assert_allclose(b.gamma_m, a.gamma_m, rtol=1e-9)


def test_laws_need_enough_levels_and_flag_nonphysical_data() -> None:
    with pytest.raises(IdentificationError, match="at least 3 levels"):
        fit_zone_laws(_laws_data([0.0, 1.0]))
    # outer slope bigger than the central one: warned per level, laws rejected when strict
    fits = [
        ZoneFit(-0.01, 0.01, (5e4, 1e4, 5e4), (0.0, 0.0, 0.0), 1.0, 0.0, 100, True, lev)
        for lev in (0, 0.5, 1)
    ]
    with (
        pytest.warns(ZoneLawWarning, match="not the biggest"),
        pytest.raises(IdentificationError, match="m1/m2"),
    ):
        fit_zone_laws(fits)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        fit_zone_laws(fits, strict=False)
    assert any("assumptions" in str(w.message) for w in rec)


# ---------------------------------------------------------------------- scheduling input
def _laws(sym_slopes: bool, m1: float, m3: float, m2: float, vh: float) -> ZoneLaws:
    m3 = m1 if sym_slopes else m3
    gm = np.array([[m1, 0.0, 0.0], [m2, 0.0, 0.0], [m3, 0.0, 0.0]])
    gc = np.array([[-(m2 - m1) * vh, 0, 0], [0.0, 0, 0], [(m2 - m3) * vh, 0, 0]], dtype=float)
    return ZoneLaws(
        gm,
        gc,
        (0.0, vh),
        (0.0, -vh),
        True,
        (0.0, 1.0),
        [0.0],
        [[m1, m2, m3]],
        [[gc[0, 0], 0.0, gc[2, 0]]],
        [-vh],
        [vh],
    )


slopes = st.floats(0.0, 1.0)
vel = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(s1=slopes, s3=slopes, vh=st.floats(1e-4, 0.5), v=vel)
def test_continuous_reading_bounded_by_velocity(s1, s3, vh, v) -> None:
    laws = _laws(False, s1 * 2e4, s3 * 2e4, 2e4, vh)
    u = laws.scheduling_input(np.array([v]), 0.5)[0]
    assert abs(u) <= abs(v) + 1e-15


@settings(max_examples=100, deadline=None)
@given(s1=slopes, s3=slopes, vh=st.floats(1e-4, 0.5))
def test_continuous_reading_is_continuous_at_limits(s1, s3, vh) -> None:
    laws = _laws(False, s1 * 2e4, s3 * 2e4, 2e4, vh)
    eps = 1e-9
    for b in (-vh, vh):
        u = laws.scheduling_input(np.array([b - eps, b, b + eps]), 0.3)
        assert np.ptp(u) <= 2.01 * eps
        assert u[1] == pytest.approx(b)


@settings(max_examples=100, deadline=None)
@given(s=slopes, vh=st.floats(1e-4, 0.5), v=vel)
def test_odd_symmetry_for_symmetric_fit(s, vh, v) -> None:
    laws = _laws(True, s * 2e4, 0.0, 2e4, vh)
    u = laws.scheduling_input(np.array([v, -v]), 0.7)
    assert u[0] == pytest.approx(-u[1], abs=1e-15)
    lit = laws.scheduling_input(np.array([v, -v]), 0.7, reading="literal")
    assert lit[0] == pytest.approx(-lit[1], abs=1e-12)


def test_literal_reading_differs_from_continuous_when_c2_nonzero() -> None:
    laws = fit_zone_laws(_laws_data([0.0, 0.5, 1.0]))
    v = np.linspace(-0.1, 0.1, 101)
    cont = laws.scheduling_input(v, 0.5)
    lit = laws.scheduling_input(v, 0.5, reading="literal")
    inner = np.abs(v) <= laws.v_high(0.5)
    np.testing.assert_array_equal(cont[inner], v[inner])
    np.testing.assert_array_equal(lit[inner], v[inner])
    with pytest.raises(DataValidationError, match="reading"):
        laws.scheduling_input(v, 0.5, reading="other")  # type: ignore[arg-type]


# ---------------------------------------------------------------------- real data
@pytest.mark.slow
@pytest.mark.realdata
def test_quiroz_zone_slopes_follow_paper(quiroz_unfiltered_dir) -> None:
    """Figs. 2-3 quantities on real constant-current records: m2 > m1, m3 and m2 grows with i."""
    from mrdamper.data.readers import read_directory

    exps = read_directory(quiroz_unfiltered_dir).filter(condition=["5mm_3Hz", "10mm_2Hz"])
    assert len(exps) == 10
    laws = fit_zone_laws(exps)
    m = laws.level_m
    assert np.all(m[:, 1] > m[:, 0]) and np.all(m[:, 1] > m[:, 2])
    assert np.all(np.diff(m[:, 1]) > 0)
    assert np.all(np.diff(laws.level_v_high) > 0)


@pytest.mark.parametrize("reading", ["continuous", "literal"])
def test_long_inputs_are_built_in_blocks_with_the_same_values(
    reading: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Above ``BLOCK`` samples the zone-law inputs are formed block by block (bounded
    temporaries on long records); every sample gets the same value as in one piece."""
    from mrdamper.analysis import hysteretic
    from mrdamper.analysis import laws as laws_module

    laws = fit_zone_laws(_laws_data([0.0, 0.25, 0.5, 0.75, 1.0]))
    rng = np.random.default_rng(4)
    n = 5000
    v = np.cumsum(rng.normal(0.0, 0.01, n))
    rho = rng.uniform(0.0, 1.0, n)
    whole_u = laws.scheduling_input(v, rho, reading=reading)
    whole_h = hysteretic.hysteretic_input(laws, v, rho, 1e-3, 2e-4, 0.5)
    monkeypatch.setattr(laws_module, "BLOCK", 777)  # in_blocks serves both inputs
    np.testing.assert_array_equal(laws.scheduling_input(v, rho, reading=reading), whole_u)
    np.testing.assert_array_equal(
        hysteretic.hysteretic_input(laws, v, rho, 1e-3, 2e-4, 0.5), whole_h
    )
