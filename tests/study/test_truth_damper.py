"""Which damper is the truth behind virtual-rig records: the rig names its reference damper in
every record and in the manifest of ``mrdamper rig doe``, and the study's control step uses it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import Experiment
from mrdamper.rig import VirtualRig
from mrdamper.rig.reference import reference_damper, reference_name
from mrdamper.study.control_step import truth_damper


def _record(name: str = "r", **meta: object) -> Experiment:
    t = np.arange(50) / 1000.0
    return Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, i=0 * t, name=name, metadata=meta)


def _rig_record(damper: object) -> Experiment:
    n = 1500
    x = 0.004 * np.sin(2 * np.pi * 2.0 * np.arange(n) / 1000.0)
    lo, hi = damper.input_range  # type: ignore[attr-defined]
    return VirtualRig(damper=damper).run(x, np.full(n, 0.5 * (lo + hi)), seed=3)


def test_the_rig_names_the_reference_damper_in_every_record() -> None:
    default = _rig_record(reference_damper())
    other = _rig_record(reference_damper("spencer1997"))
    assert default.metadata["reference_damper"] == "quiroz2022"
    assert other.metadata["reference_damper"] == "spencer1997"
    assert truth_damper([default]) == "rig"
    assert truth_damper([other]) == "rig:spencer1997"


def test_a_damper_that_is_not_shipped_is_no_known_truth(tmp_path: Path) -> None:
    import dataclasses

    mine = reference_damper("spencer1997")
    mine = dataclasses.replace(mine, provenance={"source": "my calibration"})
    assert reference_name(mine) is None
    rec = _rig_record(mine)
    assert rec.metadata["reference_damper"] == "custom"
    assert truth_damper([rec]) is None  # not assumed to be the default reference damper
    assert truth_damper([rec], plant="my-damper.json") == "my-damper.json"


def test_records_that_disagree_or_name_none() -> None:
    a = _record("a", source="virtual rig", damper="spencer", reference_damper="quiroz2022")
    b = _record("b", source="virtual rig", damper="spencer", reference_damper="spencer1997")
    assert truth_damper([a, b]) is None
    # written before the rig named its damper: the default reference damper is assumed
    old = _record("o", source="virtual rig", damper="spencer")
    assert truth_damper([old]) == "rig"
    assert truth_damper([_record("m", damper="spencer")]) is None  # measured


def test_a_voltage_driven_rig_design_is_studied_on_its_voltage() -> None:
    from mrdamper.rig.doe import table_ii
    from mrdamper.study.default import default_protocol

    data = table_ii(seed=0, scale=0.07, experiments=[6], damper=reference_damper("spencer1997"))
    proto, why = default_protocol(data)
    assert proto.name == "doe" and proto.input == "voltage" and "input 'voltage'" in why
    assert truth_damper(data) == "rig:spencer1997"


def test_a_refused_loop_run_says_why_in_its_rows(monkeypatch: pytest.MonkeyPatch) -> None:
    from mrdamper.control.loop import fidelity
    from mrdamper.models.semiphenomenological import SP1Estimator
    from mrdamper.rig.doe import table_ii
    from mrdamper.study.control_step import ControlSettings, model_in_loop

    data = table_ii(seed=0, scale=0.07, experiments=[1, 6])
    model = SP1Estimator().fit(data)
    real = fidelity.checked_run
    calls = {"n": 0}

    def refuse_the_first(run, **kw):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        if calls["n"] == 1:
            raise fidelity.NotConvergedError("halving still moves a_w by 9 %")
        return real(run, **kw)

    monkeypatch.setattr(fidelity, "checked_run", refuse_the_first)
    settings = ControlSettings(duration=2.0, controllers=("soft",), fronts=False)
    rows, _, _ = model_in_loop("sp1", "sp1", model, "rig", settings)
    assert rows and all(np.isnan(r["predicted"]) for r in rows)
    why = "predicted run refused: halving still moves a_w by 9 %"
    assert {r.get("reason") for r in rows} == {why}
    assert all(np.isfinite(r["achieved"]) for r in rows if r["metric"] != "rms_tracking")
