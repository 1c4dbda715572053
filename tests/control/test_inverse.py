"""Inverse model, exact per-sample method: round trips (force -> current -> force), saturation,
drive-lag lead, bad input. The regularised method (the default) is tested in
test_inverse_regularised.py."""

from __future__ import annotations

import warnings

import matplotlib
import numpy as np
import pytest

from mrdamper.control import InverseResult, driver_command, inverse_current
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, Note, OutOfRangeError
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.lpv import LPVEstimator, LPVModel, LTIModel
from mrdamper.models.lpv import kernels as LK
from mrdamper.models.semiphenomenological import SP3Model

matplotlib.use("Agg")

FS = 1000.0
ALPHA = np.array([[-1.2, 0.10, -0.02], [0.40, -0.05, 0.01]])
BETA = np.array([[300.0, 500.0, -40.0], [-200.0, -300.0, 30.0]])


def _motion(n: int = 3000, seed: int = 0) -> tuple[Experiment, np.ndarray]:
    """A 3 Hz sine stroke starting at rest and a random piecewise-constant current in [0, 2] A."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    x = -0.01 * np.cos(2 * np.pi * 3 * t)
    v = 0.01 * 2 * np.pi * 3 * np.sin(2 * np.pi * 3 * t)
    i = np.repeat(rng.uniform(0.1, 1.9, n // 50 + 1), 50)[:n]
    return Experiment(t=t, x=x, v=v, F=0 * t, i=i, name="motion"), i


def _lpv_v(eta: float | None = None) -> LPVModel:
    return LPVModel(
        alpha=ALPHA,
        beta=BETA,
        offset=5.0,
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 2.0),
        input_range=(0.0, 2.0),
        eta=eta,
    )


def test_lpv_round_trip_known_model() -> None:
    m = _lpv_v()
    e, i = _motion()
    F = m.predict(e.replace(i=i))
    res = inverse_current(m, e, F, method="exact")
    assert isinstance(res, InverseResult)
    tol = 1e-6 * np.max(np.abs(F))
    assert not res.saturated[m.n_m :].any()
    np.testing.assert_allclose(res.F_achieved[m.n_m :], F[m.n_m :], rtol=0, atol=2 * tol)
    # the current is recovered wherever the force depends on it noticeably
    sens = np.abs(m.predict(e.replace(i=np.clip(i + 1e-3, 0, 2))) - F) / 1e-3
    ok = (
        sens > 20.0
    )  # [N/A]; the command is held while the force is within tol, so |di| <= ~tol / sens
    ok[: m.n_m] = False
    assert ok.mean() > 0.3
    np.testing.assert_allclose(res.i[ok], i[ok], atol=4 * tol / 20.0)
    frame = res.to_frame()
    assert list(frame.columns) == ["t", "F_desired", "i", "rho", "F_achieved", "saturated"]
    assert res.plot() is not None


def test_lpv_fitted_on_virtual_rig_round_trip() -> None:
    from mrdamper.rig import doe

    ds = doe.table_ii(seed=0, scale=0.07)
    train = [e for e in ds if e.metadata["experiment"] in (1, 2, 3)][::4]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = LPVEstimator(n_m=2, n_rho=2, laws_by="bins", input_signal="u").fit(train)
    e = ds[20]
    F = m.predict(e)
    res = inverse_current(m, e, F, method="exact")
    tol = 1e-6 * np.max(np.abs(F))
    ok = ~res.saturated
    assert ok.mean() > 0.9
    np.testing.assert_allclose(res.F_achieved[ok], F[ok], rtol=0, atol=2 * tol)
    assert np.all((res.i >= m.input_range[0]) & (res.i <= m.input_range[1]))
    assert np.median(np.abs(res.i - e.i)) < 1e-6


def test_lpv_unreachable_force_saturates_at_range_ends() -> None:
    m = _lpv_v()
    e, i = _motion()
    F = m.predict(e.replace(i=i))
    res = inverse_current(m, e, 10 * (F - m.offset) + m.offset, method="exact")
    sat = res.saturated
    assert sat.mean() > 0.5
    at_end = np.isclose(res.i[sat], 0.0) | np.isclose(res.i[sat], 2.0)
    # the best force lies at an end of the range or a stationary point of F(rho) inside it
    assert at_end.mean() > 0.5
    assert np.all(np.abs(res.error[sat]) > 0)


def test_lpv_with_drive_lag_uses_lead_command() -> None:
    m = _lpv_v(eta=80.0)
    e, i = _motion()
    F = m.predict(e.replace(i=i))
    res = inverse_current(m, e, F, method="exact")
    ok = ~res.saturated
    assert ok[5:].mean() > 0.9
    np.testing.assert_allclose(res.F_achieved[ok], F[ok], atol=2e-6 * np.max(np.abs(F)))
    assert np.all((res.i >= 0) & (res.i <= 2))
    # the command passed through the drive lag gives the scheduling trajectory
    np.testing.assert_allclose(LK.first_order_lag(res.i, e.dt, 80.0), res.rho, atol=1e-9)


def test_driver_command_inverts_the_lag_exactly() -> None:
    w = np.random.default_rng(3).uniform(0, 2, 400)
    w[1] = w[0]
    rho = LK.first_order_lag(w, 1e-3, 50.0)
    cmd = driver_command(rho, 50.0, 1e-3)
    np.testing.assert_allclose(cmd[1:-1], w[1:-1], rtol=0, atol=1e-9)
    clipped = driver_command(rho, 50.0, 1e-3, limits=(0.5, 1.5))
    assert clipped.min() >= 0.5 and clipped.max() <= 1.5
    with pytest.raises(DataValidationError, match="eta"):
        driver_command(rho, -1.0, 1e-3)


def _sp3() -> SP3Model:
    return SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), input_range=(0.0, 2.0))


@pytest.mark.parametrize("kind", ["sp3", "bingham"])
def test_static_round_trip(kind: str) -> None:
    m = (
        _sp3()
        if kind == "sp3"
        else BinghamModel(
            fc=(50.0, 400.0, -40.0), c0=(800.0, 900.0), v_eps=0.01, input_range=(0.0, 2.0)
        )
    )
    e, i = _motion(seed=5)
    F = m.predict(e.replace(i=i))
    res = inverse_current(m, e, F, method="exact")
    np.testing.assert_allclose(res.F_achieved, F, rtol=0, atol=1e-8 * np.max(np.abs(F)))
    sens = np.abs(m.predict(e.replace(i=np.clip(i + 1e-3, 0, 2))) - F) / 1e-3
    ok = sens > 10.0
    assert ok.mean() > 0.5
    np.testing.assert_allclose(res.i[ok], i[ok], atol=1e-6)
    assert not res.saturated[ok].any()


def test_static_unreachable_targets() -> None:
    m = BinghamModel(fc=(50.0, 400.0), c0=(800.0, 900.0), input_range=(0.0, 2.0))
    e, _ = _motion(seed=1)
    moving = np.abs(e.v) > 1e-3
    # force opposite to the velocity: the damper can only dissipate -> smallest force, lowest
    # current
    res = inverse_current(m, e, -500.0 * np.sign(e.v), method="exact")
    assert res.saturated[moving].all()
    np.testing.assert_allclose(res.i[moving], 0.0, atol=1e-9)
    np.testing.assert_allclose(res.F_achieved, m.predict(e.replace(i=np.zeros(e.n))), rtol=1e-12)
    # more than the largest current gives -> top of the range
    big = 1e5 * np.sign(e.v)
    res = inverse_current(m, e, big, method="exact")
    assert res.saturated[moving].all()
    np.testing.assert_allclose(res.i[moving], 2.0, atol=1e-9)
    # a user range inside the identified one confines the current
    res = inverse_current(m, e, big, i_range=(0.2, 1.0), method="exact")
    np.testing.assert_allclose(res.i[moving], 1.0, atol=1e-9)
    assert res.i_range == (0.2, 1.0)


def test_arrays_input_and_bad_inputs() -> None:
    m = _sp3()
    e, i = _motion(n=500)
    F = m.predict(e.replace(i=i))
    res = inverse_current(m, {"t": e.t, "x": e.x, "v": e.v}, F, method="exact")
    np.testing.assert_allclose(res.F_achieved, F, atol=1e-6)
    with pytest.raises(DataValidationError, match="F_desired"):
        inverse_current(m, e, F[:-1], method="exact")
    with pytest.raises(DataValidationError, match="F_desired"):
        inverse_current(m, e, np.full(e.n, np.nan), method="exact")
    with pytest.raises(DataValidationError, match="mapping lacks"):
        inverse_current(m, {"t": e.t, "v": e.v}, F, method="exact")
    with pytest.raises(OutOfRangeError, match="i_range"):
        inverse_current(m, e, F, i_range=(0.0, 3.0), method="exact")
    with pytest.raises(DataValidationError, match="i_range"):
        inverse_current(m, e, F, i_range=(1.0, 0.5), method="exact")
    lpv = _lpv_v()
    slow = Experiment(t=e.t * 2, x=e.x, v=e.v, F=e.F, i=e.i)
    # another rate is solved at the model rate and interpolated back, as simulate does
    with pytest.warns(Note, match="solved at the model rate"):
        res = inverse_current(lpv, slow, F, method="exact")
    assert res.i.size == slow.n and np.all(np.isfinite(res.i)) and res.saturated.size == slow.n
    with pytest.warns(Note, match="solved at the model rate"):
        res = inverse_current(lpv, slow, F)
    assert res.i.size == slow.n and np.all(np.isfinite(res.i))
    lti = LTIModel(
        alpha=ALPHA[:, :1], beta=BETA[:, :1], fs=FS, input_signal="v", input_range=(0.0, 2.0)
    )
    with pytest.raises(DataValidationError, match="through its step: 'regularised' only"):
        inverse_current(lti, e, F, method="exact")


def test_an_object_without_inverse_form_or_step_is_refused() -> None:
    e, _ = _motion(n=200)
    bare = type("Bare", (), {"kind": "bare", "input_range": (0.0, 1.0), "input": "i"})()
    with pytest.raises(TypeError, match="'bare': neither an inverse form nor a per-sample step"):
        inverse_current(bare, e, np.zeros(e.n))
