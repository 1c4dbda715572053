"""Gain fronts: the passive front and the semi-active gains, the gain over passive at equal
travel, the gain chosen on the model, and ``quartercar --tune``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mrdamper.cli.main import main
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.fidelity import checked_run, loop_metrics
from mrdamper.control.loop.fronts import FrontsResult, gain_fronts
from mrdamper.control.loop.quarter_car import QuarterCarResult, iso_road
from mrdamper.errors import DataValidationError
from mrdamper.models.semiphenomenological import SP3Model

S = (800.0, 200.0, 60.0, 0.0, 900.0, 0.0)


def _row(
    side: str, ctrl: str, travel: float, a_w: float, tyre: float, **kw: float
) -> dict[str, object]:
    base = {"road": "C", "speed_m_s": 20.0, "side": side, "controller": ctrl, "level": np.nan}
    base.update(c_sky=np.nan, c_ground=np.nan, alpha=np.nan, mean_current=0.0, status="ok")
    base.update(a_w=a_w, rms_tyre_load=tyre, rms_travel=travel, **kw)
    return base


def _known() -> FrontsResult:
    rows = []
    for side in ("predicted", "achieved"):
        rows += [
            _row(side, "passive", 0.010, 1.0, 800.0, level=0.0),
            _row(side, "passive", 0.008, 2.0, 700.0, level=0.5),
            _row(side, "passive", 0.006, 3.0, 900.0, level=1.0),
            # at 9 mm the passive front gives a_w 1.5 and 750 N
            _row(side, "skyhook", 0.009, 1.2, 780.0, c_sky=1000.0),
            _row(side, "skyhook", 0.007, 2.0, 820.0, c_sky=3000.0),  # passive: 2.5, 800 N
            _row(side, "skyhook", 0.012, 1.0, 800.0, c_sky=500.0),  # more travel than soft
            _row(side, "groundhook", 0.009, 1.8, 675.0, c_ground=2000.0),
        ]
    rows[-1]["rms_tyre_load"] = 760.0  # the achieved groundhook point is worse than predicted
    return FrontsResult("sp3", "sp3", rows)


def test_gain_over_passive_at_equal_travel_and_the_chosen_gain() -> None:
    res = _known()
    t = res.table()
    pred = t[t["side"] == "predicted"].set_index(["controller", "c_sky", "c_ground"])
    assert pred.loc[("skyhook", 1000.0, np.nan), "aw_gain_pct"] == pytest.approx(20.0)
    assert pred.loc[("skyhook", 1000.0, np.nan), "tyre_gain_pct"] == pytest.approx(-4.0)
    assert pred.loc[("skyhook", 3000.0, np.nan), "aw_gain_pct"] == pytest.approx(20.0)
    assert np.isnan(pred.loc[("skyhook", 500.0, np.nan), "aw_gain_pct"])  # outside the front
    assert pred.loc[("groundhook", np.nan, 2000.0), "tyre_gain_pct"] == pytest.approx(10.0)
    assert t.loc[t["controller"] == "passive", "aw_gain_pct"].isna().all()
    # Pareto: soft (1.0, 800) and the groundhook point (1.8, 675) and the 1000 N s/m skyhook
    front = set(pred.index[pred["pareto"]].get_level_values(0))
    assert front == {"passive", "skyhook", "groundhook"}
    ch = res.chosen().set_index("controller")
    assert ch.loc["skyhook", "c_sky"] in (1000.0, 3000.0)
    assert ch.loc["groundhook", "tyre_gain_pct_predicted"] == pytest.approx(10.0)
    # achieved: 760 N against the achieved passive front's 750 N at 9 mm
    assert ch.loc["groundhook", "tyre_gain_pct_achieved"] == pytest.approx(100 * (1 - 760 / 750))
    assert ch.loc["skyhook", "soft_a_w_predicted"] == 1.0
    assert "hybrid" not in ch.index  # no hybrid point: nothing to choose


def test_fidelity_pairs_every_point_of_the_sweep_with_the_plant() -> None:
    fid = _known().fidelity()
    assert len(fid) == 7 * 4  # every point x a_w, tyre load, travel, mean current
    gh = fid[(fid["controller"] == "groundhook") & (fid["metric"] == "rms_tyre_load")].iloc[0]
    assert (gh["predicted"], gh["achieved"]) == (675.0, 760.0)
    assert gh["error_pct"] == pytest.approx(100 * (675 - 760) / 760)
    assert gh["difference"] == 675.0 - 760.0
    aw = fid[fid["metric"] == "a_w"]
    assert (aw["error_pct"] == 0.0).all()  # the same a_w on both sides
    assert fid.loc[fid["metric"] == "mean_current", "error_pct"].isna().all()  # 0 A achieved
    gaps = _known().widest_gaps().set_index("metric")
    assert gaps.loc["rms_tyre_load", "controller"] == "groundhook"
    assert gaps.loc["rms_tyre_load", "c_ground"] == 2000.0
    # the mean input is ranked by its difference [A], which its 0 A achieved value allows
    assert gaps.loc["mean_current", "difference"] == 0.0
    # without a plant there is nothing to compare with
    alone = FrontsResult("sp3", None, [r for r in _known().rows if r["side"] == "predicted"])
    assert alone.fidelity().empty and alone.widest_gaps().empty


def test_the_sweep_runs_the_model_and_the_plant_as_the_loop_does() -> None:
    model = SP3Model(S=S, input_range=(0.0, 1.0))
    plant = SP3Model(S=tuple(1.2 * s for s in S), input_range=(0.0, 1.0))
    res = gain_fronts(
        model,
        plant,
        duration=2.0,
        grids={"skyhook": (2000.0,), "hybrid": (3000.0,)},
        alphas=(0.5,),
        levels=(0.0, 1.0),
    )
    t = res.table()
    assert len(t) == 2 * (2 + 1 + 1)
    assert (t["status"] == "ok").all()
    road = iso_road("C", duration=2.0, fs=1000.0, seed=0)
    for side, p in (("predicted", None), ("achieved", plant)):
        for level, ctrl in ((0.0, "soft"), (1.0, "hard")):

            def run(s: int, c: str = ctrl, p: SP3Model | None = p) -> QuarterCarResult:
                return simulate_closed_loop(model, road, c, plant=p, substeps=s)

            want = loop_metrics(checked_run(run)[0])
            got = t[(t["side"] == side) & (t["level"] == level)].iloc[0]
            assert got["a_w"] == pytest.approx(want["a_w"], rel=1e-12)
            assert got["rms_tyre_load"] == pytest.approx(want["rms_tyre_load"], rel=1e-12)
    sky = t[(t["controller"] == "skyhook") & (t["side"] == "achieved")].iloc[0]
    assert sky["c_sky"] == 2000.0 and np.isnan(sky["c_ground"]) and sky["mean_current"] > 0
    fid = res.fidelity()
    hard = fid[(fid["level"] == 1.0) & (fid["metric"] == "rms_travel")].iloc[0]
    pred, ach = (
        t[(t["side"] == s) & (t["level"] == 1.0)].iloc[0] for s in ("predicted", "achieved")
    )
    assert hard["predicted"] == pred["rms_travel"] and hard["achieved"] == ach["rms_travel"]
    assert hard["error_pct"] == pytest.approx(100 * (pred["rms_travel"] / ach["rms_travel"] - 1))
    assert abs(hard["error_pct"]) > 1.0  # the plant's coefficients are 20 % larger


def test_the_sweep_refuses_levels_outside_the_range() -> None:
    model = SP3Model(S=S, input_range=(0.0, 1.0))
    with pytest.raises(DataValidationError, match="levels"):
        gain_fronts(model, levels=(0.0, 1.5), duration=2.0)
    with pytest.raises(DataValidationError, match="grids"):
        gain_fronts(model, grids={"soft": (1.0,)}, duration=2.0)


def test_quartercar_tune_writes_the_fronts(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    path = tmp_path / "sp3.json"
    SP3Model(S=S, input_range=(0.0, 1.0)).save(path)
    out = tmp_path / "tune"
    args = ["quartercar", str(path), "--tune", "--roads", "C", "--duration", "2", "--out", str(out)]
    main(args)
    df = pd.read_csv(out / "fronts.csv")
    assert set(df["side"]) == {"predicted"} and (out / "fronts.png").stat().st_size > 0
    assert {"passive", "skyhook", "groundhook", "hybrid"} == set(df["controller"])
    text = capsys.readouterr().out
    assert "gains chosen on the model" in text and "skyhook" in text
    with pytest.raises(SystemExit) as info:  # never over an existing file without --force
        main(args)
    assert info.value.code != 0
    assert "--force" in capsys.readouterr().err
    main([*args, "--force"])


def test_quartercar_tune_with_a_plant_names_the_widest_gap(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    model, plant = tmp_path / "model.json", tmp_path / "plant.json"
    SP3Model(S=S, input_range=(0.0, 1.0)).save(model)
    SP3Model(S=tuple(1.2 * s for s in S), input_range=(0.0, 1.0)).save(plant)
    out = tmp_path / "tune"
    main(["quartercar", str(model), "--plant", str(plant), "--tune", "--roads", "C",
          "--duration", "2", "--out", str(out)])  # fmt: skip
    text = capsys.readouterr().out
    line = next(t for t in text.splitlines() if t.startswith("widest model-plant gap"))
    df = pd.read_csv(out / "fronts.csv")
    keys = ["controller", "level", "c_sky", "c_ground", "alpha"]
    p = df[df["side"] == "predicted"].set_index(keys)["rms_travel"]
    a = df[df["side"] == "achieved"].set_index(keys)["rms_travel"]
    err = 100 * (p - a) / a
    assert f"rms_travel {err.loc[err.abs().idxmax()]:+.1f} %" in line
    i_p = df[df["side"] == "predicted"].set_index(keys)["mean_current"]
    i_a = df[df["side"] == "achieved"].set_index(keys)["mean_current"]
    diff = i_p - i_a
    assert f"mean_current {diff.loc[diff.abs().idxmax()]:+.3g} A" in line
    assert "ISO C" in line
