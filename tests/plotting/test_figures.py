"""Every figure function draws the expected artists on small data and returns what it drew on."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from mrdamper.analysis import fit_zone_laws, fit_zones
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError
from mrdamper.plotting import (
    plot_force_time,
    plot_fv_map,
    plot_fv_models,
    plot_index_boxes,
    plot_lti_hysteresis,
    plot_model_tracking,
    plot_zone_fit,
    plot_zone_laws,
)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _fv(level: float, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    v = 0.2 * np.sin(np.linspace(0, 4 * np.pi, n))
    return v, np.where(
        np.abs(v) < 0.02, (2000 + 8000 * level) * v, np.sign(v) * (40 + 160 * level) + 500 * v
    )


def _record(n: int = 500) -> Experiment:
    t = np.arange(n) / 100.0
    v = 0.1 * np.cos(2 * np.pi * t)
    return Experiment(
        t=t,
        x=0.1 / (2 * np.pi) * np.sin(2 * np.pi * t),
        v=v,
        F=800 * np.tanh(v / 0.02),
        i=np.full(n, 0.5),
        name="rec",
    )


def test_fv_map_one_trace_per_level() -> None:
    ax = plot_fv_map({lev: _fv(lev) for lev in (0.0, 0.5, 1.0)})
    assert [ln.get_label() for ln in ax.get_lines()] == ["i = 0 A", "i = 0.5 A", "i = 1 A"]
    assert ax.get_xlabel() == "v [m/s]" and ax.get_ylabel() == "F [N]"
    with pytest.raises(DataValidationError, match="curves"):
        plot_fv_map({})


def test_zone_fit_draws_data_three_zones_and_limits() -> None:
    v, F = _fv(1.0)
    fit = fit_zones(v, F, level=1.0)
    _, ax = plt.subplots()
    assert plot_zone_fit(v, F, fit, ax=ax) is ax
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert labels[0] == "measured" and [lab.split(":")[0] for lab in labels[1:4]] == [
        "zone I",
        "zone II",
        "zone III",
    ]
    assert len(ax.get_lines()) == 6  # + two zone limits
    assert "1 A" in ax.get_title()


def test_zone_laws_one_panel_and_scale_per_quantity() -> None:
    fits = [fit_zones(*_fv(lev), level=lev) for lev in (0.0, 0.25, 0.5, 0.75, 1.0)]
    laws = fit_zone_laws(fits)
    axes = plot_zone_laws(laws)
    assert axes.shape == (2, 3)
    for row, name in enumerate("mc"):
        for j in range(3):
            ax = axes[row, j]
            assert [ln.get_label() for ln in ax.get_lines()] == [
                f"{name}{j + 1} fit",
                f"{name}{j + 1} law",
            ]
            assert ax.get_ylabel().startswith(f"{name}{j + 1} [")
    # m2 is far steeper than m1: each slope's panel spans its own values, not the largest one's
    _, hi = axes[0, 0].get_ylim()
    assert hi < 0.5 * laws.level_m[:, 1].max()


def test_lti_hysteresis_and_tracking_panels() -> None:
    e = _record()
    axes = plot_lti_hysteresis(e, 0.9 * e.F, window=(1.0, 3.0))
    assert len(axes) == 2 and all(len(ax.get_lines()) == 2 for ax in axes)
    assert axes[0].get_xlabel() == "v [m/s]" and axes[1].get_xlabel() == "t [s]"
    assert axes[1].get_lines()[0].get_xdata().min() >= 1.0
    axes = plot_model_tracking(e, e.F * 1.01)
    assert len(axes) == 3
    assert [ln.get_label() for ln in axes[0].get_lines()] == ["measured", "LPV"]
    assert axes[2].get_ylabel() == "i [A]"
    with pytest.raises(DataValidationError, match="F_model: expected 500 samples"):
        plot_model_tracking(e, e.F[:10])
    with pytest.raises(DataValidationError, match="window"):
        plot_lti_hysteresis(e, e.F, window=(100.0, 200.0))


def test_index_boxes_mean_under_each_box() -> None:
    df = pd.DataFrame(
        {
            "model": ["lpv"] * 3 + ["sp1"] * 3 + ["p15"],
            "status": ["ok"] * 6 + ["diverged"],
            "esr": [0.01, 0.02, 0.03, 0.1, 0.2, 0.3, np.nan],
        }
    )
    ax = plot_index_boxes(df, "esr", order=["lpv", "sp1", "p15"])
    assert [t.get_text() for t in ax.get_xticklabels()] == ["lpv", "sp1", "p15"]
    texts = [t.get_text() for t in ax.texts]
    assert texts == ["mean\n0.02", "mean\n0.2", "failed"]
    assert len(ax.patches) == 2  # two filled boxes, none for the failed model
    with pytest.raises(DataValidationError, match="ssse"):
        plot_index_boxes(df, "ssse")


def test_force_time_and_fv_all_models() -> None:
    e = _record()
    preds = {"lpv": e.F * 0.98, "sp1": e.F * 0.9, "lti": e.F * 0.5}
    ax = plot_force_time(e, preds)
    assert [ln.get_label() for ln in ax.get_lines()] == ["measured", "lpv", "sp1", "lti"]
    ax = plot_fv_models(e, preds, window=(0.0, 2.0))
    assert [ln.get_label() for ln in ax.get_lines()] == ["measured", "lpv", "sp1", "lti"]
    assert ax.get_xlabel() == "v [m/s]"
    with pytest.raises(DataValidationError, match="predictions"):
        plot_force_time(e, {})


def test_a_wild_model_does_not_hide_the_others() -> None:
    e = _record()
    ax = plot_force_time(e, {"good": e.F * 0.98, "wild": e.F * 50})
    lo, hi = ax.get_ylim()
    assert hi < 3 * e.F.max() and lo > 3 * e.F.min()  # measured span widened by half of it
    assert any("beyond the axes: wild" in t.get_text() for t in ax.texts)
    ax = plot_fv_models(e, {"wild": e.F * 50}, clip_margin=None)
    assert ax.get_ylim()[1] >= 50 * e.F.max()


def test_model_panels_overlay_few_and_draw_every_model_apart() -> None:
    from mrdamper.plotting import plot_model_panels

    e = _record()
    preds = {
        "a": e.F * 0.98,
        "b": e.F * 0.9,
        "c": e.F * 0.7,
        "wild": e.F * 80,
        "gone": "diverged at sample 3",
    }
    fig = plot_model_panels(
        e, preds, plane="fx", overlay=["a", "b", "wild"], failed={"wild": "ESR 6e3 > 1"}
    )
    top, *panels = fig.axes
    assert [ln.get_label() for ln in top.get_lines()] == [
        "measured",
        "a",
        "b",
    ]  # failed never overlaid
    assert top.get_xlabel() == "x [mm]" and top.get_ylabel() == "F [N]"
    assert [ax.get_title().split(" ")[0].rstrip(":") for ax in panels] == [
        "a",
        "b",
        "c",
        "wild",
        "gone",
    ]
    assert panels[3].get_ylim()[1] >= 80 * e.F.max()  # its own scale
    assert panels[0].get_ylim()[1] < 2 * e.F.max()  # shared scale of the others
    assert "FAILED" in panels[4].get_title()
    with pytest.raises(DataValidationError, match="plane"):
        plot_model_panels(e, preds, plane="xy")
    with pytest.raises(DataValidationError, match="overlay"):
        plot_model_panels(e, preds, overlay=["nope"])
