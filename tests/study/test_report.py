"""The report: a failed model never blankets the shared figures, tables keep every row with units
and rounding, captions follow the data's origin, and the page fits a browser window."""

from __future__ import annotations

import dataclasses
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from mrdamper.data import ExperimentSet
from mrdamper.study import (
    ModelSpec,
    Protocol,
    Selection,
    Split,
    doe_protocol,
    run_study,
    write_study,
)
from mrdamper.study.figures import FAILED_ESR, failed_models, make_figures, overlay_models
from mrdamper.study.report import render_report
from mrdamper.study.report_tables import energy_table, esr_by_table, laws_table, summary_table
from mrdamper.study.tables import PAPER_HEADLINE

from .browser import find_browser, layout_problems
from .conftest import _record

#: "wild" is the toy structure with its parameters thrown far off (seeded): it simulates without
#: error but its force is far larger than the measured one (ESR >> 1).
MODELS = [ModelSpec("toy"), ModelSpec("toy", {"noise": 5e4}, label="wild"), ModelSpec("toydiverge")]


@pytest.fixture(scope="module")
def result(doe):
    return run_study(doe, doe_protocol(), MODELS, workers=1, progress=False)


@pytest.fixture(scope="module")
def written(result, tmp_path_factory):
    """The study folder of ``result`` (figures and report), written once for the tests that only
    read it."""
    out = write_study(result, tmp_path_factory.mktemp("report") / "out")
    plt.close("all")
    return out


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_failed_models_are_named_with_their_reason(result) -> None:
    failed = failed_models(result)
    assert set(failed) == {"wild", "toydiverge"}
    s = result.summary.set_index("model")
    assert (
        s.loc["wild", "esr_mean"] > FAILED_ESR and s.loc["wild", "n_failed"] == 0
    )  # ok rows, still failed
    assert "mean ESR" in failed["wild"] and "diverged" in failed["toydiverge"]
    assert overlay_models(result, failed) == ["toy"]


@pytest.mark.parametrize("name", ["fig09_force_time", "fig10_fv_models", "fig11_fx_loops"])
def test_a_failed_model_gets_its_own_panel_and_scale(result, name) -> None:
    fig = make_figures(result)[name]
    assert not isinstance(fig, str), fig
    top = fig.axes[0]
    assert [ln.get_label() for ln in top.get_lines()] == [
        "measured",
        "toy",
    ]  # nothing failed overlaid
    panels = {ax.get_title().split(" ")[0].rstrip(":"): ax for ax in fig.axes[1:]}
    assert set(panels) == {"toy", "wild", "toydiverge"}  # every model keeps a panel
    F = result.showcase.record.F
    span = F.max() - F.min()
    lo, hi = panels["toy"].get_ylim()
    assert (
        lo >= F.min() - 0.3 * span and hi <= F.max() + 0.3 * span
    )  # shared scale follows the measurement
    assert "FAILED" in panels["wild"].get_title() and "FAILED" in panels["toydiverge"].get_title()
    wild = panels["wild"].get_lines()[1].get_ydata()
    wlo, whi = panels["wild"].get_ylim()
    assert whi >= np.max(wild) and wlo <= np.min(wild)  # own scale: the whole wild trace is visible
    assert whi - wlo > 3 * (hi - lo)
    assert any("no prediction" in t.get_text() for t in panels["toydiverge"].texts)


def test_tables_keep_failed_rows_with_status_units_and_comparisons(result) -> None:
    tab = summary_table(result.summary, "toy", failed_models(result)).set_index("model")
    assert list(tab.index) == ["toy", "wild", "toydiverge"]
    assert tab.loc["wild", "status"] == "failed" and tab.loc["toy", "status"] == "ok"
    assert tab.loc["toydiverge", "scored (ok / failed)"].endswith(
        f"/ {int(result.summary['n_failed'].iloc[2])}"
    )
    for col in tab.columns:
        assert re.search(r"\[[^\]]+\]|model|status|scored|rank", col), (
            f"column without a unit: {col}"
        )
    # the comparison column is about the reference against the row, worded like the headline
    assert tab.loc["toy", "toy ESR vs this model"] == "reference"
    assert tab.loc["wild", "toy ESR vs this model"].endswith("% lower")


@pytest.mark.slow
def test_report_html_rows_rounding_and_failed_note(written) -> None:
    html = (written / "report.html").read_text()
    assert "Drawn in panels of their own" in html and "wild (mean ESR" in html
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", html)
    floats = [c for c in cells if re.fullmatch(r"-?\d*\.\d+(e[-+]\d+)?", c)]
    sig = [re.sub(r"^0+", "", c.lstrip("-").split("e")[0].replace(".", "")) for c in floats]
    assert floats and max(len(d) for d in sig) <= 4, max(
        zip(map(len, sig), floats)
    )  # 4 significant digits
    assert PAPER_HEADLINE["text"] in html and "51 %" in html and "36.8 %" in html
    # no model of this study takes zone laws: the laws section names no user
    assert "use(s) them" not in html and "post-yield samples" not in html
    numbers = [int(n) for n in re.findall(r"<b>Figure (\d+)</b>", html)]
    assert numbers == list(range(1, len(numbers) + 1))  # consecutive, whatever the paper skips
    assert "(paper Fig. 6)" not in html or "Figure 5</b> (paper Fig. 6)" in html


def test_captions_follow_the_data_origin(result) -> None:
    measured = render_report(result, result.summary, {})
    assert (
        "measured data" in measured
        and "Spencer model" not in measured
        and "virtual rig, whose" not in measured
    )
    rig = dataclasses.replace(
        result, info={**result.info, "data_origin": "virtual rig (spencer damper)"}
    )
    text = render_report(rig, rig.summary, {})
    assert "whose damper is a spencer model" in text and "true structure here" in text


def test_the_showcase_is_the_most_informative_record() -> None:
    recs = [
        _record(f"c{c}_{lev}A", 200.0, 2.0, lev, seed=k, condition=f"c{c}", current=lev)
        for k, (c, lev) in enumerate((c, lev) for c in (1, 2) for lev in (0.0, 1.0, 0.5))
    ]
    proto = Protocol(split=Split("leave-one-group-out", key="condition"), analysis=Selection())
    res = run_study(ExperimentSet(recs), proto, ["toy"], workers=1, progress=False)
    assert res.showcase.record.metadata["current"] == 1.0  # not the first (0 A) record


def test_varying_current_wins_the_showcase(result) -> None:
    i = result.showcase.record.i
    assert np.ptp(i) > 0.1


def test_esr_per_group_and_law_tables(result) -> None:
    r = result.results.assign(current=np.where(np.arange(len(result.results)) % 2, 0.5, 1.0))
    tab = esr_by_table(r, "current", result.labels).set_index("model")
    ok = r[(r["model"] == "toy") & (r["status"] == "ok")]
    assert tab.loc["toy", "0.5 A"] == pytest.approx(ok.loc[ok["current"] == 0.5, "esr"].mean())
    assert np.isnan(tab.loc["toydiverge", "1 A"])  # failed rows stay, with no number
    laws = result.analyses["all"].laws
    tabs = laws_table(laws)
    slopes = tabs["slopes m_j(i) [N s/m]"]
    assert list(slopes.columns[1:4]) == [
        "gamma_0 [N s/m]",
        "gamma_1 [N s/(m A)]",
        "gamma_2 [N s/(m A^2)]",
    ]
    np.testing.assert_array_equal(slopes.iloc[:, 1:4].to_numpy(), laws.gamma_m)


def test_layout_probe_catches_an_overflowing_table(tmp_path) -> None:
    browser = find_browser()
    if browser is None:
        pytest.skip("no headless browser (chromium) installed: apt-get install chromium")
    page = tmp_path / "wide.html"
    row = "".join(f"<td>{k:08d}</td>" for k in range(60))
    page.write_text(
        f"<html><body><table><tr>{row}</tr></table>"
        f'<div style="overflow-x:auto"><table><tr>{row}</tr></table></div></body></html>'
    )
    got = layout_problems(page, 800, browser, tmp_path)
    assert got["tables"] == 2
    assert any(p.startswith("table 0") for p in got["problems"])  # the bare one overflows
    assert not any(p.startswith("table 1") for p in got["problems"])  # the scrolling one does not


@pytest.mark.parametrize("width", [800, 1280])
@pytest.mark.slow
def test_report_tables_fit_the_browser_window(written, tmp_path, width) -> None:
    browser = find_browser()
    if browser is None:
        pytest.skip("no headless browser (chromium) installed: apt-get install chromium")
    got = layout_problems(written / "report.html", width, browser, tmp_path)
    assert got["tables"] >= 8
    assert got["problems"] == []
    if width >= 1280:  # a 1280 px page: no section's table scrolls sideways (but the folded
        # dump of results.csv at the end, one column per field of the records)
        assert [s for s in got["scrolled"] if not s.startswith("All results:")] == []


def test_energy_table_measured_first_then_each_model_on_the_same_cycles(result) -> None:
    from mrdamper.analysis import energy_per_cycle
    from mrdamper.study import Showcase

    sc = result.showcase
    tab = energy_table(sc).set_index("model")
    e = sc.record
    W = energy_per_cycle(e.t, e.x, e.v, e.F)
    assert W.size >= 1 and tab.loc["measured", "cycles"] == W.size
    assert (
        tab.loc["measured", "energy_J"] == pytest.approx(W.mean()) and W.mean() > 0
    )  # a damper dissipates
    assert abs(tab.loc["toy", "diff_pct"]) < 5  # the true structure dissipates what was measured
    assert tab.loc["wild", "diff_pct"] > 100 and np.isnan(tab.loc["toydiverge", "energy_J"])
    short = e.slice(0, int(0.3 * e.fs))  # less than one displacement cycle
    whole = energy_table(
        Showcase(fold="all", record=short, predictions={"toy": sc.predictions["toy"][: short.n]})
    )
    assert whole["cycles"].iloc[0] == 0 and whole["basis"].iloc[0].startswith("whole record")


def test_every_figure_is_drawn_for_print(result) -> None:
    from matplotlib.text import Text

    figs = {k: f for k, f in make_figures(result).items() if not isinstance(f, str)}
    assert len(figs) >= 8
    for name, fig in figs.items():
        assert fig.get_size_inches()[0] <= 7.0 + 1e-9, name  # the text width of an A4 / letter page
        fig.canvas.draw()
        small = [
            (t.get_text(), t.get_fontsize())
            for t in fig.findobj(Text)
            if t.get_visible() and t.get_text().strip() and t.get_fontsize() < 7.0
        ]
        assert not small, (name, small[:5])
        for ax in fig.axes:
            if ax.get_visible() and ax.has_data():
                assert ax.get_xlabel() and ax.get_ylabel() or ax.get_title(), name
                for label in (ax.get_xlabel(), ax.get_ylabel()):
                    assert not label or "[" in label, (name, label)  # units on every axis


def test_the_laws_sentence_names_the_models_that_use_each_set(result) -> None:
    from mrdamper.study.report import _laws_users_note
    from mrdamper.study.runner import laws_users

    assert laws_users(result.protocol) == {}  # the toy models take no zone laws
    users = laws_users(doe_protocol())  # the default models and the paper's LPV
    assert users["lpv"] == "post-yield" and users["lpv-paper"] == "zones"
    assert "sp1" not in users and "spencer" not in users
    an = next(iter(result.analyses.values()))
    note = _laws_users_note(an, users)
    assert "the paper's laws; lpv-paper use(s) them" in note
    assert "lpv, " in note and "re-estimated on its post-yield samples" in note
    assert _laws_users_note(an, {}) == ""
