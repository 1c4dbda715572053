"""The "Control relevance" section's two rankings: open loop beside closed loop.

The study ranks its models by their free-run error on the left-out records (the open-loop
ranking, the summary's mean ESR). A controller needs the model that predicts its loop: with the
truth known (virtual rig) :func:`rankings` ranks the models by the worst |error| [%] of their
loop metrics (``a_w``, RMS acceleration, tyre load, travel, tracking) against the rig's damper
over the cells (every model runs the same ones), gives the worst over the cells whose loop stays
within the model's training envelope apart, and counts the cells that leave it
(:func:`~mrdamper.control.loop.stroke_cells.envelope_left`, column ``envelope_left`` of
``control.csv``), whose errors are extrapolation.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from mrdamper.study.control_step import ControlRelevance

__all__ = ["LOOP_METRICS", "outside_cells", "rankings"]

#: The loop metrics of the closed-loop ranking.
LOOP_METRICS: tuple[str, ...] = ("a_w", "rms_acc", "rms_tyre_load", "rms_travel", "rms_tracking")


def _cells(cr: ControlRelevance) -> pd.DataFrame:
    t = cr.table.dropna(subset=["road"])
    left = t["envelope_left"] if "envelope_left" in t else pd.Series("", index=t.index)
    return t.assign(envelope_left=left.fillna("").astype(str))


def rankings(summary: pd.DataFrame, cr: ControlRelevance) -> pd.DataFrame:
    """Per model: open-loop rank (mean ESR) and, with a truth, closed-loop rank.

    Parameters
    ----------
    summary : DataFrame
        The study's per-model summary (``model``, ``esr_mean``).
    cr : ControlRelevance
        The control step's result.

    Returns
    -------
    DataFrame
        ``model, open-loop rank, mean ESR, closed-loop rank, worst loop error [%], where, worst
        within the envelope [%], cells outside the envelope``, sorted by the closed-loop rank
        when there is one (the rank of the worst loop error over every cell: every model runs
        the same cells, and a study trained on Table II alone has none within its envelope).
    """
    open_ = summary[["model", "esr_mean"]].dropna()
    open_rank = {m: k + 1 for k, m in enumerate(open_.sort_values("esr_mean")["model"])}
    t = _cells(cr)
    rows = []
    for model in dict.fromkeys(cr.table["model"]):
        sub = t[(t["model"] == model) & t["metric"].isin(LOOP_METRICS)]
        cells = sub.drop_duplicates(["controller", "road", "speed_m_s"])
        inside = sub[sub["envelope_left"] == ""]
        row: dict[str, Any] = {
            "model": model,
            "open-loop rank": open_rank.get(model, np.nan),
            "mean ESR": summary.set_index("model")["esr_mean"].get(model, np.nan),
            "worst loop error [%]": np.nan,
            "where": "",
            "worst within the envelope [%]": np.nan,
            "cells outside the envelope": f"{int((cells['envelope_left'] != '').sum())} of "
            f"{len(cells)}",
        }
        err = sub["error_pct"].abs()
        if cr.truth is not None and err.notna().any():
            r = sub.loc[err.idxmax()]
            row["worst loop error [%]"] = float(err.max())
            row["where"] = f"{r['metric']}, {r['controller']} ISO {r['road']} @ {r['speed_m_s']:g}"
            within = inside["error_pct"].abs()
            row["worst within the envelope [%]"] = (
                float(within.max()) if within.notna().any() else np.nan
            )
        rows.append(row)
    out = pd.DataFrame(rows)
    if cr.truth is None:
        dropped = ["worst loop error [%]", "where", "worst within the envelope [%]"]
        return out.drop(columns=dropped).sort_values("open-loop rank")
    ranked = out["worst loop error [%]"].rank(method="min")
    out.insert(3, "closed-loop rank", ranked)
    return out.sort_values(["closed-loop rank", "open-loop rank"], na_position="last")


def outside_cells(cr: ControlRelevance) -> list[str]:
    """``"lpv: skyhook ISO C @ 20 m/s (stroke x1.9, velocity x1.2)"`` for every cell whose loop
    leaves the model's training envelope."""
    t = _cells(cr)
    t = t[t["envelope_left"] != ""].drop_duplicates(["model", "controller", "road", "speed_m_s"])
    return [
        f"{r.model}: {r.controller} ISO {r.road} @ {r.speed_m_s:g} m/s ({r.envelope_left})"
        for r in t.itertuples()
    ]
