"""The control-oriented extension of the DoE: the loop's motions and currents replayed on the rig,
fast motions, fast switching, within the stroke, reproducible, on the command line."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import mrdamper.cli.rig as cli_rig
from mrdamper.cli.main import main
from mrdamper.control.loop.doe_extension import control_extension
from mrdamper.data import ExperimentSet, read_records
from mrdamper.errors import DataValidationError
from mrdamper.models.bingham import BinghamModel
from mrdamper.rig.doe import table_ii
from mrdamper.rig.doe_control import CONTROL_EXTENSION, STROKE_TEST


def _soft(damper):  # type: ignore[no-untyped-def]
    # a softer test damper: the motions are not scaled down for the load cell
    return dataclasses.replace(damper, c0=800.0, c1=600.0)


def _first_model() -> BinghamModel:
    # a first model of the soft test damper, as a Table II fit would give
    return BinghamModel(fc=(80.0, 980.0), c0=(800.0, 1400.0), input_range=(0.0, 1.0))


def test_extension_moves_fast_switches_fast_and_stays_in_the_stroke(damper) -> None:  # type: ignore[no-untyped-def]
    damper = _soft(damper)
    ext = control_extension(seed=1, scale=0.1, damper=damper, model=_first_model())
    doe = table_ii(seed=0, scale=0.07, damper=damper, experiments=[2])
    n = 2 * len(CONTROL_EXTENSION)
    assert [r.name for r in ext] == [f"ctrl{k:02d}" for k in range(1, n + 1)] + [
        f"stroke{k:02d}" for k in range(1, len(STROKE_TEST) + 1)
    ]
    stroke, ext = ext[n:], ExperimentSet(ext[:n])
    # no record of the extension names a constant current: the LPV zone laws group records by
    # it only when every record has it, and Table II's and the replays' do not
    assert not any("current" in r.metadata for r in [*ext, *stroke])
    assert {r.metadata["pattern"] for r in stroke} == {"stroke test"}
    assert [r.metadata["pattern"] for r in ext[:2]] == ["loop current", "APRBS"]
    v_ext = max(float(np.max(np.abs(r.v))) for r in ext)
    v_doe = max(float(np.max(np.abs(r.v))) for r in doe)
    assert v_ext > 0.5 and v_ext > 3 * v_doe  # the loop's velocities, not Table II's
    for r in ext:
        assert np.max(np.abs(r.x)) <= 0.02 + 1e-9  # half the default 0.04 m stroke
        assert np.max(np.abs(r.F)) <= 0.9 * 5000.0 + 50.0  # within the load cell's range
    rows = list(zip(CONTROL_EXTENSION, ext[0::2], strict=True))
    # the loop's own currents: passive soft and hard hold the ends of the range (the measured
    # current carries the transducer's noise); the semi-active controllers vary it on the
    # rougher roads, while the damper moves fast
    for row, r in rows:
        if row.controller in ("soft", "hard"):
            assert abs(np.mean(r.i) - (row.controller == "hard")) < 0.02
        elif row.road_class in ("C", "D"):
            assert np.ptp(r.i) > 0.3, row
            moving = np.abs(r.v) > 0.1
            assert np.ptp(r.i[moving]) > 0.3, row
    for r in ext[1::2]:  # APRBS: over the range, often (50 ms holds; 3 s records)
        assert np.ptp(r.i) > 0.5 and np.sum(np.abs(np.diff(r.i[::10])) > 0.05) >= 5
    again = control_extension(seed=1, scale=0.1, damper=damper, model=_first_model())
    np.testing.assert_array_equal(ext[4].F, again[4].F)
    np.testing.assert_array_equal(stroke[4].F, again[n + 4].F)
    # the stroke test does not change the rows' records (its seeds come after theirs)
    rows_only = control_extension(
        seed=1, scale=0.1, damper=damper, model=_first_model(), stroke_rows=()
    )
    assert len(rows_only) == n
    np.testing.assert_array_equal(ext[n - 1].F, rows_only[n - 1].F)
    other = control_extension(seed=2, scale=0.1, damper=damper, model=_first_model())
    assert not np.array_equal(ext[0].x, other[0].x)
    with pytest.raises(DataValidationError, match="scale") as err:
        control_extension(seed=1, scale=0.01, damper=damper, model=_first_model())
    assert "\n" not in str(err.value)
    volts = dataclasses.replace(_first_model(), input="voltage")
    with pytest.raises(DataValidationError, match="model") as err:
        control_extension(seed=1, scale=0.1, damper=damper, model=volts)
    assert "\n" not in str(err.value)


def test_rig_doe_extension_control_on_the_command_line(
    monkeypatch: pytest.MonkeyPatch, damper, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(cli_rig, "_damper", lambda spec: _soft(damper))
    first = tmp_path / "first.json"
    _first_model().save(first)
    out = tmp_path / "doe"
    args = ["rig", "doe", "--out", str(out), "--scale", "0.07", "--fs", "200"]
    main([*args, "--extension", "control", "--loop-model", str(first)])
    assert "100 records" in capsys.readouterr().out
    names = pd.read_csv(out / "manifest.csv")["name"].tolist()
    assert len(names) == 100 and names[-1] == "stroke09" and (out / "ctrl01.csv").exists()
    # the folder reads back as the records a fit takes (the extension's manifest rows leave
    # experiment, replicate and band empty)
    back = read_records(out)
    assert len(back) == 100
    assert next(r for r in back if r.name == "stroke01").metadata["pattern"] == "stroke test"
    ctrl = next(r for r in back if r.name == "ctrl01")
    assert "experiment" not in ctrl.metadata and ctrl.metadata["pattern"] == "loop current"
    assert next(r for r in back if r.name.startswith("exp")).metadata["experiment"] >= 1
    with pytest.raises(SystemExit):
        main([*args[:3], str(tmp_path / "y"), *args[4:], "--loop-model", str(first)])
    err = capsys.readouterr().err
    assert "--loop-model" in err and len(err.strip().splitlines()) == 1
    with pytest.raises(SystemExit):
        main([*args[:3], str(tmp_path / "x"), *args[4:], "--extension", "fast"])
    err = capsys.readouterr().err
    assert "--extension" in err and len(err.strip().splitlines()) == 1


def test_a_higher_highpass_keeps_more_of_the_loops_velocity_within_the_stroke(damper) -> None:  # type: ignore[no-untyped-def]
    from mrdamper.rig.doe import resolve_rig
    from mrdamper.rig.doe_control import HIGHPASS, replay_loop_motion

    rig = resolve_rig(None, _soft(damper), 1000.0)
    t = np.arange(4000) / 1000.0
    # a body mode (1.2 Hz, 40 mm: most of the stroke) and a wheel hop (10 Hz, 3 mm)
    travel = 0.04 * np.sin(2 * np.pi * 1.2 * t) + 0.003 * np.sin(2 * np.pi * 10 * t)
    current = np.zeros_like(t)

    def replay(highpass: float) -> np.ndarray:
        seeds = tuple(np.random.SeedSequence(3).spawn(3))
        recs = replay_loop_motion(
            rig,
            travel,
            current,
            current_range=(0.0, 1.0),
            seeds=seeds,  # type: ignore[arg-type]
            names=("a", "b"),
            metadata={},
            seed_label=3,
            highpass=highpass,
        )
        assert np.max(np.abs(recs[0].x)) <= 0.02 + 1e-9
        return np.asarray(recs[0].v)

    def wheel_hop(v: np.ndarray) -> float:  # the 10 Hz velocity amplitude [m/s]
        mid = slice(1000, 3000)  # away from the fades
        w = np.exp(-2j * np.pi * 10 * t[mid])
        return float(2 * abs(np.mean(v[mid] * w)))

    v1, v_default = replay(1.0), replay(HIGHPASS)
    assert HIGHPASS > 1.0 and wheel_hop(v_default) > 1.5 * wheel_hop(v1)
    assert wheel_hop(v_default) == pytest.approx(2 * np.pi * 10 * 0.003, rel=0.05)  # unscaled
    for bad in (0.0, 500.0, float("nan")):
        with pytest.raises(DataValidationError, match="highpass") as err:
            replay(bad)
        assert "\n" not in str(err.value)


def test_the_stroke_test_sweeps_the_stroke_slowly_at_constant_currents(damper) -> None:  # type: ignore[no-untyped-def]
    from mrdamper.rig.doe import resolve_rig
    from mrdamper.rig.doe_control import stroke_test

    rig = resolve_rig(None, _soft(damper), 1000.0)
    seeds = list(range(10, 10 + len(STROKE_TEST)))
    recs = stroke_test(rig, current_range=(0.0, 1.0), seeds=seeds)
    assert [r.metadata["pattern"] for r in recs] == ["stroke test"] * len(STROKE_TEST)
    for row, r in zip(STROKE_TEST, recs, strict=True):
        # 90 % of half the 40 mm stroke, at the row's body-band frequency and constant current
        assert np.max(np.abs(r.x)) == pytest.approx(0.018, rel=0.02)
        assert np.max(np.abs(r.v)) == pytest.approx(2 * np.pi * row.frequency * 0.018, rel=0.05)
        assert np.mean(r.i) == pytest.approx(row.level, abs=0.02) and np.ptp(r.i) < 0.05
        assert r.n / r.fs == pytest.approx((row.cycles + 1) / row.frequency, abs=2e-3)
    short = stroke_test(rig, current_range=(0.0, 1.0), seeds=seeds, scale=0.1)
    assert short[0].n / short[0].fs == pytest.approx(3 / STROKE_TEST[0].frequency, abs=2e-3)
    with pytest.raises(DataValidationError, match="seeds") as err:
        stroke_test(rig, current_range=(0.0, 1.0), seeds=seeds[:2])
    assert "\n" not in str(err.value)
