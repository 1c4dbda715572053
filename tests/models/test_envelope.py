"""The training envelope in use: its frequency band, the one-line note of predict / simulate /
score when a record leaves it (naming the dimension and by how much), the save / load round trip,
and NARX's regressors clipped to it (bounded beyond it, the step equal to predict)."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import Experiment
from mrdamper.errors import Note
from mrdamper.models import get_estimator, load_model
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.envelope import band_frequency, envelope_note, envelope_of, leaves
from mrdamper.models.narx import NARXModel
from mrdamper.models.step import run_step

TRUTH = BinghamModel(
    fc=(100.0, 400.0, -50.0), c0=(800.0, 1500.0, 0.0), f0=5.0, v_eps=0.0, input_range=(0.0, 1.0)
)


def _sine(amp: float, freq: float, level: float = 0.5, fs: float = 500.0, s: float = 4.0):
    t = np.arange(round(s * fs)) / fs
    x = amp * np.sin(2 * np.pi * freq * t)
    v = amp * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t)
    e = Experiment(t=t, x=x, v=v, F=np.zeros_like(t), i=np.full(t.size, level), name="s")
    return e.replace(F=TRUTH.predict(e), name=f"s{amp:g}_{freq:g}_{level:g}")


def _model_with_envelope() -> BinghamModel:
    train = [_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)]
    env = envelope_of(
        [e.x for e in train],
        [e.v for e in train],
        [e.i for e in train],
        [e.F for e in train],
        [e.dt for e in train],
    )
    return dataclasses.replace(TRUTH, provenance={"envelope": env})


def test_band_frequency_of_a_sine_and_of_no_motion() -> None:
    t = np.arange(5000) / 1000.0
    assert band_frequency(np.sin(2 * np.pi * 7.0 * t), 1e-3) == pytest.approx(7.0, abs=0.3)
    assert band_frequency(np.zeros(100), 1e-3) == 0.0


def test_leaves_names_each_dimension_and_by_how_much() -> None:
    trained = {"v_max": 0.1, "x_range": [-0.01, 0.01], "e_range": [0.0, 1.0], "f_band": 2.0}
    inside = {"v_max": 0.1, "x_range": [-0.01, 0.0102], "e_range": [0.0, 1.0], "f_band": 2.0}
    assert leaves(trained, inside) == {} and envelope_note("k", "r", trained, inside) == ""
    seen = {"v_max": 0.2, "x_range": [-0.015, 0.01], "e_range": [0.0, 1.5], "f_band": 6.0}
    out = leaves(trained, seen)
    assert set(out) == {"velocity", "displacement", "frequency", "electrical"}
    assert out["velocity"][0] == pytest.approx(2.0) and out["frequency"][0] == pytest.approx(3.0)
    assert out["displacement"][0] == pytest.approx(1.5)
    assert "50% of the range outside" in out["electrical"][1]
    note = envelope_note("lpv", "rec", trained, seen)
    assert note.startswith("lpv: record 'rec' leaves the model's training envelope: velocity")
    assert "\n" not in note


def test_excursions_carry_the_frequency_band_only_when_both_sides_have_one() -> None:
    from mrdamper.models.envelope import excursions

    trained = {"v_max": 0.1, "x_range": [-0.01, 0.01], "e_range": [0.0, 1.0], "v_switch": 0.0}
    seen = {**trained, "v_max": 0.2, "f_band": 12.0}
    assert set(excursions(trained, seen)) == {"velocity", "stroke", "switching"}
    out = excursions({**trained, "f_band": 4.0}, seen)
    assert out["frequency"] == pytest.approx(3.0) and out["velocity"] == pytest.approx(2.0)


def test_one_trained_level_is_named_with_the_distance_not_a_share_of_no_range() -> None:
    trained = {"v_max": 0.1, "x_range": [-0.01, 0.01], "e_range": [0.5, 0.5], "f_band": 2.0}
    seen = {**trained, "e_range": [1.0, 1.0]}
    ratio, text = leaves(trained, seen)["electrical"]
    assert ratio == pytest.approx(2.0)
    assert text == "electrical input [1, 1] against the one level trained, 0.5 (0.5 beyond it)"
    assert leaves(trained, {**trained, "e_range": [0.5, 0.5]}) == {}
    at_zero = {**trained, "e_range": [0.0, 0.0]}
    assert "(0.2 beyond it)" in leaves(at_zero, {**trained, "e_range": [0.0, 0.2]})["electrical"][1]


def test_predict_simulate_and_score_say_once_when_a_record_leaves(tmp_path: Path) -> None:
    m = _model_with_envelope()
    assert m.envelope is not None and m.envelope["f_band"] == pytest.approx(1.0, abs=0.3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m.predict(_sine(0.01, 1.0, 0.5))  # inside
        assert not [w for w in caught if issubclass(w.category, Note)]
        m.simulate(_sine(0.02, 3.0, 0.5))
        m.score(_sine(0.02, 3.0, 0.5))
    notes = [str(w.message) for w in caught if issubclass(w.category, Note)]
    assert len(notes) == 2  # one per call, not one per inner predict
    assert "velocity" in notes[0] and "displacement" in notes[0] and "frequency" in notes[0]
    assert "6.00 x" in notes[0]  # velocity: 0.377 against 0.0628 m/s
    # the saved model carries its envelope, and the loaded one says the same
    path = m.save(tmp_path / "m.json")
    back = load_model(path)
    assert back.envelope == m.envelope
    assert back.envelope_note(_sine(0.02, 3.0, 0.5)) == m.envelope_note(_sine(0.02, 3.0, 0.5))


def test_the_note_points_at_the_user_s_line() -> None:
    # not at the line of mrdamper that predicted (models/base.py): the user's call
    m = _model_with_envelope()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m.score(_sine(0.02, 3.0, 0.5))
    [note] = [w for w in caught if issubclass(w.category, Note)]
    assert Path(note.filename) == Path(__file__), note.filename


def test_a_model_without_envelope_says_nothing() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", Note)
        TRUTH.predict(_sine(0.05, 5.0, 0.5))


def test_fit_records_the_envelope_with_its_band() -> None:
    train = [_sine(0.01, 2.0, lev) for lev in (0.0, 0.5, 1.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = get_estimator("bingham").fit(train)
    env = m.envelope
    assert env is not None and env["f_band"] == pytest.approx(2.0, abs=0.3)
    assert env["x_range"] == pytest.approx([-0.01, 0.01], abs=1e-4)


def _narx_burst() -> NARXModel:
    """A NARX model whose cubic x term bursts beyond |x| = 10 mm (trained within it)."""
    return NARXModel(
        fs=500.0,
        base=[[0, 1], [1, 0], [2, 0]],
        terms=[[0, -1, -1], [1, 1, 1], [2, -1, -1]],
        theta=[0.5, 30.0, 0.5],
        scales=[1000.0, 0.01, 0.1, 1.0, 1.0],
        v0=0.005,
        input_range=(0.0, 1.0),
    )


def test_narx_clipped_regressors_stay_bounded_and_step_equals_predict() -> None:
    free = _narx_burst()
    clipped = dataclasses.replace(free, x_limits=(-0.01, 0.01), v_limit=0.0629)
    big = _sine(0.03, 1.0, 0.5)
    F_free, F_clip = free.predict(big), clipped.predict(big)
    inside = _sine(0.01, 1.0, 0.5)
    assert np.array_equal(free.predict(inside), clipped.predict(inside))
    assert np.max(np.abs(F_free)) > 10 * np.max(np.abs(F_clip))
    assert np.max(np.abs(F_clip)) <= 1.1 * np.max(np.abs(clipped.predict(inside)))
    step, status, _ = run_step(clipped.step(), big.x, big.v, big.i, big.dt)
    assert status == 0
    n = 100  # the free run starts from the measured force, the step from rest: 0.5**100 later
    assert np.allclose(step[n:], F_clip[n:], rtol=0, atol=1e-9 * np.max(np.abs(F_clip)))


def test_narx_estimator_clips_by_default_and_saves_the_limits(tmp_path: Path) -> None:
    train = [_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = get_estimator("narx", n_terms=4, refine=False).fit(train)
        free = get_estimator("narx", n_terms=4, refine=False, extrapolation="free").fit(train)
    assert m.x_limits == pytest.approx((-0.01, 0.01), abs=1e-6)
    assert m.v_limit == pytest.approx(0.02 * np.pi, rel=1e-3)
    assert free.x_limits == (-np.inf, np.inf) and free.v_limit == np.inf
    back = load_model(m.save(tmp_path / "narx.json"))
    assert back == m
    back_free = load_model(free.save(tmp_path / "free.json"))
    assert back_free.v_limit == np.inf
