"""LPV / LTI input-output models: known-answer identification, bad input, JSON round trip,
range policy, divergence detection, order selection."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mrdamper import (
    DataValidationError,
    Experiment,
    IdentificationError,
    OutOfRangeError,
    SchemaError,
    SimulationDivergedError,
    get_estimator,
    load_model,
)
from mrdamper.analysis import ZoneLaws
from mrdamper.errors import Note
from mrdamper.models.lpv import LPVEstimator, LPVModel, LTIModel, select_order
from mrdamper.models.lpv import kernels as K
from mrdamper.models.lpv.estimator import MIN_MODEL_FS

FS = 500.0  # at least the LPV family's lowest default model rate (MIN_MODEL_FS)
ALPHA = np.array([[-1.2, 0.30, -0.10], [0.45, -0.10, 0.05]])  # a_j(rho), rho in [0, 1]
BETA = np.array([[900.0, 1500.0, -400.0], [-500.0, -700.0, 300.0]])  # b_j(rho) [N s/m]


def _record(rho_level, seed, n=1500, name=None, varying=False, laws=None, offset=0.0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    v = 0.1 * np.sin(2 * np.pi * 1.3 * t) + 0.03 * rng.standard_normal(n)
    i = np.full(n, float(rho_level))
    if varying:
        i = np.clip(0.5 + 0.5 * np.sin(2 * np.pi * 0.37 * t), 0.0, 1.0)
    u = v if laws is None else laws.scheduling_input(v, i)
    y, bad = K.simulate_record(u, i, ALPHA, BETA, 1e12)
    assert bad == -1
    return Experiment(
        t=t,
        x=np.cumsum(v) / FS,
        v=v,
        F=y + offset,
        i=i,
        name=name or f"r{seed}",
        metadata={"current": float(rho_level)},
    )


def _train(laws=None, offset=0.0):
    recs = [_record(lev, k, laws=laws, offset=offset) for k, lev in enumerate((0.0, 0.5, 1.0))]
    recs.append(_record(0.0, 9, varying=True, name="varying", laws=laws, offset=offset))
    return recs


def _known_laws() -> ZoneLaws:
    gm = np.array([[800.0, 2000.0, 0.0], [15000.0, 40000.0, 0.0], [900.0, 1800.0, 0.0]])
    return ZoneLaws(
        gm,
        np.zeros((3, 3)),
        (0.01, 0.01),
        (-0.01, -0.01),
        True,
        (0.0, 1.0),
        [0.0, 1.0],
        gm[:, :2].T,
        np.zeros((2, 3)),
        [-0.01, -0.02],
        [0.01, 0.02],
    )


@pytest.mark.parametrize(
    ("refine", "solver"), [(False, "gauss-newton"), (True, "gauss-newton"), (True, "least_squares")]
)
@pytest.mark.slow
def test_identifies_known_lpv_coefficients(refine, solver) -> None:
    est = LPVEstimator(
        n_m=2, n_rho=2, input_signal="v", offset=False, refine=refine, oe_solver=solver
    )
    m = est.fit(_train())
    np.testing.assert_allclose(m.alpha, ALPHA, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(m.beta, BETA, rtol=1e-8, atol=1e-6)
    assert m.provenance["ls_solver"] in ("cholesky", "qr")
    assert m.provenance["frozen_stable"] is True
    e = _record(0.3, 42, name="test")
    assert m.score(e).esr < 1e-12


def test_identifies_through_known_scheduling_input_with_offset() -> None:
    laws = _known_laws()
    m = LPVEstimator(n_m=2, n_rho=2, zone_laws=laws, refine=True, input_signal="u").fit(
        _train(laws, offset=-92.0)
    )
    assert m.offset == pytest.approx(-92.0, abs=1e-5)
    np.testing.assert_allclose(m.alpha, ALPHA, rtol=1e-7, atol=1e-8)
    assert m.zone_laws is laws


def test_estimator_does_not_mutate_input_and_lti_kind() -> None:
    recs = _train()
    before = [r.F.copy() for r in recs]
    m = get_estimator("lti", n_m=2, input_signal="v").fit(recs)
    assert isinstance(m, LTIModel) and m.kind == "lti" and m.n_rho == 0
    for r, b in zip(recs, before):
        np.testing.assert_array_equal(r.F, b)
    # the LTI model cannot follow the scheduled dynamics as well as the LPV model
    lpv = get_estimator("lpv", n_m=2, n_rho=2, input_signal="v").fit(recs)
    e = _record(1.0, 77)
    assert lpv.score(e).esr < m.score(e).esr


def test_json_round_trip_is_bit_identical(tmp_path) -> None:
    laws = _known_laws()
    m = LPVEstimator(n_m=2, n_rho=2, zone_laws=laws, refine=False).fit(_train(laws))
    path = m.save(tmp_path / "lpv.json")
    again = load_model(path)
    e = _record(0.7, 5)
    np.testing.assert_array_equal(again.predict(e), m.predict(e))
    assert isinstance(again.zone_laws, ZoneLaws)
    with pytest.raises(FileExistsError):
        m.save(path)
    m.save(path, force=True)


def test_range_policy_on_scheduling_variable() -> None:
    m = LPVEstimator(n_m=2, n_rho=2, input_signal="v", refine=False).fit(_train())
    hot = _record(1.5, 3)
    with pytest.raises(OutOfRangeError, match="i"):
        m.predict(hot)
    with pytest.warns(RuntimeWarning, match="extrapolating"):
        m.with_range_policy("warn").predict(hot)
    clipped = m.with_range_policy("clip").predict(hot)
    at_max = m.predict(hot.replace(i=np.ones(hot.n)))
    np.testing.assert_array_equal(clipped, at_max)


def test_divergence_is_detected() -> None:
    m = LPVModel(
        alpha=np.array([[-1.05]]),
        beta=np.array([[1.0]]),
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
        force_bound=1e6,
    )
    assert not m.is_frozen_stable()
    with pytest.raises(SimulationDivergedError, match="diverged at sample"):
        m.predict(_record(0.5, 1))


@pytest.mark.parametrize(
    ("settings", "field"),
    [
        ({"n_m": 0}, "n_m"),
        ({"n_rho": -1}, "n_rho"),
        ({"input_signal": "w"}, "input_signal"),
        ({"reading": "free"}, "reading"),
        ({"eta": -3.0}, "eta"),
        ({"fs": 0.0}, "fs"),
    ],
)
def test_bad_settings(settings, field) -> None:
    with pytest.raises(DataValidationError, match=field):
        LPVEstimator(**{"input_signal": "v", **settings}).fit(_train())


def test_bad_data() -> None:
    recs = [_record(0.5, k) for k in range(2)] + [_record(1.0, 5)]  # two current levels
    with pytest.raises(IdentificationError, match="distinct"):
        LPVEstimator(n_rho=2, input_signal="v").fit(recs)
    other_rate = _record(0.0, 1)
    t = np.arange(other_rate.n) / 1000.0
    # Mixed rates: the lowest one is the model rate, with a one-line note (same rule as NARX).
    with pytest.warns(Note, match="model rate model_fs"):
        mixed = LPVEstimator(input_signal="v", refine=False, stability="warn").fit(
            _train() + [other_rate.replace(t=t, name="fast")]
        )
    assert mixed.fs == min(FS, 1000.0)
    with pytest.raises(DataValidationError, match="model_fs"):
        LPVEstimator(input_signal="v", model_fs=-1.0).fit(_train())
    with pytest.warns(Note, match="now called 'model_fs'"):
        assert LPVEstimator(fs=100.0).model_fs == 100.0
    with pytest.raises(SchemaError):
        LPVEstimator(input_signal="v").fit([])
    with pytest.raises(DataValidationError, match="n_rho"):
        get_estimator("lti", n_rho=1)._validate()


def test_records_below_the_lowest_default_rate_are_up_sampled_with_a_note() -> None:
    slow = [r.replace(t=r.t * FS / 100.0) for r in _train()]  # the same samples at 100 Hz
    assert slow[0].fs == pytest.approx(100.0)
    with pytest.warns(Note, match=r"model_fs = 500 Hz \(the kind's lowest default rate\)"):
        up = LPVEstimator(input_signal="v", refine=False, stability="warn").fit(slow)
    assert up.fs == MIN_MODEL_FS == 500.0
    assert up.predict(slow[0]).shape == (slow[0].n,)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        own = LPVEstimator(input_signal="v", refine=False, stability="warn", model_fs=100.0)
        assert own.fit(slow).fs == 100.0
    with pytest.warns(RuntimeWarning, match="above the record rate 100 Hz"):
        LPVEstimator(input_signal="v", refine=False, stability="warn", model_fs=1000.0).fit(slow)


def test_resampling_to_model_rate() -> None:
    m = LPVEstimator(n_m=2, n_rho=2, input_signal="v", refine=False).fit(_train())
    slow = _record(0.4, 8, n=3000)
    fast_t = np.arange(5 * slow.n - 4) / (5 * FS)
    fast = Experiment(
        t=fast_t,
        x=np.interp(fast_t, slow.t, slow.x),
        v=np.interp(fast_t, slow.t, slow.v),
        F=np.interp(fast_t, slow.t, slow.F),
        i=np.full(fast_t.size, 0.4),
        name="fast",
    )
    assert m.predict(fast).size == fast.n
    assert m.score(fast).esr < 0.05  # interpolated white-ish input: only an approximation


def test_drive_lag_scheduling_variable() -> None:
    t = np.arange(1000) / FS
    volt = np.where((t % 1.0) < 0.5, 0.0, 2.0)
    e = Experiment(t=t, x=0 * t, v=np.sin(t), F=np.sin(t), voltage=volt, name="v")
    m = LPVModel(
        alpha=np.zeros((1, 2)),
        beta=np.zeros((1, 2)),
        fs=FS,
        input_signal="v",
        input="voltage",
        eta=50.0,
        input_range=(0.0, 2.0),
    )
    rho = m.scheduling_variable(e)
    k = int(np.argmax(volt > 0)) + 1
    assert rho[k] == pytest.approx(2.0 * (1 - np.exp(-50.0 / FS)))
    assert np.all(rho <= 2.0) and np.all(rho >= 0.0)


def test_select_order_table() -> None:
    recs = _train()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tab = select_order(
            recs[:3], recs[3:], orders=(1, 2), rho_degrees=(0, 2), input_signal="v", refine=False
        )
    assert set(tab.columns) >= {"n_m", "n_rho", "val_esr", "max_frozen_pole", "error"}
    best = tab.iloc[0]
    assert (best.n_m, best.n_rho) == (2, 2)
    assert best.val_esr < 1e-10


@pytest.mark.slow
@pytest.mark.realdata
def test_quiroz_one_fold_accuracy(quiroz_unfiltered_dir) -> None:
    """Leave-one-condition-out fold 5 mm / 3 Hz: free-run test ESR of the refined LPV model."""
    from mrdamper.data.readers import read_directory

    s = read_directory(quiroz_unfiltered_dir)
    train = s.where(lambda e: e.metadata["condition"] != "5mm_3Hz")
    test = s.filter(condition="5mm_3Hz")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = LPVEstimator(model_fs=200.0).fit(train)
    esr = np.mean([m.score(e).esr for e in test])
    assert esr < 0.04


def test_gram_pass_matches_the_regression_matrix() -> None:
    """The blockwise Gram sums (records longer and shorter than a chunk, partial last blocks)
    equal ``X^T X``, ``X^T t``, ``t^T t`` of the materialised regression (an independent path)."""
    rng = np.random.default_rng(5)
    lens = [3, 700, 2 * K._BLOCK * K._CHUNK + 1000, K._BLOCK + 4]
    n = sum(lens)
    starts = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
    y, u, rho = rng.standard_normal(n), rng.standard_normal(n), rng.uniform(0.0, 1.0, n)
    w = rng.uniform(0.2, 2.0, len(lens))
    for n_m, n_p, with_const in ((3, 3, True), (2, 1, False), (5, 2, True)):
        G, g, yy, n_eq = K.gram_pass(y, u, rho, starts, w, n_m, n_p, with_const)
        X, t = K.build_regressors(y, u, rho, starts, w, n_m, n_p, with_const)
        assert n_eq == X.shape[0] == sum(max(L - n_m, 0) for L in lens)
        np.testing.assert_allclose(G, X.T @ X, rtol=1e-12, atol=1e-12 * np.abs(G).max())
        np.testing.assert_allclose(g, X.T @ t, rtol=1e-12, atol=1e-12 * np.abs(g).max())
        assert yy == pytest.approx(float(t @ t), rel=1e-12)


@pytest.mark.parametrize(
    ("n", "with_offset", "with_stiffness"), [(700, True, True), (5, False, False)]
)
def test_oe_normal_equations_match_the_stored_jacobian(n, with_offset, with_stiffness) -> None:
    """The blockwise normal equations (a record across block boundaries, and one shorter than the
    order's start-up) equal ``J^T J``, ``J^T e`` and ``e^T e`` of the stored sensitivity Jacobian
    of :func:`simulate_sensitivity` (itself checked against central differences of the fused
    free-run kernel), and the cost equals the free-run residual's ``residual_sse``."""
    rng = np.random.default_rng(3)
    u, rho = rng.standard_normal(n), rng.uniform(0.0, 1.0, n)
    F, xd = rng.standard_normal(n), rng.standard_normal(n)
    f0, k_x, w = 0.3, (1.7 if with_stiffness else 0.0), 0.8
    y, J, bad = K.simulate_sensitivity(u, rho, ALPHA, BETA, 1e12)
    assert bad == -1
    # the stored sensitivities against central differences of the fused free-run kernel
    theta, h = np.r_[ALPHA.ravel(), BETA.ravel()], 1e-6
    for c in range(theta.size):
        step = np.zeros(theta.size)
        step[c] = h * max(1.0, abs(theta[c]))
        ya = K.simulate_record(u, rho, *K.split_theta(theta + step, 2, 3), 1e12)[0]
        yb = K.simulate_record(u, rho, *K.split_theta(theta - step, 2, 3), 1e12)[0]
        fd = (ya - yb) / (2 * step[c])
        np.testing.assert_allclose(J[:, c], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max() + 1e-12)
    e = y + f0 + k_x * xd - F
    cols = (
        [J] + ([np.ones((n, 1))] if with_offset else []) + ([xd[:, None]] if with_stiffness else [])
    )
    Jx = np.hstack(cols)
    cost, g, H, bad = K.oe_normal_equations(
        u, rho, ALPHA, BETA, F, xd, f0, k_x, w, 1e12, with_offset, with_stiffness
    )
    assert bad == -1
    assert cost == pytest.approx(w * float(e @ e), rel=1e-12)
    assert K.residual_sse(y, F, f0, xd, k_x) == pytest.approx(float(e @ e), rel=1e-12)
    np.testing.assert_allclose(g, w * Jx.T @ e, rtol=1e-10, atol=1e-12 * np.abs(g).max())
    np.testing.assert_allclose(H, w * Jx.T @ Jx, rtol=1e-10, atol=1e-12 * np.abs(H).max())
    assert np.array_equal(H, H.T)
