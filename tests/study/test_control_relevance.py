"""The study's control-relevance step: predicted against achieved on the virtual rig, the spread
of the models on measured data, failing models keeping their rows, and the report section."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mrdamper.study import doe_protocol, run_study
from mrdamper.study.control_step import ControlSettings, control_relevance, truth_damper
from mrdamper.study.report import render_report

QUICK = ControlSettings(duration=2.0, controllers=("soft", "skyhook"), fronts=False)


@pytest.fixture(scope="module")
def rig_study():  # type: ignore[no-untyped-def]
    doe = pytest.importorskip("mrdamper.rig.doe")
    pytest.importorskip("mrdamper.rig.reference").reference_damper()
    data = doe.table_ii(seed=0, scale=0.07, experiments=[1, 6, 7, 8])
    return run_study(
        data,
        doe_protocol(),
        ["sp1", "lti", "toyfail"],
        workers=1,
        progress=False,
        control=ControlSettings(duration=2.0, controllers=("soft", "skyhook")),
    )


@pytest.mark.slow  # fits SP-1 and LTI on a short DoE, then the loop with the rig's damper
def test_a_rig_study_gets_predicted_against_achieved(rig_study) -> None:  # type: ignore[no-untyped-def]
    cr = rig_study.control
    assert cr is not None and cr.truth == "rig"
    t = cr.table
    sp1 = t[(t["model"] == "sp1") & (t["metric"] == "a_w")]
    assert list(sp1["controller"]) == ["soft", "skyhook"]
    assert np.isfinite(sp1[["predicted", "achieved", "error_pct"]].to_numpy()).all()
    got = 100 * (sp1["predicted"] - sp1["achieved"]) / sp1["achieved"]
    np.testing.assert_allclose(sp1["error_pct"], got)
    # LTI has no inverse form: skyhook inverts it through its step
    lti = t[(t["model"] == "lti") & (t["metric"] == "a_w")]
    assert list(lti["controller"]) == ["soft", "skyhook"] and lti["achieved"].notna().all()
    fail = t[t["model"] == "toyfail"]
    assert len(fail) == 2 and fail["reason"].str.startswith("fit failed: ").all()
    assert not isinstance(cr.fronts["sp1"], str) and "fit failed" in str(cr.fronts["toyfail"])
    assert "control_time_s" in rig_study.info
    html = render_report(rig_study, rig_study.summary, {})
    sec = html[html.index("<h2>Control relevance</h2>") :]
    sec = sec[: sec.index("<h2>", 10)]
    assert "The truth is known" in sec and "quiroz2022" in sec
    assert "Fit failed" in sec and "Gain fronts" in sec
    # the two rankings side by side: SP-1 and LTI ran, each with a closed-loop rank
    assert "Which model for a controller?" in sec and "closed-loop rank" in sec
    assert "open-loop rank" in sec
    # the widest model-plant gap of SP-1's sweep, as FrontsResult.widest_gaps finds it
    gap = cr.fronts["sp1"].widest_gaps().set_index("metric").loc["a_w", "error_pct"]
    assert "furthest from the reference damper" in sec and f"{gap:+.1f} %" in sec
    assert "control_time_s" not in html
    # the same step again gives the same table (the report stays byte-identical)
    again = control_relevance(
        {"sp1": rig_study.models[("all", "sp1")]}, ["sp1"], {"sp1": "sp1"}, "rig", "all",
        ControlSettings(duration=2.0, controllers=("soft", "skyhook"), fronts=False),
    )  # fmt: skip
    pd.testing.assert_frame_equal(
        again.table.drop(columns="reason").reset_index(drop=True),
        t[t["model"] == "sp1"].drop(columns="reason").reset_index(drop=True),
    )


def test_measured_data_say_no_truth_and_show_the_spread(doe) -> None:  # type: ignore[no-untyped-def]
    from mrdamper.models.semiphenomenological import SP1Estimator, SP3Estimator

    models = {"sp1": SP1Estimator().fit(doe), "sp3": SP3Estimator().fit(doe)}
    assert truth_damper(doe) is None
    cr = control_relevance(
        models, ["sp1", "sp3", "toy"], {"sp1": "sp1", "sp3": "sp3", "toy": "toy"}, None, "all",
        QUICK, fit_errors={"toy": "IdentificationError: singular"},
    )  # fmt: skip
    t = cr.table
    assert cr.truth is None and t["achieved"].isna().all()
    aw = t[(t["metric"] == "a_w") & (t["controller"] == "skyhook")].set_index("model")
    med = aw["predicted"].median()
    np.testing.assert_allclose(aw["vs_median_pct"], 100 * (aw["predicted"] - med) / med)
    assert aw.loc["sp1", "vs_median_pct"] != 0
    assert aw.loc["sp1", "vs_median_pct"] == pytest.approx(-aw.loc["sp3", "vs_median_pct"])
    assert t[t["model"] == "toy"]["reason"].str.contains("singular").all()


def test_a_measured_study_reports_no_truth_and_keeps_failing_rows(doe) -> None:  # type: ignore[no-untyped-def]
    res = run_study(
        doe, doe_protocol(), ["toy", "toyfail"], workers=1, progress=False, control=QUICK
    )
    cr = res.control
    assert cr is not None and cr.truth is None
    assert set(cr.table["model"]) == {"toy", "toyfail"}
    assert cr.table["reason"].notna().all()  # neither can run in the loop: each keeps its rows
    html = render_report(res, res.summary, {})
    assert "No truth is available" in html and "the records are measured" in html
    off = run_study(doe, doe_protocol(), ["toy"], workers=1, progress=False, control=None)
    assert off.control is None
    assert "switched off" in render_report(off, off.summary, {})


def test_settings_are_checked() -> None:
    from mrdamper.errors import DataValidationError

    with pytest.raises(DataValidationError, match="duration"):
        ControlSettings(duration=1.0)
    with pytest.raises(DataValidationError, match="controller"):
        ControlSettings(controllers=("soft", "sky"))


def test_command_line_settings() -> None:
    from mrdamper.cli.study import control_settings
    from mrdamper.errors import DataValidationError

    assert control_settings(True, "C", 3.0) is None
    s = control_settings(False, "c, d", 6.0)
    assert s.road_classes == ("C", "D") and s.duration == 6.0
    with pytest.raises(DataValidationError, match="--control-roads"):
        control_settings(False, "C,Z", 3.0)


def _section_of(truth: str | None):  # type: ignore[no-untyped-def]
    """A control section with an implausible row, a refused run and a pair that did not run."""
    import types

    from mrdamper.study import report
    from mrdamper.study.control_step import ControlRelevance
    from mrdamper.study.report_control import control_section

    values = {"a_w": (27.2, 3.15), "rms_tyre_load": (640.0, 610.0), "rms_travel": (0.005, 0.0051)}
    rows = []
    for ctrl in ("hard", "skyhook"):
        for metric, (pred, ach) in values.items():
            rows.append(
                {"model": "lpv-paper", "kind": "lpv", "controller": ctrl, "road": "C",
                 "speed_m_s": 20.0, "metric": metric, "predicted": pred, "achieved": ach,
                 "error_pct": 100 * (pred - ach) / ach, "unit": "", "reason": None,
                 "vs_median_pct": 100 * (pred - ach) / ach}
            )  # fmt: skip
    rows[-1]["reason"] = "predicted run refused: the plant step is not converged"
    rows.append(
        {"model": "lti", "kind": "lti", "controller": "skyhook",
         "reason": "DataValidationError: MODEL: kind 'lti' has no inverse; passive soft/hard work"}
    )  # fmt: skip
    cr = ControlRelevance(truth, "all", ControlSettings(), pd.DataFrame(rows))
    summary = pd.DataFrame({"model": ["lpv-paper", "lti"], "esr_mean": [0.01, 0.05]})
    res = types.SimpleNamespace(control=cr, info={"data_origin": "measured"}, summary=summary)
    page = control_section(res, report._table, "A")  # type: ignore[arg-type]
    return cr, page


@pytest.mark.parametrize("truth", ["rig", None])
def test_the_section_flags_implausible_rows_and_says_why_in_words(truth) -> None:  # type: ignore[no-untyped-def]
    from mrdamper.study.report_control import in_words, wide_table

    cr, page = _section_of(truth)
    wide = wide_table(cr, "A").set_index(["model", "controller"])
    against = "achieved" if truth else "the models' median"
    flag = f"implausible: a_w predicted 27.2 m/s² against 3.15 m/s² {against} (+763 %)"
    assert wide.loc[("lpv-paper", "hard"), "note"] == flag
    assert wide.loc[("lpv-paper", "skyhook"), "note"].startswith("Predicted run refused")
    assert (
        wide.loc[("lti", "skyhook"), "note"] == "Kind 'lti' has no inverse; passive soft/hard work"
    )
    assert "Error" not in page and "MODEL:" not in page and "+763 %" in page
    headline = page.split("</p>", 1)[0]
    assert (
        len(headline) < 300 and "2 row(s) hold a prediction off by more than a factor 2" in headline
    )
    assert in_words("fit failed: IdentificationError: singular") == "Fit failed: singular"
    assert in_words("lpv: 2 of 2 loops leave", capital=False) == "lpv: 2 of 2 loops leave"


def test_the_section_fits_a_1280_px_page(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from mrdamper.study import report

    from .browser import find_browser, layout_problems

    browser = find_browser()
    if browser is None:
        pytest.skip("no headless browser (chromium) installed: apt-get install chromium")
    page = tmp_path / "section.html"
    body = _section_of("rig")[1]
    page.write_text(
        f"<html><head><style>{report._CSS}</style></head><body><h2>Control relevance</h2>"
        f"{body}</body></html>",
        encoding="utf-8",
    )
    got = layout_problems(page, 1280, browser, tmp_path)
    assert got["tables"] >= 2 and got["problems"] == [] and got["scrolled"] == []


def test_the_loop_and_the_writing_have_their_own_progress(doe, monkeypatch, tmp_path) -> None:  # type: ignore[no-untyped-def]
    # the quarter-car loop runs after the simulations: its own bar, advanced once per model
    from rich.progress import Progress

    from mrdamper.study import runner

    shown: list[Progress] = []

    def bars(enabled: bool) -> Progress:
        shown.append(Progress(disable=True))
        return shown[-1]

    monkeypatch.setattr(runner, "progress_bars", bars)
    res = run_study(
        doe, doe_protocol(), ["toy", "toyfail"], workers=1, progress=True, control=QUICK
    )
    tasks = {t.description: t for bar in shown for t in bar.tasks}
    assert set(tasks) == {"fitting", "simulating", "quarter car"}
    loop = tasks["quarter car"]
    assert loop.total == 1 and loop.completed == 1  # toy fitted (and ran), toyfail did not
    # then the command line's last stage: the figures and the report being written
    import mrdamper.study
    from mrdamper.cli.study import write_or_fail

    written: list[object] = []
    monkeypatch.setattr(mrdamper.study, "write_study", lambda *a, **k: written.append(a))
    write_or_fail(res, tmp_path / "out", False, show=True)
    writing = shown[-1].tasks[0]
    assert writing.description == "writing" and writing.finished and len(written) == 1


def test_the_closed_loop_ranking_keeps_cells_outside_the_envelope_apart_and_lists_them() -> None:
    """The ranking beside the open-loop one: the worst error over every cell ranks, the worst
    within the training envelope is given apart, the cells outside are listed, and the open-loop
    order is the summary's ESR."""
    from mrdamper.study.control_step import ControlRelevance
    from mrdamper.study.report_control_rank import outside_cells, rankings

    rows = []
    errors = {("m1", "C"): (2.0, ""), ("m1", "D"): (8.0, "stroke x2.3"), ("m2", "C"): (5.0, "")}
    errors[("m2", "D")] = (4.0, "")
    for (model, road), (err, left) in errors.items():
        for metric in ("a_w", "rms_travel", "mean_current"):
            e = 40.0 if metric == "mean_current" else err  # not a loop metric of the ranking
            rows.append(
                {"model": model, "kind": "sp1", "controller": "skyhook", "road": road,
                 "speed_m_s": 20.0, "metric": metric, "predicted": 1.0 + e / 100, "achieved": 1.0,
                 "error_pct": e, "unit": "", "envelope_left": left, "reason": None}
            )  # fmt: skip
    cr = ControlRelevance("rig", "all", ControlSettings(), pd.DataFrame(rows))
    summary = pd.DataFrame({"model": ["m1", "m2"], "esr_mean": [0.03, 0.01]})
    ranks = rankings(summary, cr).set_index("model")
    # over every cell m2 (worst 5 %) is ahead of m1 (8 %, outside its envelope)
    assert ranks.loc["m2", "closed-loop rank"] == 1 and ranks.loc["m1", "closed-loop rank"] == 2
    assert ranks.loc["m1", "open-loop rank"] == 2 and ranks.loc["m2", "open-loop rank"] == 1
    assert ranks.loc["m1", "worst loop error [%]"] == pytest.approx(8.0)
    assert ranks.loc["m1", "worst within the envelope [%]"] == pytest.approx(2.0)
    assert ranks.loc["m1", "cells outside the envelope"] == "1 of 2"
    assert outside_cells(cr) == ["m1: skyhook ISO D @ 20 m/s (stroke x2.3)"]
