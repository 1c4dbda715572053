"""The rig test plan: the commands of the DoE and its extension for a physical rig, checked
against the rig's limits; and the extension's default first model (fitted on Table II)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

import mrdamper.cli.rig as cli_rig
from mrdamper.cli.main import main
from mrdamper.data import Experiment
from mrdamper.models.bingham import BinghamModel
from mrdamper.rig.doe import table_ii
from mrdamper.rig.doe_control import STROKE_TEST, stroke_test
from mrdamper.rig.plan import PLAN_NAME, PLAN_SOURCE, PlanRig, RigLimits, plan_limits
from mrdamper.rig.virtual_rig import VirtualRig


def _soft(damper):  # type: ignore[no-untyped-def]
    # a softer test damper: the motions are not scaled down for the load cell
    return dataclasses.replace(damper, c0=800.0, c1=600.0)


class _Recording(VirtualRig):
    """The virtual rig, remembering the commands of every run."""

    def run(self, x_command: Any, i_command: Any, **kw: Any) -> Experiment:
        self.__dict__.setdefault("commands", []).append((kw["name"], x_command, i_command))
        return super().run(x_command, i_command, **kw)


def test_the_plan_is_what_the_virtual_rig_is_commanded(damper) -> None:  # type: ignore[no-untyped-def]
    damper = _soft(damper)
    rig = _Recording(damper=damper, fs=200.0)
    table_ii(seed=3, scale=0.07, rig=rig, experiments=[2, 6])
    stroke_test(rig, current_range=(0.0, 1.0), seeds=[1] * len(STROKE_TEST), scale=0.1)
    plan_rig = PlanRig(damper=damper, fs=200.0)
    plan = [
        *table_ii(seed=3, scale=0.07, rig=plan_rig, experiments=[2, 6]),
        *stroke_test(plan_rig, current_range=(0.0, 1.0), seeds=[1] * len(STROKE_TEST), scale=0.1),
    ]
    commands = rig.__dict__["commands"]
    assert [r.name for r in plan] == [name for name, _, _ in commands]
    for rec, (_, x, i) in zip(plan, commands, strict=True):
        np.testing.assert_array_equal(rec.x, x)
        np.testing.assert_array_equal(rec.i, i)
        assert rec.metadata["source"] == PLAN_SOURCE
    # F is the damper estimate's force for the command motion
    rec = plan[0]
    np.testing.assert_allclose(rec.F, damper.predict(rec), rtol=1e-12)


def _record(name: str, x: np.ndarray, i: np.ndarray, force: float) -> Experiment:
    t = np.arange(x.size) / 100.0
    return Experiment(t=t, x=x, v=np.gradient(x) * 100.0, i=i, F=np.full(x.size, force), name=name)


def test_plan_limits_name_every_limit_a_record_exceeds() -> None:
    limits = RigLimits(stroke=0.04, velocity=0.5, electrical=(0.0, 1.0), load_cell=5000.0)
    t = np.arange(200) / 100.0
    inside = _record("in", 0.01 * np.sin(2 * np.pi * t), np.full(200, 0.5), 1000.0)
    outside = _record("out", 0.03 * np.sin(2 * np.pi * 5 * t), np.full(200, 1.2), 6000.0)
    table = plan_limits([inside, outside], limits).set_index("record")
    assert table.loc["in", "exceeds"] == ""
    assert table.loc["out", "exceeds"] == "stroke, velocity, current, load cell"
    assert table.loc["out", "peak travel [mm]"] == pytest.approx(30.0, rel=1e-3)
    assert table.loc["in", "stroke limit [mm]"] == 20.0
    # no velocity limit: reported, not checked
    free = dataclasses.replace(limits, velocity=None)
    assert plan_limits([outside], free)["exceeds"][0] == "stroke, current, load cell"


@pytest.mark.slow
def test_rig_doe_plan_only_on_the_command_line(
    monkeypatch: pytest.MonkeyPatch, damper, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(cli_rig, "_damper", lambda spec: _soft(damper))
    first = tmp_path / "first.json"
    BinghamModel(fc=(80.0, 980.0), c0=(800.0, 1400.0), input_range=(0.0, 1.0)).save(first)
    out = tmp_path / "plan"
    args = ["rig", "doe", "--out", str(out), "--scale", "0.07", "--fs", "200", "--plan-only"]
    # the extension's loop motions depend on the damper: a plan needs the user's model of it
    with pytest.raises(SystemExit):
        main([*args, "--extension", "control"])
    err = capsys.readouterr().err
    assert "--loop-model" in err and len(err.strip().splitlines()) == 1
    main([*args, "--extension", "control", "--loop-model", str(first), "--max-velocity", "0.3"])
    captured = capsys.readouterr()
    assert "100 records" in captured.out and "planned" in captured.out
    table = pd.read_csv(out / PLAN_NAME, keep_default_na=False)
    assert len(table) == 100 and table["record"].iloc[-1] == "stroke09"
    assert (table["peak travel [mm]"] <= table["stroke limit [mm]"]).all()
    fast = table[table["peak velocity [m/s]"] > 0.3]
    assert len(fast) > 0 and (fast["exceeds"] == "velocity").all()
    # one warning line per limit, naming how many records exceed it
    warnings = [line for line in captured.err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and f"{len(fast)} of 100 records" in warnings[0]
    commands = pd.read_csv(out / "ctrl01.csv")
    assert list(commands.columns) == ["t [s]", "x [m]", "i [A]"] and len(commands) > 100
    # --max-velocity has no meaning without a plan
    with pytest.raises(SystemExit):
        main(["rig", "doe", "--out", str(tmp_path / "x"), "--max-velocity", "1"])
    err = capsys.readouterr().err
    assert "--max-velocity" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_the_extension_loop_model_defaults_to_a_fit_on_table_ii(
    monkeypatch: pytest.MonkeyPatch, damper, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(cli_rig, "_damper", lambda spec: _soft(damper))
    out = tmp_path / "doe"
    args = ["rig", "doe", "--out", str(out), "--scale", "0.07", "--fs", "200"]
    main([*args, "--extension", "control", "--loop-model", "bingham"])
    out_text = capsys.readouterr().out
    assert "extension loops run with bingham fitted on the 61 Table II records" in out_text
    manifest = pd.read_csv(out / "manifest.csv")
    assert manifest["displacement"].str.contains("bingham model").sum() == 30
    with pytest.raises(SystemExit):
        main(
            [
                *args[:3],
                str(tmp_path / "y"),
                *args[4:],
                "--extension",
                "control",
                "--loop-model",
                "nonsense",
            ]
        )
    err = capsys.readouterr().err
    assert "--loop-model" in err and "'rig'" in err and len(err.strip().splitlines()) == 1


def test_the_rig_of_rig_doe_takes_the_stroke_and_the_damper_estimate(damper) -> None:  # type: ignore[no-untyped-def]
    first = BinghamModel(fc=(80.0, 980.0), c0=(800.0, 1400.0), input_range=(0.0, 1.0))
    plan = cli_rig._rig(None, 200.0, 0.03, True, first)
    assert isinstance(plan, PlanRig) and plan.actuator.stroke == 0.03 and plan.model is first
    assert RigLimits.of(plan).stroke == 0.03
    virtual = cli_rig._rig(None, 200.0, 0.05, False, first)
    assert type(virtual) is VirtualRig and virtual.actuator.stroke == 0.05
    assert virtual.model is not first  # the virtual rig keeps its reference damper
