"""The control-oriented extension of the DoE: fast motions, fast switching, within the stroke,
reproducible, on the command line."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import mrdamper.cli.rig as cli_rig
from mrdamper.cli.main import main
from mrdamper.errors import DataValidationError
from mrdamper.rig.doe import table_ii
from mrdamper.rig.doe_control import CONTROL_EXTENSION, control_extension


def _soft(damper):  # type: ignore[no-untyped-def]
    # a softer test damper: the motions are not scaled down for the load cell
    return dataclasses.replace(damper, c0=800.0, c1=600.0)


def test_extension_moves_fast_switches_fast_and_stays_in_the_stroke(damper) -> None:  # type: ignore[no-untyped-def]
    damper = _soft(damper)
    ext = control_extension(seed=1, scale=0.1, damper=damper)
    doe = table_ii(seed=0, scale=0.07, damper=damper, experiments=[2])
    assert [r.name for r in ext] == [f"ctrl{k:02d}" for k in range(1, len(CONTROL_EXTENSION) + 1)]
    v_ext = max(float(np.max(np.abs(r.v))) for r in ext)
    v_doe = max(float(np.max(np.abs(r.v))) for r in doe)
    assert v_ext > 0.5 and v_ext > 3 * v_doe  # the loop's velocities, not Table II's
    for r in ext:
        assert np.max(np.abs(r.x)) <= 0.02 + 1e-9  # half the default 0.04 m stroke
        # the current switches over the range, often (APRBS, 50 ms holds; 3 s records)
        assert np.ptp(r.i) > 0.5 and np.sum(np.abs(np.diff(r.i)) > 0.05) > 10
        assert np.max(np.abs(r.F)) <= 0.9 * 5000.0 + 50.0  # within the load cell's range
    again = control_extension(seed=1, scale=0.1, damper=damper)
    np.testing.assert_array_equal(ext[0].F, again[0].F)
    other = control_extension(seed=2, scale=0.1, damper=damper)
    assert not np.array_equal(ext[0].x, other[0].x)
    with pytest.raises(DataValidationError, match="scale") as err:
        control_extension(seed=1, scale=0.01, damper=damper)
    assert "\n" not in str(err.value)


def test_rig_doe_extension_control_on_the_command_line(
    monkeypatch: pytest.MonkeyPatch, damper, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(cli_rig, "_damper", lambda spec: _soft(damper))
    out = tmp_path / "doe"
    args = ["rig", "doe", "--out", str(out), "--scale", "0.07", "--fs", "200"]
    main([*args, "--extension", "control"])
    assert "67 records" in capsys.readouterr().out
    names = pd.read_csv(out / "manifest.csv")["name"].tolist()
    assert len(names) == 67 and names[-1] == "ctrl06" and (out / "ctrl01.csv").exists()
    with pytest.raises(SystemExit):
        main([*args[:3], str(tmp_path / "x"), *args[4:], "--extension", "fast"])
    err = capsys.readouterr().err
    assert "--extension" in err and len(err.strip().splitlines()) == 1
