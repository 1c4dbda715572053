"""Regularised inverse: round trip on a known model, rate bound, options, and the targets on the
real records (every unfiltered Quiroz record, LPV and SP-1; the Dyke record with its voltage)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mrdamper.control import inverse_current
from mrdamper.control.inverse.inverse_check import check_inverse, check_inverse_frame
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError
from mrdamper.models.lpv import LPVModel
from mrdamper.models.semiphenomenological import SP3Model

FS = 1000.0
ALPHA = np.array([[-1.2, 0.10, -0.02], [0.40, -0.05, 0.01]])
BETA = np.array([[300.0, 500.0, -40.0], [-200.0, -300.0, 30.0]])


def _motion(level: float = 1.3, n: int = 3000) -> Experiment:
    t = np.arange(n) / FS
    x = -0.01 * np.cos(2 * np.pi * 3 * t)
    v = 0.01 * 2 * np.pi * 3 * np.sin(2 * np.pi * 3 * t)
    return Experiment(t=t, x=x, v=v, F=0 * t, i=np.full(n, level), name="motion")


@pytest.mark.parametrize("which", ["lpv", "sp3"])
def test_constant_current_recovered_from_the_models_own_force(which: str) -> None:
    if which == "lpv":
        m: Any = LPVModel(
            alpha=ALPHA,
            beta=BETA,
            offset=5.0,
            fs=FS,
            input_signal="v",
            rho_range=(0.0, 2.0),
            input_range=(0.0, 2.0),
        )
    else:
        m = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), input_range=(0.0, 2.0))
    e = _motion()
    F = m.predict(e)
    res = inverse_current(m, e, F)
    moving = np.abs(e.v) > 0.2 * np.abs(e.v).max()
    # starting from the lowest input, the regularised inverse reaches 1.3 A within the first cycle
    # and a half (the default weight at 1 kHz is about 1.6 x the force authority)
    late = moving & (e.t > 0.5)
    assert np.max(np.abs(res.i[late] - 1.3)) < 1e-6
    assert np.all((res.i >= 0.0) & (res.i <= 2.0))


def test_rate_bound_and_weight() -> None:
    m = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), input_range=(0.0, 2.0))
    e = _motion()
    F = m.predict(e)
    res = inverse_current(m, e, F, rate=5.0)  # [A/s]
    assert np.max(np.abs(np.diff(res.i))) <= 5.0 / FS + 1e-12
    assert res.i[40] == pytest.approx(
        res.i[0] + 40 * 5.0 / FS, rel=1e-9
    )  # still ramping (first sample free)
    heavy = inverse_current(m, e, F, reg=1e6)
    light = inverse_current(m, e, F, reg=0.0)
    assert np.sqrt(np.mean(light.error**2)) < 1e-6 * np.max(np.abs(F))
    assert np.mean(heavy.i) < np.mean(light.i)  # a heavy weight holds the input near its start
    for bad in ({"reg": -1.0}, {"rate": 0.0}, {"method": "newton"}):
        with pytest.raises(DataValidationError, match=next(iter(bad))):
            inverse_current(m, e, F, **bad)  # type: ignore[arg-type]


@pytest.mark.slow  # accuracy check on the 30 Quiroz records
def test_quiroz_targets_every_record(
    quiroz_models: dict[str, Any], quiroz_records: list[Any]
) -> None:
    for kind, model in quiroz_models.items():
        frame = check_inverse_frame([check_inverse(model, e) for e in quiroz_records])
        assert len(frame) == 30
        bad = frame[(frame.median_input_error > 0.1) | (frame.ssse_ratio > 1.5)]
        assert bad.empty, f"{kind}: {bad.to_string()}"


@pytest.mark.slow  # accuracy check on the Dyke record
@pytest.mark.parametrize("kind", ["sp1", "lpv"])
def test_dyke_targets(dyke_models: dict[str, Any], dyke_record: Any, kind: str) -> None:
    # one inversion checked against both targets (force and voltage figure)
    check = check_inverse(dyke_models[kind], dyke_record)
    assert check.ssse_ratio <= 1.5, f"force target: SSSE ratio {check.ssse_ratio:.3g}"
    assert check.median_input_error <= 0.1, (
        f"voltage target: median input error {check.median_input_error:.3g}"
    )


def test_lead_horizon_setting() -> None:
    from mrdamper.control.inverse.current import horizon_samples

    assert horizon_samples(None, 1e-3) == 1
    assert horizon_samples(250.0, 1.0 / 3004.8) == 12  # one lag time constant
    assert horizon_samples(250.0, 1e-3, 0.0) == 1
    m = LPVModel(
        alpha=ALPHA,
        beta=BETA,
        offset=5.0,
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 2.0),
        input_range=(0.0, 2.0),
        eta=60.0,
    )
    e = _motion()
    t = np.asarray(e.t)
    e = e.replace(i=np.where((t > 0.5) & (t < 1.8), 1.6, 0.4))
    F = m.predict(e)
    lead = inverse_current(m, e, F)
    plain = inverse_current(m, e, F, horizon=0.0)
    assert not np.array_equal(lead.rho, plain.rho)
    for r in (lead, plain):
        assert np.all((r.i >= 0.0) & (r.i <= 2.0))
        step = np.abs(np.diff(r.rho))
        assert np.all(step <= (1.0 - np.exp(-60.0 / FS)) * 2.0 + 1e-12)  # rho moves through the lag
    with pytest.raises(DataValidationError, match="horizon"):
        inverse_current(m, e, F, horizon=-1.0)


def _lagged_sp3(eta: float) -> SP3Model:
    return SP3Model(
        S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0),
        input_range=(0.0, 2.0),
        eta=eta,
        rho_range=(0.0, 2.0),
    )


def test_static_map_with_drive_lag_inverted_through_the_lag() -> None:
    m = _lagged_sp3(40.0)
    e = _motion()
    t = np.asarray(e.t)
    cmd = np.where((t > 0.5) & (t < 1.8), 1.6, 0.4)  # a switching command the lag smooths
    e = e.replace(i=cmd)
    F = m.predict(e)
    assert not np.allclose(F, SP3Model(S=m.S, input_range=(0.0, 2.0)).predict(e))  # the lag matters
    res = inverse_current(m, e, F, reg=0.0)
    moving = np.abs(e.v) > 0.2 * np.abs(e.v).max()
    late = moving & (t > 0.3)
    # the command is recovered (the map sees its lagged value) and the force reproduced
    assert np.median(np.abs(res.i[late] - cmd[late])) < 1e-6
    assert np.sqrt(np.mean(res.error[t > 0.3] ** 2)) < 1e-6 * np.max(np.abs(F))
    # rho moves only as far as the lag lets it in one sample
    e_lag = np.exp(-40.0 / FS)
    step = np.abs(np.diff(res.rho)[1:])
    assert np.all(step <= (1.0 - e_lag) * 2.0 + 1e-12)
    with pytest.raises(DataValidationError, match="method"):
        inverse_current(m, e, F, method="exact")


def test_static_map_drive_lag_round_trip_and_validation(tmp_path: Any) -> None:
    from mrdamper.models.registry import load_model

    m = _lagged_sp3(40.0)
    back = load_model(m.save(tmp_path / "sp3.json"))
    assert back.eta == 40.0 and back.rho_range == (0.0, 2.0)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(DataValidationError, match="eta"):
            _lagged_sp3(bad)
