"""FMI 2.0 FMU export: fmpy's validation, the FMU driven by fmpy against Python's step and
``predict`` on synthetic and measured records, a closed loop, and the one-line refusals
(skipped without gcc or fmpy; the measured records without the shared data)."""

from __future__ import annotations

import dataclasses
import shutil
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper.control.export.fmu import export_fmu, fmu_sources, run_fmu
from mrdamper.errors import DataValidationError, MrDamperError, OutputExistsError
from mrdamper.models.spencer import spencer1997
from mrdamper.models.step import run_step
from tests.control.test_c_export import (
    _rel,
    _sub_sample_record,
    spencer_predicting_like_its_step,
)

fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (optional extra [fmu])")
pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found")


def _validated(model: Any, path: Path, **kw: Any) -> Path:
    from fmpy.validation import validate_fmu

    fmu = export_fmu(model, path, **kw)
    assert validate_fmu(str(fmu)) == []
    return fmu


def test_spencer_fmu_matches_step_and_predict(tmp_path: Path) -> None:
    model, dt = spencer1997(), 1e-3
    rec = _sub_sample_record(3000, dt, "voltage")
    fmu = _validated(model, tmp_path / "damper.fmu", name="damper", dt=dt)
    F = run_fmu(fmu, rec.x, rec.v, rec.voltage)[:, 0]
    F_step, status, _ = run_step(model.step(dt=dt), rec.x, rec.v, rec.voltage, dt)
    assert status == 0
    assert _rel(F, F_step) < 1e-9
    assert _rel(F, spencer_predicting_like_its_step(model, dt).predict(rec)) < 1e-9
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
        desc = z.read("modelDescription.xml").decode()
    assert {"binaries/linux64/damper.so", "sources/damper.c", "sources/damper_fmu.c"} <= names
    assert 'canHandleVariableCommunicationStepSize="false"' in desc
    assert 'kind="spencer"' in desc and 'inputMax="2.25"' in desc and 'stepSize="0.001"' in desc
    md = fmpy.read_model_description(str(fmu))
    assert [(v.name, v.causality, v.unit) for v in md.modelVariables] == [
        ("x", "input", "m"),
        ("v", "input", "m/s"),
        ("voltage", "input", "V"),
        ("F", "output", "N"),
    ]


@pytest.mark.slow
def test_fmu_on_quiroz_records(
    tmp_path: Path, quiroz_models: dict[str, Any], quiroz_records: list[Any]
) -> None:
    """LPV and SP-1 fitted on the Quiroz records, and a published Spencer model in current units,
    driven by a measured record; the SP-1 inverse FMU against the Python inverse."""
    from mrdamper.control import inverse_current

    rec = next(e for e in quiroz_records if e.name == "sine_25mm_0.5Hz_0.5A")  # 200 Hz
    for kind in ("lpv", "sp1"):
        model = quiroz_models[kind]
        fmu = _validated(model, tmp_path / f"{kind}.fmu", name=kind, dt=rec.dt)
        assert _rel(run_fmu(fmu, rec.x, rec.v, rec.i)[:, 0], model.predict(rec)) < 1e-9
    spencer = dataclasses.replace(spencer1997(), input="i", input_range=(0.0, 2.25))
    fmu = _validated(spencer, tmp_path / "sp.fmu", name="sp", dt=rec.dt)
    F = run_fmu(fmu, rec.x, rec.v, rec.i)[:, 0]
    assert _rel(F, spencer_predicting_like_its_step(spencer, rec.dt).predict(rec)) < 1e-9
    sp1 = quiroz_models["sp1"]
    inv = _validated(sp1, tmp_path / "inv.fmu", name="inv", dt=rec.dt, inverse=True, reg=800.0)
    out = run_fmu(inv, rec.x, rec.v, rec.F)
    res = inverse_current(sp1, rec, rec.F, reg=800.0, n_grid=16)  # the export's default grid
    assert _rel(out[:, 0], res.rho) < 1e-9
    assert _rel(out[:, 1], res.F_achieved) < 1e-9


def test_fmu_as_the_damper_of_a_closed_loop(tmp_path: Path) -> None:
    """A mass on a spring and the damper over a bump, stepped sample by sample: the FMU as the
    damper gives the trajectory of the Python step as the damper."""
    from fmpy.fmi2 import FMU2Slave

    model, dt, n = spencer1997(), 1e-3, 1500
    fmu = export_fmu(model, tmp_path / "d.fmu", name="d", dt=dt)
    md = fmpy.read_model_description(str(fmu))
    slave = FMU2Slave(
        guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)), modelIdentifier="d", instanceName="d"
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    step = model.step(dt=dt)
    mass, k, e = 250.0, 2.0e4, 1.0  # [kg], [N/m], [V]
    road = 0.02 * (np.arange(n) * dt > 0.1)

    def plant(x: float, v: float, F: float, r: float) -> tuple[float, float]:
        a = (-k * (x - r) - F) / mass  # semi-implicit Euler
        return x + dt * (v + dt * a), v + dt * a

    traj = {}
    for via in ("fmu", "python"):
        x, v, out = 0.0, 0.0, np.zeros(n)
        state = step.initial_state(x, v, e)
        for j in range(n):
            if via == "fmu":
                slave.setReal([0, 1, 2], [x, v, e])
                F = slave.getReal([3])[0]
                slave.doStep(currentCommunicationPoint=j * dt, communicationStepSize=dt)
            else:
                F = step.force(step.form, state, x, v, e)
            x1, v1 = plant(x, v, F, road[j])
            if via == "python":
                assert step.advance(step.form, state, x, v, e, x1, v1, e, dt) == 0
            out[j], x, v = F, x1, v1
        traj[via] = out
    slave.terminate()
    slave.freeInstance()
    assert np.max(np.abs(traj["fmu"])) > 100.0  # the bump moves the damper
    assert _rel(traj["fmu"], traj["python"]) < 1e-9


def test_fmu_refusals_write_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from mrdamper.models.bingham import BinghamModel
    from mrdamper.models.phenomenological import P15Model

    out = tmp_path / "d.fmu"
    toy = dataclasses.make_dataclass("Toy", [("kind", str)])("toy")
    with pytest.raises(DataValidationError, match="kind 'toy' has no C step"):
        export_fmu(toy, out)
    with pytest.raises(DataValidationError, match="records no sample time it was fitted at"):
        export_fmu(P15Model(input_range=(0.0, 1.0)), out)
    with pytest.raises(DataValidationError, match="inverse: the C export of a spencer"):
        export_fmu(spencer1997(), out, dt=1e-3, inverse=True)
    with pytest.raises(DataValidationError, match="records no sample time it was fitted at"):
        export_fmu(spencer1997(), out)
    bing = BinghamModel(fc=(100.0, 500.0), c0=(1000.0, 2000.0), input_range=(0.0, 1.0))
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(MrDamperError, match="gcc: not found"):
        export_fmu(bing, out, dt=1e-3)
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []
    export_fmu(bing, out, dt=1e-3)
    with pytest.raises(OutputExistsError):
        export_fmu(bing, out, dt=1e-3)
    export_fmu(bing, out, dt=1e-3, force=True)
    assert [p.name for p in tmp_path.iterdir()] == ["d.fmu"]
    files, step = fmu_sources(bing, "b", dt=2e-3)
    assert step == 2e-3 and "fmi2DoStep" in files["sources/b_fmu.c"]


def test_fmu_refuses_another_communication_step(tmp_path: Path) -> None:
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    fmu = export_fmu(spencer1997(), tmp_path / "d.fmu", name="d", dt=1e-3)
    md = fmpy.read_model_description(str(fmu))
    slave = FMU2Slave(
        guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)), modelIdentifier="d", instanceName="d"
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    with pytest.raises(FMICallException):
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=2e-3)
    slave.freeInstance()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["spencer", "narx", "lugre"])
def test_quarter_car_with_the_fmu_as_plant(
    tmp_path: Path, kind: str, kind_models: dict[str, Any]
) -> None:
    """The quarter car (an SP-1 skyhook controller, ISO class C) with the FMU as the damper
    (``plant=damper.fmu``: the FMU's binary stepped from the compiled loop) gives the metrics of
    the same loop with the model itself as the damper, to 1e-9 (continuous-time plants, one of
    them a hysteresis family, and a discrete-time plant; each family's loop compiles once, some
    20 s)."""
    from mrdamper.control.loop.closed_loop import simulate_closed_loop
    from mrdamper.control.loop.quarter_car import iso_road

    plant = kind_models[kind]
    fmu = export_fmu(plant, tmp_path / "d.fmu", name="d", dt=None if kind == "narx" else 1e-3)
    road = iso_road("C", duration=1.0)
    ctrl = kind_models["sp1"]
    a = simulate_closed_loop(ctrl, road, "skyhook", plant=plant).metrics()
    b = simulate_closed_loop(ctrl, road, "skyhook", plant=str(fmu)).metrics()
    assert a.keys() == b.keys()
    for key, value in a.items():
        if isinstance(value, float) and value != 0.0:
            assert abs(b[key] - value) <= 1e-9 * abs(value), key


def test_fmu_plant_refusals(tmp_path: Path, kind_models: dict[str, Any]) -> None:
    from mrdamper.control.export.fmu_plant import FMUPlant
    from mrdamper.control.loop.closed_loop import resolve_plant

    sp1 = kind_models["sp1"]
    inv = export_fmu(sp1, tmp_path / "inv.fmu", name="inv", dt=1e-3, inverse=True)
    with pytest.raises(DataValidationError, match="the FMU of an inverse"):
        resolve_plant(str(inv))
    with pytest.raises(DataValidationError, match="no such FMU"):
        FMUPlant(tmp_path / "none.fmu")
    bad = tmp_path / "bad.fmu"
    bad.write_text("not a zip")
    with pytest.raises(DataValidationError, match="not a readable FMU"):
        FMUPlant(bad)
    plant = resolve_plant(str(export_fmu(sp1, tmp_path / "d.fmu", name="d", dt=1e-3)))
    assert plant.kind == "sp1" and plant.input == sp1.input and plant.step().dt is None


def test_inverse_fmu_of_a_hysteresis_model(tmp_path: Path) -> None:
    """The inverse FMU of a Dahl model (closed form per sample through its step) driven by fmpy
    against ``inverse_current``; with a drive lag its first output is the lagged input."""
    from mrdamper.control import inverse_current
    from mrdamper.models.dahl import DahlModel
    from tests.models.hysteresis_cases import record

    rec = record(5, duration=0.5)
    model = DahlModel(
        c0a=900.0, c0b=5000.0, k0=400.0, Fda=150.0, Fdb=800.0, sigma=3000.0,
        input_range=(0.0, 1.0),
    )  # fmt: skip
    model = dataclasses.replace(model, substeps=model.substeps_for(rec))
    F = model.predict(rec)
    fmu = _validated(model, tmp_path / "inv.fmu", name="inv", dt=rec.dt, inverse=True, reg=200.0)
    out = run_fmu(fmu, rec.x, rec.v, F)
    res = inverse_current(model, rec, F, reg=200.0)
    assert _rel(out[:, 0], res.i) < 1e-9
    assert _rel(out[:, 1], res.F_achieved) < 1e-9
    lagged = dataclasses.replace(model, eta=50.0)
    F = lagged.predict(rec)
    fmu = _validated(lagged, tmp_path / "lag.fmu", name="lag", dt=rec.dt, inverse=True, reg=200.0)
    out = run_fmu(fmu, rec.x, rec.v, F)
    res = inverse_current(lagged, rec, F, reg=200.0)
    assert _rel(out[:, 0], res.rho) < 1e-9
