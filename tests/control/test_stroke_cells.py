"""The closed-loop cells beyond the training stroke: flagged per cell, kept apart in the summary."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mrdamper.control.loop.stroke_cells import (
    envelope_left,
    fidelity_summary,
    flag_cells,
    stroke_note,
)


def _table() -> tuple[pd.DataFrame, pd.DataFrame]:
    rows, runs = [], []
    cells = {("skyhook", "B"): (0.6, 2.0, 4.0), ("skyhook", "D"): (3.2, 1.0, 9.0)}
    for (ctrl, road), (ratio, aw, travel) in cells.items():
        for metric, err in (("a_w", aw), ("rms_travel", -travel), ("mean_current", 50.0)):
            rows.append(
                {"controller": ctrl, "road": road, "speed_m_s": 25.0, "metric": metric,
                 "predicted": 1.0, "achieved": 1.0, "error_pct": err}
            )  # fmt: skip
        for side, r in (("predicted", 99.0), ("achieved", ratio)):  # only achieved counts
            runs.append(
                {"controller": ctrl, "road": road, "speed_m_s": 25.0, "side": side,
                 "excursion_stroke": r, "excursion_velocity": 0.5}
            )  # fmt: skip
    return pd.DataFrame(rows), pd.DataFrame(runs)


def test_cells_beyond_the_stroke_are_flagged_and_kept_apart() -> None:
    table, runs = _table()
    flagged = flag_cells(table, runs)
    by_road = flagged.drop_duplicates("road").set_index("road")
    assert by_road.loc["B", "stroke_ratio"] == pytest.approx(0.6)
    assert not by_road.loc["B", "outside_stroke"] and by_road.loc["D", "outside_stroke"]
    summ = fidelity_summary(flagged).set_index("metric")
    # the covered cell's |error| is the target's figure; the cell beyond the stroke is apart
    assert summ.loc["rms_travel", "worst_covered_pct"] == pytest.approx(4.0)
    assert summ.loc["rms_travel", "worst_outside_pct"] == pytest.approx(9.0)
    assert summ.loc["rms_travel", "holds"] == "yes" and summ.loc["a_w", "holds"] == "yes"
    assert np.isnan(summ.loc["mean_current", "target_pct"])
    assert summ.loc["rms_travel", "where_outside"] == "skyhook D @ 25 m/s"
    note = stroke_note(flagged)
    assert note is not None and note.startswith("1 of 2 cells") and "x3.2" in note


def test_a_model_without_an_envelope_flags_nothing() -> None:
    table, runs = _table()
    flagged = flag_cells(table, runs.drop(columns=["excursion_stroke"]))
    assert not flagged["outside_stroke"].any() and flagged["stroke_ratio"].isna().all()
    assert stroke_note(flagged) is None


def test_envelope_left_names_the_dimensions_largest_first() -> None:
    run = {"side": "achieved", "excursion_stroke": 2.3, "excursion_velocity": 1.2,
           "excursion_frequency": 1.02, "excursion_switching": np.inf}  # fmt: skip
    assert envelope_left(run) == "switching while moving (new), stroke x2.3, velocity x1.2"
    assert envelope_left({"excursion_stroke": 0.5}) == ""
