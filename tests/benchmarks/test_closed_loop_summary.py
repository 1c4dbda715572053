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
