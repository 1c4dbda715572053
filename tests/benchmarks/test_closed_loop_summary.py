"""The closed-loop benchmark's per-controller summary: the layout ``docs/results.md`` quotes."""

from __future__ import annotations

import numpy as np
import pandas as pd

from tests.conftest import load_benchmark


def test_summary_takes_the_worst_road_class_c_apart_and_counts_refused_runs() -> None:
    bench = load_benchmark("closed_loop")
    rows = []
    errors = {"C": 2.0, "D": -7.5}  # signed: the summary reports |error|
    for road, err in errors.items():
        for metric in ("a_w", "rms_acc", "rms_tyre_load", "rms_travel", "mean_current"):
            rows.append(
                {
                    "kind": "lpv",
                    "controller": "skyhook",
                    "road": road,
                    "metric": metric,
                    "error_pct": err,
                }
            )
        rows.append(
            {
                "kind": "lpv",
                "controller": "skyhook",
                "road": road,
                "metric": "rms_tracking",
                "error_pct": 3.0 * err,
            }
        )
        rows.append(
            {"kind": "lpv", "controller": "soft", "road": road, "metric": "a_w", "error_pct": err}
        )
        rows.append(
            {
                "kind": "lpv",
                "controller": "soft",
                "road": road,
                "metric": "rms_tracking",
                "error_pct": np.nan,
            }
        )
    runs = pd.DataFrame(
        [
            {"kind": "lpv", "controller": "skyhook", "refused": "refused: substeps: ..."},
            {"kind": "lpv", "controller": "skyhook", "refused": np.nan},
        ]
    )
    out = bench.controller_summary(pd.DataFrame(rows), runs).set_index("controller")
    assert out.loc["skyhook", "worst [%]"] == (
        "7.5 / 7.5 / 7.5 / 7.5 (2.0 / 2.0 / 2.0 / 2.0); tracking 22.5, current 7.5; "
        "1 run(s) refused or diverged"
    )
    # a passive controller has no tracking error, and metrics it lacks read nan
    assert out.loc["soft", "worst [%]"] == "7.5 / nan / nan / nan (2.0 / nan / nan / nan)"
    # with the values, the worst mean-current gap is also given in mA against its mean
    table = pd.DataFrame(rows)
    table["achieved"] = np.where(table["road"] == "C", 0.020, 0.0132)
    table["predicted"] = table["achieved"] * (1 + table["error_pct"] / 100)
    out = bench.controller_summary(table, runs).set_index("controller")
    assert "; tracking 22.5, current 7.5 (1.0 of 13.2 mA);" in out.loc["skyhook", "worst [%]"]
    volts = bench.controller_summary(table, runs, "V").set_index("controller")
    assert "current 7.5 (1.0 of 13.2 mV)" in volts.loc["skyhook", "worst [%]"]


def test_front_summary_takes_the_worst_gain_and_the_chosen_one() -> None:
    bench = load_benchmark("closed_loop")
    rows = []
    current = {2000.0: 30.0, 8000.0: 1.0, 12000.0: np.nan}
    for gain, err in ((2000.0, 1.0), (8000.0, -20.0), (12000.0, np.nan)):  # 12000: refused
        for metric in ("a_w", "rms_tyre_load", "rms_travel", "mean_current"):
            rows.append(
                {
                    "kind": "lpv",
                    "controller": "groundhook",
                    "level": np.nan,
                    "c_sky": np.nan,
                    "c_ground": gain,
                    "alpha": np.nan,
                    "metric": metric,
                    # the mean current's worst is elsewhere: "worst at" ignores it
                    "error_pct": err if metric != "mean_current" else current[gain],
                }
            )
    chosen = pd.DataFrame(
        [
            {
                "kind": "lpv",
                "controller": "groundhook",
                "c_sky": np.nan,
                "c_ground": 2000.0,
                "alpha": np.nan,
                **{f"{m}_predicted": 1.01 for m in ("a_w", "rms_tyre_load", "rms_travel")},
                **{f"{m}_achieved": 1.0 for m in ("a_w", "rms_tyre_load", "rms_travel")},
            }
        ]
    )
    out = bench.front_summary(pd.DataFrame(rows), chosen).iloc[0]
    assert out["over the sweep"] == "20.0 / 20.0 / 20.0 / 30.0"
    assert out["worst at"] == "c_ground 8000"
    assert out["chosen gain"] == "c_ground 2000"
    assert out["at the chosen gain"] == "1.0 / 1.0 / 1.0"
    assert out["refused"] == 1
