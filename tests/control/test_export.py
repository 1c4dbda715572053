"""LPV export: .mat and JSON round trips rebuild A(rho), C(rho) and the zone laws."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import loadmat

from mrdamper.analysis import ZoneLaws
from mrdamper.control import export_lpv, lpv_export_data, state_space
from mrdamper.errors import DataValidationError, OutputExistsError
from mrdamper.models.base import decode_value
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.lpv import LPVModel, LTIModel

ALPHA = np.array([[-1.2, 0.30, -0.10], [0.45, -0.10, 0.05], [-0.02, 0.01, 0.0]])
BETA = np.array([[900.0, 1500.0, -400.0], [-500.0, -700.0, 300.0], [10.0, 5.0, 1.0]])
LAWS = ZoneLaws(
    gamma_m=np.array([[300.0, 200.0, 1.0], [3000.0, 4000.0, -500.0], [300.0, 150.0, 2.0]]),
    gamma_c=np.array([[-50.0, -200.0, 3.0], [0.5, 0.0, 0.0], [50.0, 200.0, 4.0]]),
    mu_high=(0.01, 0.02),
    mu_low=(-0.01, -0.02),
    symmetric=True,
    rho_range=(0.0, 2.0),
    levels=np.zeros(0),
    level_m=np.zeros((0, 3)),
    level_c=np.zeros((0, 3)),
    level_v_low=np.zeros(0),
    level_v_high=np.zeros(0),
)


def _model(eta: float | None = None) -> LPVModel:
    return LPVModel(
        alpha=ALPHA,
        beta=BETA,
        offset=3.5,
        fs=200.0,
        input_signal="u",
        zone_laws=LAWS,
        rho_range=(0.0, 2.0),
        input_range=(0.0, 2.0),
        eta=eta,
        provenance={"note": "test", "x": 1.5},
    )


def _rebuild(A_poly: np.ndarray, C_poly: np.ndarray, rho: float) -> tuple[np.ndarray, np.ndarray]:
    powers = rho ** np.arange(A_poly.shape[-1])
    return (A_poly * powers).sum(-1), (C_poly * powers).sum(-1)


def test_mat_round_trip_rebuilds_state_space(tmp_path) -> None:
    m = _model(eta=40.0)
    path = export_lpv(m, tmp_path / "lpv.mat")
    d = loadmat(path)
    assert str(d["schema"][0]) == "mrdamper.lpv_export" and str(d["model_kind"][0]) == "lpv"
    assert d["Ts"].item() == pytest.approx(1 / 200.0)
    assert d["eta"].item() == 40.0 and str(d["rho_name"][0]) == "i"
    for rho in (0.0, 0.7, 2.0):
        A, C = _rebuild(d["A_poly"], d["C_poly"], rho)
        ss = state_space(m, rho)
        np.testing.assert_allclose(A, ss.A, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(C, ss.C, rtol=1e-14, atol=1e-12)
    np.testing.assert_array_equal(d["B"], state_space(m, 0.0).B)
    grid = d["rho_grid"].ravel()
    k = 7
    np.testing.assert_array_equal(d["A_grid"][:, :, k], state_space(m, grid[k]).A)
    poles = d["poles_re"][k] + 1j * d["poles_im"][k]
    np.testing.assert_allclose(
        np.sort(np.abs(poles)), np.sort(np.abs(m.frozen_poles([grid[k]])[0]))
    )
    np.testing.assert_allclose(d["max_pole_modulus"].ravel(), np.abs(m.frozen_poles(grid)).max(1))
    # the zone laws rebuild the LPV input u exactly as the model does
    np.testing.assert_array_equal(d["gamma_m"], LAWS.gamma_m)
    v = np.linspace(-0.3, 0.3, 41)
    rho = 1.3
    gm, mu_h, mu_l = d["gamma_m"], d["mu_high"].ravel(), d["mu_low"].ravel()
    m_r = gm @ rho ** np.arange(gm.shape[1])
    hi, lo = mu_h[0] * rho + mu_h[1], mu_l[0] * rho + mu_l[1]
    u = np.where(
        v < lo,
        lo + m_r[0] / m_r[1] * (v - lo),
        np.where(v > hi, hi + m_r[2] / m_r[1] * (v - hi), v),
    )
    np.testing.assert_allclose(u, LAWS.scheduling_input(v, rho), rtol=1e-14, atol=1e-16)
    assert json.loads(str(d["provenance"][0]))["note"] == "test"


def test_json_round_trip_and_lti(tmp_path) -> None:
    m = LTIModel(
        alpha=ALPHA[:, :1],
        beta=BETA[:, :1],
        offset=1.0,
        fs=500.0,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )
    path = export_lpv(m, tmp_path / "lti.json", format="json", rho_grid=[0.0, 0.5])
    d = decode_value(json.loads(path.read_text()))
    assert d["model_kind"] == "lti" and d["gamma_m"].shape == (0, 0) and np.isnan(d["eta"])
    A, C = _rebuild(d["A_poly"], d["C_poly"], 0.3)
    ss = state_space(m, 0.3)
    np.testing.assert_array_equal(A, ss.A)
    np.testing.assert_array_equal(C, ss.C)
    assert d["A_grid"].shape == (3, 3, 2)
    np.testing.assert_array_equal(d["rho_grid"], [0.0, 0.5])


def test_refuses_overwrite_and_bad_input(tmp_path) -> None:
    m = _model()
    p = export_lpv(m, tmp_path / "a.mat")
    with pytest.raises(OutputExistsError):
        export_lpv(m, p)
    export_lpv(m, p, force=True)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.mat"]
    with pytest.raises(DataValidationError, match="format"):
        export_lpv(m, tmp_path / "b.x", format="csv")  # type: ignore[arg-type]
    with pytest.raises(DataValidationError, match="kind 'bingham'"):
        lpv_export_data(BinghamModel(fc=(1.0,), c0=(1.0,), input_range=(0.0, 1.0)))
    with pytest.raises(DataValidationError, match="rho_grid"):
        lpv_export_data(m, rho_grid=[np.nan])
