"""The virtual rig: determinism, signal path, variation, validation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, OutOfRangeError
from mrdamper.metrics import esr
from mrdamper.rig import ReplicateVariation, SensorSuite, VirtualRig
from mrdamper.signals import aprbs, road_profile

FS = 1000.0


@pytest.fixture()
def commands() -> tuple[np.ndarray, np.ndarray]:
    x = road_profile(FS, 10.0, seed=1, max_frequency=5.0)
    i = aprbs(FS, 10.0, low=0.0, high=1.0, min_hold=0.2, seed=2)
    return x, i


def test_same_seed_same_bytes_other_seed_other_noise(damper, commands) -> None:
    rig = VirtualRig(damper=damper)
    a = rig.run(*commands, seed=5, name="a")
    b = rig.run(*commands, seed=5, name="a")
    c = rig.run(*commands, seed=6, name="a")
    for ch in ("t", "x", "v", "i", "F"):
        assert getattr(a, ch).tobytes() == getattr(b, ch).tobytes()
    assert a.F.tobytes() != c.F.tobytes() and a.x.tobytes() != c.x.tobytes()
    assert a.metadata["seed"] == 5 and a.metadata["source"] == "virtual rig"
    assert a.metadata["damper"] == "test_tanh"
    assert a.fs == FS and a.n == commands[0].size


def test_ideal_rig_force_is_the_damper_on_the_true_motion(damper, commands) -> None:
    rig = VirtualRig(
        damper=damper, sensors=SensorSuite.ideal(), variation=ReplicateVariation.none()
    )
    rec = rig.run(*commands, seed=0)
    x_true, v_true = rig.actuator.track(commands[0], FS)
    i_true = rig.driver.drive(commands[1], FS)
    np.testing.assert_array_equal(rec.x, x_true)
    np.testing.assert_array_equal(rec.i, i_true)
    plant = Experiment(t=rec.t, x=x_true, v=v_true, F=0 * x_true, i=i_true)
    np.testing.assert_array_equal(rec.F, damper.predict(plant))
    # velocity from the (noise-free) LVDT through the zero-phase filter matches the true velocity
    inner = slice(200, -200)
    assert np.max(np.abs(rec.v[inner] - v_true[inner])) < 0.01 * np.max(np.abs(v_true))


def test_default_rig_record_is_close_to_but_not_the_model(damper, commands) -> None:
    rec = VirtualRig(damper=damper).run(*commands, seed=3)
    # noise, quantisation, velocity estimate and the drawn drift keep the record near the model
    e = esr(rec.F, damper.with_range_policy("clip").predict(rec))
    assert 1e-6 < e < 0.02
    assert np.std(rec.v) == pytest.approx(np.std(np.gradient(commands[0], 1 / FS)), rel=0.1)


def test_replicates_differ_by_drawn_variation(damper, commands) -> None:
    rig = VirtualRig(
        damper=damper,
        sensors=SensorSuite.ideal(),
        variation=ReplicateVariation(gain_std=0.05, drift_std=0.0, offset_std=0.0),
    )
    base = VirtualRig(
        damper=damper, sensors=SensorSuite.ideal(), variation=ReplicateVariation.none()
    )
    F0 = base.run(*commands, seed=0).F
    gains = []
    for seed in range(8):
        rec = rig.run(*commands, seed=seed)
        g = rec.metadata["force_gain"]
        np.testing.assert_allclose(rec.F, (1 + g) * F0, rtol=1e-12, atol=1e-9)
        gains.append(g)
    assert 0.01 < np.std(gains) < 0.15


def test_parameter_drift_perturbs_named_parameters(damper, commands) -> None:
    var = ReplicateVariation(gain_std=0, drift_std=0, offset_std=0, parameter_std={"fy1": 0.1})
    drawn = var.draw(damper, np.random.default_rng(0))
    assert drawn.damper.fy1 == pytest.approx(damper.fy1 * (1 + drawn.parameters["fy1"]))
    assert drawn.damper.c0 == damper.c0
    rec = VirtualRig(damper=damper, variation=var).run(*commands, seed=1)
    assert "drift_fy1" in rec.metadata
    with pytest.raises(DataValidationError, match="parameter_std"):
        ReplicateVariation(parameter_std={"nope": 0.1}).draw(damper, np.random.default_rng(0))


def test_voltage_driven_damper_records_voltage(damper, commands) -> None:
    from dataclasses import replace

    vdamper = replace(damper, input="voltage", input_range=(0.0, 2.0))
    rig = VirtualRig(damper=vdamper)
    rec = rig.run(commands[0], 2 * commands[1], seed=0)
    assert rec.i is None and rec.voltage is not None
    np.testing.assert_allclose(rec.voltage, rig.driver.drive(2 * commands[1], FS), atol=0.01)


def test_validation(damper, commands) -> None:
    rig = VirtualRig(damper=damper)
    x, i = commands
    with pytest.raises(DataValidationError, match="i_command"):
        rig.run(x, i[:-1], seed=0)
    with pytest.raises(DataValidationError, match="x_command"):
        rig.run(x * 10, i, seed=0)
    with pytest.raises(DataValidationError, match="x_command"):
        rig.run(np.where(np.arange(x.size) == 7, np.nan, x), i, seed=0)
    with pytest.raises(DataValidationError, match="seed"):
        rig.run(x, i, seed=None)  # type: ignore[arg-type]
    with pytest.raises(DataValidationError, match="damper"):
        VirtualRig(damper="spencer")  # type: ignore[arg-type]
    # the damper's range policy applies to currents it was not identified on
    with pytest.raises(OutOfRangeError):
        rig.run(x, 2 * i, seed=0)
    with pytest.raises(DataValidationError, match="F"):  # load-cell overload is reported
        VirtualRig(damper=damper.__class__(c0=1e6, input_range=(0.0, 1.0))).run(x, i, seed=0)


def test_velocity_is_what_the_measured_data_pipeline_computes(damper, commands) -> None:
    from mrdamper.data.preprocessing import velocity_from_displacement

    rec = VirtualRig(damper=damper).run(*commands, seed=4)
    again = velocity_from_displacement(rec, cutoff=rec.metadata["velocity_cutoff"])
    np.testing.assert_allclose(rec.v, again.v, rtol=0, atol=1e-12)
    with pytest.raises(DataValidationError, match="velocity_cutoff"):
        VirtualRig(damper=damper, fs=80.0)


def test_non_finite_damper_force_is_reported(damper, commands) -> None:
    from dataclasses import dataclass

    from mrdamper.errors import SimulationDivergedError

    @dataclass(frozen=True, kw_only=True)
    class Exploding(type(damper)):  # type: ignore[misc]
        def predict(self, experiment):  # type: ignore[no-untyped-def]
            F = super().predict(experiment)
            F[500:] = np.inf
            return F

    with pytest.raises(SimulationDivergedError) as info:
        VirtualRig(damper=Exploding(input_range=(0.0, 1.0))).run(*commands, seed=0)
    assert info.value.sample == 500


# the damper fixture is an immutable value, so sharing it across examples is safe
@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(seed=st.integers(0, 2**40), fmax=st.floats(1.0, 8.0), high=st.floats(0.1, 1.0))
def test_any_seed_gives_a_valid_in_stroke_record(
    damper, seed: int, fmax: float, high: float
) -> None:
    x = road_profile(FS, 3.0, seed=seed, max_frequency=fmax)
    i = aprbs(FS, 3.0, low=0.0, high=high, min_hold=0.1, seed=seed + 1)
    rec = VirtualRig(damper=damper).run(x, i, seed=seed)
    assert np.max(np.abs(rec.x)) <= 0.02 + 1e-4
    assert np.all(np.isfinite(rec.F)) and rec.i.min() >= 0.0
