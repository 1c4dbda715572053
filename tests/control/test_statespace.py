"""State-space export: equivalence with the transfer-function simulation at constant rho,
canonical structure, python-control export, frozen-pole stability."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mrdamper import DataValidationError
from mrdamper.control import frozen_stability, simulate_state_space, state_space, to_control
from mrdamper.models.lpv import LPVModel
from mrdamper.models.lpv import kernels as K

ALPHA = np.array([[-1.2, 0.30, -0.10], [0.45, -0.10, 0.05], [-0.02, 0.01, 0.0]])
BETA = np.array([[900.0, 1500.0, -400.0], [-500.0, -700.0, 300.0], [10.0, 5.0, 1.0]])


def _model() -> LPVModel:
    return LPVModel(
        alpha=ALPHA,
        beta=BETA,
        offset=3.5,
        fs=200.0,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )


@pytest.mark.parametrize("rho", [0.0, 0.37, 1.0])
def test_state_space_equals_transfer_function_at_constant_rho(rho) -> None:
    m = _model()
    u = np.random.default_rng(0).standard_normal(2000) * 0.05
    y_tf, bad = K.simulate_record(u, np.full(u.size, rho), m.alpha, m.beta, 1e12)
    assert bad == -1
    y_ss = simulate_state_space(m, u, rho)
    np.testing.assert_allclose(y_ss, y_tf + m.offset, rtol=1e-9, atol=1e-9 * np.max(np.abs(y_tf)))


def test_canonical_structure_and_control_export() -> None:
    m = _model()
    ss = state_space(m, 0.5)
    n = m.n_m
    np.testing.assert_array_equal(ss.A[:-1, 1:], np.eye(n - 1))
    np.testing.assert_allclose(ss.A[-1], -m.a(0.5)[::-1])
    np.testing.assert_array_equal(ss.B[:, 0], np.r_[np.zeros(n - 1), 1.0])
    np.testing.assert_allclose(ss.C[0], m.b(0.5)[::-1])
    assert ss.D[0, 0] == 0.0 and ss.dt == 1 / 200.0
    sys = to_control(m, 0.5)
    assert sys.dt == pytest.approx(1 / 200.0)
    np.testing.assert_allclose(np.sort_complex(sys.poles()), np.sort_complex(ss.poles))
    # same poles as the model's own frozen-pole check
    np.testing.assert_allclose(np.sort(np.abs(ss.poles)), np.sort(np.abs(m.frozen_poles([0.5])[0])))
    assert ss.to_frame().shape == (n + 1, n + 1)


def test_frozen_stability_table() -> None:
    tab = frozen_stability(_model(), n_grid=11)
    assert len(tab) == 11 and tab["stable"].all()
    bad = LPVModel(
        alpha=np.array([[-1.0, -0.2]]),
        beta=np.array([[1.0, 0.0]]),
        fs=100.0,
        input_signal="v",
        rho_range=(0.0, 1.0),
    )
    tab = frozen_stability(bad, n_grid=3)
    assert list(tab["stable"]) == [False, False, False]


def test_bad_input() -> None:
    with pytest.raises(DataValidationError, match="rho"):
        state_space(_model(), float("nan"))
    with pytest.raises(DataValidationError, match="model"):
        state_space(object(), 0.0)


def test_control_grid_on_a_fitted_quiroz_model(quiroz_models: dict[str, Any]) -> None:
    control = pytest.importorskip("control")
    from mrdamper.control.export.statespace import control_grid

    m = quiroz_models["lpv"]
    g = control_grid(m, n_grid=5)
    assert len(g) == 5 and all(isinstance(s, control.StateSpace) for s in g.systems)
    assert g[0].dt == pytest.approx(1.0 / m.fs)
    frame = g.to_frame()
    np.testing.assert_allclose(
        frame["max_pole_modulus"], [np.max(np.abs(s.poles())) for s in g.systems], rtol=1e-12
    )
    # the DC gain is the frozen model's static slope sum(b) / (1 + sum(a))
    for r, gain in zip(g.rho, frame["dc_gain"]):
        assert gain == pytest.approx(np.sum(m.b(r)) / (1.0 + np.sum(m.a(r))), rel=1e-9)
    # the response at 1 A damps more than at 0 A (larger static slope), as the records show
    assert frame["dc_gain"].iloc[-1] > frame["dc_gain"].iloc[0] > 0
