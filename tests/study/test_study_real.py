"""The study with the real pieces: virtual-rig Table II records, the analysis, real estimators,
and (slow) the real Quiroz records."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mrdamper.study import Protocol, Selection, Split, doe_protocol, run_study, write_study


@pytest.fixture(scope="module")
def short_doe(rig_damper):
    doe = pytest.importorskip("mrdamper.rig.doe")
    return doe.table_ii(seed=0, scale=0.1, damper=rig_damper, experiments=[1, 2, 6, 7, 8])


@pytest.mark.slow  # every real model fitted and scored on a short DoE
def test_quick_doe_study_with_real_models(short_doe, tmp_path) -> None:
    res = run_study(short_doe, doe_protocol(), ["lti", "sp2"], workers=2, progress=False)
    an = res.analyses["all"]
    assert an.error == "" and an.by == "plateaus"
    assert len(an.fits) == 5  # the five SC levels of the rig
    scored = len(short_doe) - 2 - 3  # first replicates of 1, 2 train; of 6, 7, 8 analyse
    assert len(res.results) == 2 * scored
    ok = res.results[res.results["status"] == "ok"]
    assert len(ok) == len(res.results), res.results[res.results["status"] != "ok"][
        ["model", "error"]
    ]
    assert np.isfinite(ok["esr"]).all() and (ok["esr"] > 0).all()
    # the static SP-2 map describes a damper's F-v hysteresis better than a linear model does
    s = res.summary.set_index("model")
    assert s.loc["sp2", "esr_mean"] < s.loc["lti", "esr_mean"]
    out = write_study(res, tmp_path / "out")
    figs = {p.stem for p in (out / "figures").glob("*.png")}
    assert {
        "fig01_fv_map",
        "fig02_zone_fit",
        "fig03_zone_laws",
        "fig04_lti_hysteresis",
        "fig07_esr_boxes",
        "fig08_ssse_boxes",
        "fig09_force_time",
        "fig10_fv_models",
    } <= figs
    html = (out / "report.html").read_text()
    assert html.count('<img src="data:image/png;base64,') == len(figs)
    assert pd.read_csv(out / "summary.csv")["model"].tolist() == ["lti", "sp2"]


@pytest.mark.slow
@pytest.mark.realdata
def test_quiroz_leave_one_condition_out(quiroz_unfiltered_dir) -> None:
    from mrdamper.data.readers import read_directory

    data = read_directory(quiroz_unfiltered_dir)
    two = data.where(lambda e: e.metadata["condition"] in ("5mm_3Hz", "10mm_2Hz"))
    proto = Protocol(
        name="q2", analysis=Selection(), split=Split("leave-one-group-out", key="condition")
    )
    res = run_study(two, proto, ["sp2"], workers=2, progress=False)
    r = res.results
    assert set(r["fold"]) == {"condition=5mm_3Hz", "condition=10mm_2Hz"} and len(r) == 10
    for fold, grp in res.roles.groupby("fold"):
        held = fold.split("=")[1]
        assert all(held in n for n in grp.loc[grp.role == "score", "record"])
        assert not any(held in n for n in grp.loc[grp.role == "train", "record"])
    assert (r["status"] == "ok").all()
    # trained on another amplitude/frequency, SP-2 must still beat predicting the mean force
    assert (r["esr"] < 1.0).all()
    assert res.analyses["condition=5mm_3Hz"].by == "current"
    # the report speaks of measured data, and its showcase is a 1 A record, not the first (0 A) one
    assert res.info["data_origin"] == "measured"
    assert res.showcase.record.metadata["current"] == 1.0
    from mrdamper.study.report import render_report

    html = render_report(res, res.summary, {})
    assert (
        "measured data" in html and "Spencer model" not in html and "virtual rig, whose" not in html
    )
