"""Tests of the Bingham plastic reference model (known answers, round trip, errors)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, IdentificationError, OutOfRangeError
from mrdamper.models import get_estimator, load_model, model_class
from mrdamper.models.bingham import BinghamEstimator, BinghamModel


def _record(
    current: float | np.ndarray,
    seed: int = 0,
    n: int = 2000,
    name: str = "r",
    noise: float = 0.0,
    truth: BinghamModel | None = None,
) -> Experiment:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    x = 0.01 * np.sin(2 * np.pi * 1.7 * t + rng.uniform(0, 6))
    v = 0.01 * 2 * np.pi * 1.7 * np.cos(2 * np.pi * 1.7 * t + rng.uniform(0, 6))
    i = np.broadcast_to(np.asarray(current, dtype=float), t.shape).copy()
    exp = Experiment(t=t, x=x, v=v, F=0 * t, i=i, name=name)
    if truth is not None:
        F = truth.predict(exp) + noise * rng.standard_normal(n)
        exp = exp.replace(F=F)
    return exp


TRUTH = BinghamModel(
    fc=(60.0, 900.0, -250.0), c0=(1500.0, 4000.0, 1000.0), f0=-12.0, input_range=(0, 1)
)


def test_predict_follows_the_equation() -> None:
    exp = _record(0.5)
    F = TRUTH.predict(exp)
    fc = 60 + 900 * 0.5 - 250 * 0.25
    c0 = 1500 + 4000 * 0.5 + 1000 * 0.25
    np.testing.assert_allclose(F, fc * np.sign(exp.v) + c0 * exp.v - 12.0)
    smooth = BinghamModel(fc=(100.0,), c0=(0.0,), v_eps=0.01, input_range=(0, 1))
    np.testing.assert_allclose(smooth.predict(exp), 100 * np.tanh(exp.v / 0.01))


@pytest.mark.parametrize("v_eps", [0.0, 0.005])
def test_known_answer_identification(v_eps: float) -> None:
    truth = BinghamModel(fc=TRUTH.fc, c0=TRUTH.c0, f0=TRUTH.f0, v_eps=v_eps, input_range=(0, 1))
    data = [
        _record(c, seed=k, truth=truth, name=f"c{c}")
        for k, c in enumerate((0.0, 0.25, 0.5, 0.75, 1.0))
    ]
    fit = BinghamEstimator(degree=2, v_eps=v_eps).fit(data)
    np.testing.assert_allclose(fit.fc, truth.fc, rtol=1e-8, atol=1e-6)
    np.testing.assert_allclose(fit.c0, truth.c0, rtol=1e-8, atol=1e-6)
    assert fit.f0 == pytest.approx(truth.f0, abs=1e-6)
    assert fit.input_range == (0.0, 1.0)


def test_noisy_identification_is_close() -> None:
    data = [
        _record(c, seed=k, truth=TRUTH, noise=20.0, name=f"c{c}")
        for k, c in enumerate((0.0, 0.25, 0.5, 0.75, 1.0))
    ]
    fit = BinghamEstimator(degree=2).fit(data)
    test = _record(0.6, seed=42, truth=TRUTH)
    assert fit.score(test).esr < 1e-3


def test_one_level_reduces_to_constants_two_levels_need_degree_one() -> None:
    data = [_record(0.5, seed=1, truth=TRUTH)]
    with pytest.warns(UserWarning, match=r"one i level \(0.5 A\).*\[0.5, 0.5\] A"):
        reduced = BinghamEstimator(degree=2).fit(data)
    fit = BinghamEstimator(degree=0).fit(data)
    assert fit.score(data[0]).esr < 1e-20
    assert reduced.fc == pytest.approx(fit.fc) and reduced.c0 == pytest.approx(fit.c0)
    assert reduced.input_range == (0.5, 0.5)
    two = [*data, _record(1.0, seed=2, truth=TRUTH, name="c1")]
    with pytest.raises(IdentificationError, match="degree=2"):
        BinghamEstimator(degree=2).fit(two)


def test_round_trip_and_registry(tmp_path: Path) -> None:
    assert model_class("bingham") is BinghamModel
    assert isinstance(get_estimator("bingham", degree=1), BinghamEstimator)
    data = [
        _record(c, seed=k, truth=TRUTH, name=f"c{c}", noise=5.0)
        for k, c in enumerate((0.0, 0.5, 1.0))
    ]
    fit = BinghamEstimator(degree=2, v_eps=0.002).fit(data)
    loaded = load_model(fit.save(tmp_path / "b.json"))
    assert loaded == fit
    np.testing.assert_array_equal(loaded.predict(data[1]), fit.predict(data[1]))


def test_errors_name_the_field() -> None:
    with pytest.raises(DataValidationError, match="fc"):
        BinghamModel(fc=(), c0=(1.0,))
    with pytest.raises(DataValidationError, match="v_eps"):
        BinghamModel(fc=(1.0,), c0=(1.0,), v_eps=-1.0)
    with pytest.raises(DataValidationError, match="degree"):
        BinghamEstimator(degree=-1).fit([_record(0.5, truth=TRUTH)])
    with pytest.raises(DataValidationError, match="voltage"):
        BinghamEstimator(input="voltage").fit([_record(0.5, truth=TRUTH)])
    with pytest.raises(OutOfRangeError):
        TRUTH.predict(_record(1.5))


def test_dissipative_for_non_negative_coefficients() -> None:
    """With fc, c0 >= 0 and no offset the force opposes the motion: F v >= 0 at every sample."""
    m = BinghamModel(fc=(50.0, 500.0), c0=(800.0, 1200.0), input_range=(0, 1))
    for c in (0.0, 0.3, 1.0):
        exp = _record(c)
        assert np.all(m.predict(exp) * exp.v >= 0)
