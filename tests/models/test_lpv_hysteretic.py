"""Hysteretic LPV input (``input_signal="hysteretic"``): the Dahl operator's limits and exactness,
the input's static limit, identification on virtual-rig records, round trip and refusals."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment
from mrdamper.analysis import ZoneLaws
from mrdamper.analysis.hysteretic import dahl_state, hysteretic_input
from mrdamper.control import c_source, inverse_current, lpv_export_data, state_space
from mrdamper.models.lpv import LPVEstimator, LPVModel
from mrdamper.models.lpv import choice as _lpv_choice
from mrdamper.models.lpv import inputs as _lpv_inputs
from mrdamper.rig import VirtualRig, reference_damper

X_Y = 1e-4  # stroke scale [m]


def _laws() -> ZoneLaws:
    gm = np.array([[800.0, 2000.0, 0.0], [15000.0, 40000.0, 0.0], [900.0, 1800.0, 0.0]])
    return ZoneLaws(
        gm,
        np.zeros((3, 3)),
        (0.01, 0.01),
        (-0.01, -0.02),
        False,
        (0.0, 1.0),
        [0.0, 1.0],
        gm[:, :2].T,
        np.zeros((2, 3)),
        [-0.02, -0.03],
        [0.01, 0.02],
    )


# ----------------------------------------------------------------------------- operator
def test_monotone_motion_follows_the_closed_form() -> None:
    """From rest and moving one way, ``z = 1 - exp(-x / x_y)``: slope ``1 / x_y`` at small
    strokes (stiffness-like), 1 at large strokes (saturated)."""
    dt = 1e-4
    v = 0.002 + 0.001 * np.sin(np.arange(20000) * 0.001)  # positive, varying [m/s]
    z = dahl_state(v, dt, X_Y)
    x = np.r_[0.0, np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)]  # trapezoidal displacement
    np.testing.assert_allclose(z, 1.0 - np.exp(-x / X_Y), rtol=1e-12, atol=1e-14)
    small = x < 0.05 * X_Y
    assert small.sum() >= 10
    np.testing.assert_allclose(z[small][1:], x[small][1:] / X_Y, rtol=0.03)
    assert abs(z[-1] - 1.0) < 1e-12


def test_large_strokes_saturate_and_small_strokes_do_not() -> None:
    dt, f = 1e-3, 2.0
    t = np.arange(4000) * dt
    for amp, saturated in ((100 * X_Y, True), (0.05 * X_Y, False)):
        v = 2 * np.pi * f * amp * np.cos(2 * np.pi * f * t)
        z = dahl_state(v, dt, X_Y)
        assert np.all(np.abs(z) <= 1.0)
        x = amp * np.sin(2 * np.pi * f * t)
        if saturated:  # after the first quarter period, away from reversals z equals sign(v)
            mid = (np.abs(x) < 0.5 * amp) & (t > 0.25 / f)
            np.testing.assert_allclose(z[mid], np.sign(v[mid]), atol=1e-9)
        else:  # a stroke of 0.1 x_y peak to peak keeps |z| about 0.05 or less: no saturation
            assert np.max(np.abs(z)) < 0.06
            # after the first stroke the state follows the displacement with slope 1 / x_y
            late = t > 0.5
            np.testing.assert_allclose(np.ptp(z[late]), np.ptp(x[late]) / X_Y, rtol=0.05)


def test_exact_against_a_fine_step_reference() -> None:
    """Velocity linear between samples, reversals on samples: 50 sub-steps give the same state."""
    dt = 0.01
    t = np.arange(301) * dt
    v = 0.02 * np.cos(2 * np.pi * 1.0 * t)  # zeros at 0.25 s + k 0.5 s, on samples
    v[np.abs(v) < 1e-15] = 0.0
    tf = np.arange(300 * 50 + 1) * dt / 50
    zf = dahl_state(np.interp(tf, t, v), dt / 50, X_Y)
    z = dahl_state(v, dt, X_Y)
    np.testing.assert_allclose(z, zf[::50], rtol=0, atol=1e-12)
    # stable for any step: a step far above the stroke scale keeps |z| <= 1
    assert np.all(np.abs(dahl_state(v, 10.0, X_Y)) <= 1.0)


def test_bad_operator_input() -> None:
    with pytest.raises(DataValidationError, match="stroke"):
        dahl_state(np.zeros(3), 1e-3, 0.0)
    with pytest.raises(DataValidationError, match="dt"):
        dahl_state(np.zeros(3), -1.0, X_Y)
    with pytest.raises(DataValidationError, match="blend"):
        hysteretic_input(_laws(), np.zeros(3), np.zeros(3), 1e-3, X_Y, 1.5)


def test_zero_blend_is_the_static_input() -> None:
    rng = np.random.default_rng(0)
    v = 0.05 * rng.standard_normal(500)
    rho = rng.uniform(0.0, 1.0, 500)
    laws = _laws()
    u0 = hysteretic_input(laws, v, rho, 1e-3, X_Y, 0.0)
    np.testing.assert_allclose(u0, laws.scheduling_input(v, rho), rtol=1e-12, atol=1e-15)
    u1 = hysteretic_input(laws, v, rho, 1e-3, X_Y, 1.0)
    assert not np.allclose(u1, u0)


# ----------------------------------------------------------------------------- identification
def _fit(train: list[Experiment], **settings) -> LPVModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return LPVEstimator(**settings).fit(train)


def test_fit_on_rig_records(rig_data) -> None:
    """On the rig (a Bouc-Wen damper) the hysteretic input predicts a small-stroke chirp the
    static input misses; both fit the training sines."""
    train, test = rig_data
    hys = _fit(train, input_signal="hysteretic", stroke=X_Y, blend=0.5)
    static = _fit(train, input_signal="u")
    assert hys.is_frozen_stable() and hys.provenance["frozen_stable"]
    assert np.mean([hys.score(e).esr for e in train]) < 0.01
    e_hys, e_static = hys.score(test[0]).esr, static.score(test[0]).esr
    assert e_hys < 0.02
    assert e_hys < 0.5 * e_static


@pytest.mark.slow
def test_choice_on_training_records_and_round_trip(rig_data) -> None:
    train, test = rig_data
    m = _fit(train[::2], blend=0.5, choose_on="training")  # the default input; stroke chosen
    rows = m.provenance["hysteretic_choice"]
    assert [r["stroke"] for r in rows] == list(_lpv_inputs.STROKES)
    best = min(rows, key=lambda r: r["train_esr"])
    assert (m.stroke, m.blend) == (best["stroke"], 0.5)
    assert m.provenance["settings"]["stroke"] is None
    back = LPVModel.from_dict(m.to_dict())
    assert (back.stroke, back.blend, back.input_signal) == (m.stroke, 0.5, "hysteretic")
    np.testing.assert_array_equal(back.predict(test[0]), m.predict(test[0]))
    # an old file (no stroke / blend fields) still loads as a static-input model
    d = _fit(train[:3], input_signal="u").to_dict()
    d["parameters"].pop("stroke")
    d["parameters"].pop("blend")
    assert LPVModel.from_dict(d).input_signal == "u"


def test_settings_and_refusals(rig_data) -> None:
    train, _ = rig_data
    with pytest.raises(DataValidationError, match="stroke.*input_signal='hysteretic' only"):
        LPVEstimator(input_signal="u", stroke=1e-4).fit(train)
    with pytest.raises(DataValidationError, match="blend"):
        LPVEstimator(input_signal="hysteretic", stroke=1e-4, blend=2.0).fit(train)
    with pytest.raises(DataValidationError, match="reading"):
        LPVEstimator(input_signal="hysteretic", reading="literal").fit(train)
    m = _fit(train[:3], input_signal="hysteretic", stroke=X_Y, blend=0.5)
    with pytest.raises(DataValidationError, match="stroke"):
        LPVModel(**{**m.parameters, "stroke": None, "input_range": (0.0, 1.0)})
    # the state-space matrices are those of the transfer function from u: still available
    assert state_space(m, 0.5).A.shape == (m.n_m, m.n_m)
    # the control tools step the Dahl state along the motion (tests/control)
    assert lpv_export_data(m)["stroke"] == X_Y
    assert "_BLEND" in c_source(m, name="d")[1]
    assert inverse_current(m, train[0], np.asarray(train[0].F)).i.size == train[0].n


@pytest.mark.slow
def test_long_campaigns_choose_on_windows(rig_data, monkeypatch) -> None:
    """Above the threshold the candidates are compared on windows; the model uses every sample."""
    train, _ = rig_data
    monkeypatch.setattr(_lpv_choice, "CHOICE_THRESHOLD", 1000)
    monkeypatch.setattr(_lpv_choice, "CHOICE_BUDGET", 4000)
    m = _fit(train[:6], blend=0.5, choose_on="training")
    info = m.provenance["hysteretic_windows"]  # (records shorter than a window: whole records)
    assert info["windows"] == 6 and info["samples_used"] == sum(e.n for e in train[:6])
    assert m.provenance["n_samples"] == sum(e.n for e in train[:6])  # the final fit: every sample
    assert m.stroke in _lpv_inputs.STROKES


def test_post_yield_slopes_extrapolate_in_velocity(rig_data) -> None:
    """Trained on sines up to 63 mm/s, the default outer slopes (post-yield samples) predict a
    0.3 m/s sine of the rig better than the three-zone regression's, whose outer slopes are
    steepened by the samples just past the zone limit that have not yielded; the paper's static
    input keeps the regression's slopes."""
    train, _ = rig_data
    fs = 1000.0
    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=fs)
    t = np.arange(round(1.5 * fs)) / fs
    x = 0.3 / (2 * np.pi * 4.0) * np.sin(2 * np.pi * 4.0 * t)
    fast = rig.run(x, np.full(t.size, 0.5), seed=7, name="fast", metadata={"current": 0.5})
    post = _fit(train, input_signal="hysteretic", stroke=X_Y, blend=0.5)
    zones = _fit(train, input_signal="hysteretic", stroke=X_Y, blend=0.5, outer_slopes="zones")
    assert post.provenance["outer_slopes"] == "post-yield"
    assert zones.provenance["outer_slopes"] == "zones"
    assert _fit(train, input_signal="u").provenance["outer_slopes"] == "zones"
    m3 = lambda m: float(m.zone_laws.m(0.5)[2])  # noqa: E731
    assert m3(post) < m3(zones)
    e_post, e_zones = post.score(fast).esr, zones.score(fast).esr
    print(f"ESR at 0.3 m/s: post-yield {e_post:.4f}, zones {e_zones:.4f}")
    assert e_post < 0.7 * e_zones


def test_post_yield_laws_that_break_eq_20_fall_back_to_the_regression(
    rig_data, monkeypatch
) -> None:
    """Post-yield slopes whose laws break eq. (20) (here forced: an outer slope above the
    central one) do not fail the fit: the regression's slopes are used, and the provenance says
    so."""
    import dataclasses

    from mrdamper.analysis import laws as _laws_module

    def steep(fit, v, F, **kw):  # type: ignore[no-untyped-def]
        m = (fit.m[0], fit.m[1], 2.0 * fit.m[1])
        return dataclasses.replace(fit, m=m)

    train, _ = rig_data
    monkeypatch.setattr(_laws_module, "post_yield_slopes", steep)
    model = _fit(train, input_signal="hysteretic", stroke=X_Y, blend=0.5)
    zones = _fit(train, input_signal="hysteretic", stroke=X_Y, blend=0.5, outer_slopes="zones")
    assert model.provenance["outer_slopes"] == "zones"
    assert "break eq. (20)" in model.provenance["outer_slopes_note"]
    np.testing.assert_array_equal(model.zone_laws.gamma_m, zones.zone_laws.gamma_m)
