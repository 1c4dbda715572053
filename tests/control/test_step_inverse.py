"""The per-sample inverse of the tanh, Bouc-Wen, Dahl and LuGre models (closed form through their
step): on a record a model simulated itself, the exact inverse gives back the input and the force
where the force depends on the input; the regularised one runs with its defaults; the refusals."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mrdamper.control import inverse_current
from mrdamper.errors import DataValidationError
from mrdamper.models import model_class
from mrdamper.models.protocols import InvertibleModel, StepInvertibleModel
from tests.models.hysteresis_cases import record

KINDS = ("tanh", "boucwen", "dahl", "lugre")


def _truth(kind: str, eta: float = 0.0) -> Any:
    from tests.control.test_c_export import _hysteresis_truths

    params = _hysteresis_truths()[kind]
    return model_class(kind)(**params, eta=eta, input="i", input_range=(0.0, 1.0))


@pytest.mark.parametrize("kind", KINDS)
def test_exact_inverse_recovers_the_input_of_a_simulated_record(kind: str) -> None:
    """The record's force is the model's own free run with a stepped current in [0, 1] A; the
    exact inverse returns that current wherever the force's slope in the input is more than 1 %
    of its largest (elsewhere the force barely depends on it), and its free run returns the
    force at every sample (to 1e-9 of its largest; measured: a few 1e-16)."""
    model = _truth(kind)
    assert isinstance(model, StepInvertibleModel) and not isinstance(model, InvertibleModel)
    rec = record(5, duration=1.0)
    F = model.predict(rec)
    res = inverse_current(model, rec, F, method="exact")
    assert res.model_kind == kind and res.i_range == (0.0, 1.0)
    scale = float(np.max(np.abs(F)))
    assert np.max(np.abs(res.F_achieved - F)) < 1e-9 * scale
    assert not res.saturated.any()  # every current of the record is inside the range
    lo = model.with_range_policy("ignore").predict(rec.replace(i=np.zeros(rec.n)))
    hi = model.with_range_policy("ignore").predict(rec.replace(i=np.ones(rec.n)))
    slope = np.abs(hi - lo)  # |dF/di| [N/A] at each sample (affine in i)
    sharp = slope > 0.01 * slope.max()
    assert sharp.mean() > 0.5
    assert np.max(np.abs(res.i - rec.i)[sharp]) < 1e-9  # [A] (measured: a few 1e-16)


@pytest.mark.parametrize("kind", ["dahl", "lugre"])
def test_regularised_inverse_tracks_and_saturates(kind: str) -> None:
    """With its default weight the regularised inverse follows the force closely; ``reg=0`` is
    the exact inverse; a force beyond the largest input saturates at the upper limit, and the
    rate bound holds."""
    model = _truth(kind)
    rec = record(6, duration=1.0)
    F = model.predict(rec)
    res = inverse_current(model, rec, F)
    err = np.sqrt(np.mean(res.error**2)) / np.std(F)
    assert 0.0 < err < 0.2
    exact = inverse_current(model, rec, F, method="exact")
    np.testing.assert_array_equal(inverse_current(model, rec, F, reg=0.0).i, exact.i)
    big = inverse_current(model, rec, 10.0 * F, method="exact")
    moving = np.abs(rec.v) > 0.2 * np.max(np.abs(rec.v))
    assert big.saturated[moving].all() and np.all(big.i[moving] == 1.0)
    slow = inverse_current(model, rec, F, reg=0.0, rate=2.0)
    assert np.max(np.abs(np.diff(slow.i))) <= 2.0 * rec.dt * (1 + 1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_exact_inverse_with_a_drive_lag_recovers_the_command(kind: str) -> None:
    """A lagged model (80 1/s) simulated with a stepped current: the exact inverse solves for the
    lagged input and returns the command through the lag's inverse. Within every level held over
    two intervals, where the force's slope in the input is more than 1 % of its largest at both
    samples, the command is the record's (the model's free run reads the command linearly
    interpolated; the inverse holds it, so across a step they differ by that half sample)."""
    model = _truth(kind, eta=80.0)
    rec = record(5, duration=1.0)
    F = model.predict(rec)
    res = inverse_current(model, rec, F, method="exact")
    assert not res.saturated.any()
    assert np.all((res.i >= 0.0) & (res.i <= 1.0))
    lo = model.with_range_policy("ignore").predict(rec.replace(i=np.zeros(rec.n)))
    hi = model.with_range_policy("ignore").predict(rec.replace(i=np.ones(rec.n)))
    sharp = np.abs(hi - lo) > 0.01 * np.max(np.abs(hi - lo))
    held = np.zeros(rec.n, dtype=bool)
    held[1:-1] = (rec.i[:-2] == rec.i[1:-1]) & (rec.i[1:-1] == rec.i[2:])  # level held k-1..k+1
    check = held & sharp & np.roll(sharp, -1) & np.roll(sharp, 1)
    assert check.mean() > 0.5
    # [A]; measured 1e-7: the model's lag is RK4 sub-steps, the lag's inverse the exponential
    assert np.max(np.abs(res.i - rec.i)[check]) < 1e-6
    assert np.sqrt(np.mean(res.error**2)) < 0.02 * np.std(F)  # measured 0.2-0.24 %
    regularised = inverse_current(model, rec, F)  # the defaults run with the lag too
    assert np.sqrt(np.mean(regularised.error**2)) < 0.2 * np.std(F)


def test_refusals() -> None:
    rec = record(7, duration=0.2)
    from mrdamper.models.spencer import spencer1997

    with pytest.raises(DataValidationError, match="through its step: 'regularised' only"):
        inverse_current(spencer1997(), rec, np.zeros(rec.n), method="exact")


def test_quarter_car_with_a_hysteresis_model_as_controller() -> None:
    """A model without a drive lag (``eta = 0``) drives the quarter car with the passive and the
    semi-active controllers (its step stands in for the controller's model; the passive input is
    the constant one, not passed through a lag that the model does not have)."""
    from mrdamper.control.loop.closed_loop import simulate_closed_loop
    from mrdamper.control.loop.quarter_car import iso_road

    model = _truth("dahl")
    road = iso_road("C", duration=1.5)
    soft = simulate_closed_loop(model, road, "soft")
    assert np.all(soft.i == model.input_range[0]) and np.isfinite(soft.metrics()["rms_acc"])
    sky = simulate_closed_loop(model, road, "skyhook")
    assert sky.i.max() > sky.i.min()  # the controller moves the input
