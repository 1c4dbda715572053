"""Tests of the polynomial NARX black-box model.

Known answers, free run, divergence, I/O, errors.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import get_estimator, load_model, model_class
from mrdamper.models.narx import NARXEstimator, NARXModel, candidate_structure

BASE, CANDIDATES = candidate_structure(2, 1, 3)
# base rows: 0 F[k-1], 1 F[k-2], 2 x[k], 3 x[k-1], 4 v[k], 5 v[k-1], 6 i[k], 7 i[k-1],
# 8 tanh_v[k], 9 tanh_v[k-1]
TRUTH = NARXModel(
    fs=1000.0,
    base=BASE,
    terms=[[-1, -1, -1], [0, -1, -1], [1, -1, -1], [4, -1, -1], [4, 6, -1], [6, 8, -1], [0, 6, -1]],
    theta=[0.01, 0.6, -0.1, 0.5, 0.3, 0.2, -0.1],
    scales=[1000.0, 0.01, 0.3, 1.0, 1.0],
    v0=0.05,
    input_range=(0.0, 1.0),
)


def _white(seed: int, n: int = 3000, name: str | None = None) -> Experiment:
    """Independent uniform inputs: persistently exciting for every candidate monomial."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    i = rng.uniform(0.0, 1.0, n)
    i[:2] = (0.0, 1.0)  # every record spans the full current range [0, 1] A
    return Experiment(
        t=t,
        x=rng.uniform(-0.01, 0.01, n),
        v=rng.uniform(-0.3, 0.3, n),
        F=0 * t,
        i=i,
        name=name or f"w{seed}",
    )


def _from_truth(seed: int, noise: float = 0.0, n: int = 3000) -> Experiment:
    e = _white(seed, n)
    F = TRUTH.predict(e)
    if noise:
        F = F + noise * np.random.default_rng(seed + 100).standard_normal(F.size)
    return e.replace(F=F)


def test_candidate_structure_counts() -> None:
    base, slots = candidate_structure(2, 1, 2, output_degree=1, use_tanh=False)
    assert base.shape == (8, 2)
    # monomials of degree <= 2 in 8 variables: 1 + 8 + 36 = 45; minus F*F products: 3
    assert slots.shape == (42, 2)
    assert (slots[0] == -1).all()
    assert all(sum(1 for j in row if j >= 0 and base[j, 0] == 0) <= 1 for row in slots)


def test_predict_follows_the_equation() -> None:
    e = _white(1, 400)
    F = TRUTH.predict(e)
    c = TRUTH.coefficients()
    k = np.arange(2, e.n)
    expect = (
        c["1"]
        + c["F[k-1]"] * F[k - 1]
        + c["F[k-2]"] * F[k - 2]
        + c["v[k]"] * e.v[k]
        + c["v[k]*i[k]"] * e.v[k] * e.i[k]
        + c["i[k]*tanh_v[k]"] * e.i[k] * np.tanh(e.v[k] / 0.05)
        + c["F[k-1]*i[k]"] * F[k - 1] * e.i[k]
    )
    np.testing.assert_allclose(F[2:], expect, rtol=1e-12, atol=1e-9)
    assert c["v[k]"] == pytest.approx(0.5 * 1000 / 0.3)


@pytest.mark.parametrize("refine", [False, True])
def test_known_answer_identification(refine: bool) -> None:
    """Noise-free data of a known NARX: its terms are found and their coefficients recovered."""
    data = [_from_truth(s) for s in range(3)]
    fit = NARXEstimator(refine=refine, v0=0.05).fit(data)
    got, want = fit.coefficients(), TRUTH.coefficients()
    assert set(want) <= set(got)
    for name, value in got.items():
        assert value == pytest.approx(want.get(name, 0.0), rel=1e-7, abs=1e-7), name
    assert fit.input_range == (0.0, 1.0)
    assert fit.score(_from_truth(7)).esr < 1e-20


def test_noisy_identification_is_close_and_refinement_does_not_hurt() -> None:
    data = [_from_truth(s, noise=20.0) for s in range(3)]
    ls = NARXEstimator(refine=False, v0=0.05).fit(data)
    oe = NARXEstimator(refine=True, v0=0.05).fit(data)
    test = _from_truth(11)
    assert ls.score(test).esr < 1e-3
    assert oe.provenance["free_run_cost"] <= ls.provenance["free_run_cost"]
    assert oe.score(test).esr < 1e-3


def test_free_run_never_feeds_back_the_measured_force() -> None:
    e = _from_truth(3, noise=30.0)
    fit = NARXEstimator(refine=False, v0=0.05).fit([_from_truth(s, noise=30.0) for s in range(3)])
    tampered = e.replace(F=np.where(np.arange(e.n) >= fit.max_lag, e.F + 500.0, e.F))
    np.testing.assert_array_equal(fit.predict(tampered), fit.predict(e))
    one_step = fit.one_step_predict(e)
    assert not np.array_equal(fit.one_step_predict(tampered), one_step)
    # Output (measurement) noise: the free run follows the noise-free force, so its error sits
    # at the noise floor sigma^2; one-step prediction feeds back noisy measured forces through
    # the F[k-1], F[k-2] terms, which adds error on top of sigma^2.
    err_free = np.mean((fit.predict(e) - e.F) ** 2)
    err_one = np.mean((one_step - e.F) ** 2)
    assert err_free == pytest.approx(30.0**2, rel=0.1)
    assert err_one > 1.05 * err_free


def test_divergence_is_reported_with_the_sample() -> None:
    base = np.array([[0, 1], [2, 0]])
    m = NARXModel(
        fs=1000.0,
        base=base,
        terms=[[0], [1]],
        theta=[1.5, 1.0],
        scales=[1.0, 1.0, 1.0, 1.0, 1.0],
        v0=1.0,
        force_bound=1e6,
        input_range=(0, 1),
    )
    n = 200
    t = np.arange(n) * 1e-3
    e = Experiment(t=t, x=0 * t, v=np.ones(n), F=np.zeros(n), i=np.zeros(n), name="blow-up")
    F = np.zeros(n)
    for k in range(1, n):
        F[k] = 1.5 * F[k - 1] + 1.0
    first = int(np.argmax(np.abs(F) > 1e6))
    with pytest.raises(SimulationDivergedError, match="blow-up") as info:
        m.predict(e)
    assert info.value.sample == first
    assert info.value.model == "narx"


def test_round_trip_is_bit_identical(tmp_path: Path) -> None:
    assert model_class("narx") is NARXModel
    assert isinstance(get_estimator("narx", degree=2), NARXEstimator)
    data = [_from_truth(s, noise=10.0) for s in range(2)]
    fit = NARXEstimator(n_terms=8).fit(data)
    loaded = load_model(fit.save(tmp_path / "narx.json"))
    assert isinstance(loaded, NARXModel)
    assert loaded == fit
    np.testing.assert_array_equal(loaded.predict(data[1]), fit.predict(data[1]))
    assert loaded.term_names == fit.term_names


def test_other_record_rate_is_resampled() -> None:
    fit = NARXEstimator(refine=False, v0=0.05, model_fs=1000.0).fit(
        [_from_truth(s) for s in range(2)]
    )
    e = _white(5, 600)
    t = np.arange(2 * e.n) * 5e-4
    fast = Experiment(
        t=t,
        x=np.repeat(e.x, 2),
        v=np.repeat(e.v, 2),
        F=np.zeros(t.size),
        i=np.repeat(e.i, 2),
        name="fast",
    )
    F = fit.predict(fast)
    assert F.shape == (fast.n,) and np.all(np.isfinite(F))


def test_predict_never_reads_the_measured_force() -> None:
    """The free run starts from rest (the first ``max_lag`` forces 0 N), as the step and its C
    and FMU exports do: the record's measured force changes nothing."""
    fit = NARXEstimator(refine=False, v0=0.05).fit([_from_truth(s) for s in range(2)])
    e = _from_truth(4)
    shifted = e.replace(F=e.F + np.where(np.arange(e.n) < fit.max_lag, 300.0, 0.0))
    a = fit.predict(e)
    np.testing.assert_array_equal(a, fit.predict(shifted))
    np.testing.assert_array_equal(a[: fit.max_lag], 0.0)
    assert np.max(np.abs(a)) > 10.0


def test_bad_input_names_the_field() -> None:
    data = [_from_truth(0)]
    with pytest.raises(DataValidationError, match="voltage"):
        NARXEstimator(input="voltage").fit(data)
    fit = NARXEstimator(refine=False, v0=0.05).fit(data)
    no_i = Experiment(
        t=data[0].t, x=data[0].x, v=data[0].v, F=data[0].F, voltage=data[0].i, name="v-only"
    )
    with pytest.raises(DataValidationError, match="'i'"):
        fit.predict(no_i)
    short = data[0].slice(0, 2)
    with pytest.raises(DataValidationError, match="initial-condition"):
        fit.predict(short)
    with pytest.raises(IdentificationError, match="equations"):
        NARXEstimator().fit([data[0].slice(0, 100)])
    for settings, field in (
        ({"n_a": 0}, "n_a"),
        ({"degree": 0}, "degree"),
        ({"n_terms": 0}, "n_terms"),
        ({"input": "q"}, "input"),
        ({"v0": -1.0}, "v0"),
        ({"err_tol": 2.0}, "err_tol"),
        ({"bound_factor": 0.5}, "bound_factor"),
    ):
        with pytest.raises(DataValidationError, match=field):
            NARXEstimator(**settings).fit(data)
    flat = data[0].replace(F=np.full(data[0].n, 5.0))
    with pytest.raises(DataValidationError, match="constant force"):
        NARXEstimator().fit([flat])
    with pytest.raises(DataValidationError, match="theta"):
        NARXModel(fs=1.0, base=BASE, terms=[[0, -1, -1]], theta=[1.0, 2.0], scales=[1.0] * 5)
    with pytest.raises(DataValidationError, match="base"):
        NARXModel(fs=1.0, base=[[0, 0]], terms=[[0]], theta=[1.0], scales=[1.0] * 5)


def test_fit_does_not_mutate_and_is_deterministic() -> None:
    data = [_from_truth(s, noise=5.0) for s in range(2)]
    before = [d.F.copy() for d in data]
    a = NARXEstimator().fit(data)
    b = NARXEstimator().fit(data)
    for d, f in zip(data, before, strict=True):
        np.testing.assert_array_equal(d.F, f)
    np.testing.assert_array_equal(a.theta, b.theta)
    np.testing.assert_array_equal(a.terms, b.terms)


@pytest.mark.slow
@pytest.mark.realdata
def test_quiroz_one_fold_smoke(quiroz_unfiltered_dir: Path) -> None:
    """Leave-one-condition-out fold 5 mm / 3 Hz: runs, finite, far better than the mean force."""
    from mrdamper.data.readers import read_directory

    s = read_directory(quiroz_unfiltered_dir)
    train = s.where(lambda e: e.metadata["condition"] != "5mm_3Hz")
    test = s.filter(condition="5mm_3Hz")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = NARXEstimator().fit(train)
    esr = [m.score(e).esr for e in test]
    assert np.all(np.isfinite(esr))
    assert np.mean(esr) < 0.5  # loose sanity bound: clearly better than predicting the mean force


def test_old_setting_name_refine_max_nfev_is_accepted_with_a_note() -> None:
    from mrdamper.errors import DataValidationError, Note
    from mrdamper.models import get_estimator

    with pytest.warns(Note, match="'refine_max_nfev' is now called 'max_nfev'"):
        est = get_estimator("narx", refine_max_nfev=7)
    assert est.max_nfev == 7
    with pytest.raises(DataValidationError, match="refine_max_nfev"):
        get_estimator("narx", refine_max_nfev=7, max_nfev=9)


def test_term_selection_matches_least_squares_on_the_selected_columns() -> None:
    """Each error reduction ratio is what adding that column explains, by plain least squares;
    the first pick is the column best correlated with the output; a collinear copy and a zero
    column are never picked."""
    from mrdamper.models.narx.fit import gram_select

    rng = np.random.default_rng(3)
    X = rng.standard_normal((400, 8))
    X[:, 6] = 2.0 * X[:, 1]  # collinear with column 1
    X[:, 7] = 0.0
    y = 3.0 * X[:, 2] - 1.5 * X[:, 4] + 0.5 * X[:, 1] + 0.05 * rng.standard_normal(400)
    B = np.column_stack([X, y])
    A = B.T @ B
    d = np.sqrt(np.diag(A))
    d[d == 0] = 1.0
    A /= d[:, None] * d[None, :]
    A[7, :] = 0.0
    order, err = gram_select(A, 6, 1e-12, 1e-8)
    assert order[0] == 2  # the largest share of y
    assert not ({1, 6} <= set(order.tolist())) and 7 not in order
    yy = y @ y
    explained = 0.0
    for k in range(order.size):
        cols = X[:, order[: k + 1]]
        res = y - cols @ np.linalg.lstsq(cols, y, rcond=None)[0]
        assert err[k] == pytest.approx(1.0 - res @ res / yy - explained, abs=1e-9)
        explained += err[k]
    assert order.dtype == np.int64 and err.dtype == np.float64
