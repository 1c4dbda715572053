"""Which closed-loop cells lie beyond the stroke the model was trained on, and the fidelity summary.

A rig replays a loop's motion only within its stroke: the control extension
(:mod:`mrdamper.control.loop.doe_extension`) high-passes the loop's travel and its stroke test spans
90 % of the rig's stroke, so a model trained on rig records has never seen the damper moved over
more than that. A quarter-car loop on a rough road moves the damper further (the body motion,
near 1.2 Hz, carries most of the travel). Such a *cell* (one controller on one road at one speed)
is outside what the rig can cover, and its error is the model's extrapolation, not a miss on the
motions it was trained on.

:func:`flag_cells` adds to the table of :func:`~mrdamper.control.loop.fidelity.closed_loop_fidelity`
the cell's ``stroke_ratio`` (the achieved loop's damper displacement span over the span of the
model's training records, from the envelope the model carries) and ``outside_stroke`` (the ratio
above ``1 +`` :data:`~mrdamper.models.envelope.ENVELOPE_TOLERANCE`, as for a record).
:func:`fidelity_summary` gives, per metric, the worst |error| over the covered cells and over the
cells outside, against :data:`TARGETS`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from mrdamper.models.envelope import ENVELOPE_TOLERANCE

__all__ = ["CELL", "TARGETS", "envelope_left", "fidelity_summary", "flag_cells", "stroke_note"]

#: The columns that name a cell of the closed-loop table.
CELL = ("controller", "road", "speed_m_s")

#: Target |error| [%] per metric on the covered cells (the mean current has none: a controller
#: that rarely switches has a mean current of a few mA, whose relative error says little).
TARGETS: dict[str, float] = {
    "a_w": 3.0,
    "rms_acc": 3.0,
    "rms_tyre_load": 3.0,
    "rms_travel": 5.0,
    "rms_tracking": 5.0,
}


def flag_cells(table: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """``table`` with the columns ``stroke_ratio`` [-] and ``outside_stroke`` added.

    Parameters
    ----------
    table : DataFrame
        :meth:`~mrdamper.control.loop.fidelity.FidelityResult.table` (columns :data:`CELL`, ...).
    runs : DataFrame
        :meth:`~mrdamper.control.loop.fidelity.FidelityResult.runs_frame`; the achieved side's
        ``excursion_stroke`` is the cell's ratio (NaN when the model carries no envelope or the
        run was refused, and then the cell is not flagged).

    Returns
    -------
    DataFrame
        A copy of ``table`` with the two columns.
    """
    ratio = pd.Series(np.nan, index=table.index, dtype=float)
    if "excursion_stroke" in runs.columns and len(runs):
        ach = runs[runs["side"] == "achieved"]
        by_cell = {
            (str(r.controller), str(r.road), float(r.speed_m_s)): float(r.excursion_stroke)
            for r in ach.itertuples()
        }
        ratio = pd.Series(
            [
                by_cell.get((str(c), str(rd), float(s)), np.nan)
                for c, rd, s in zip(
                    table["controller"], table["road"], table["speed_m_s"], strict=True
                )
            ],
            index=table.index,
            dtype=float,
        )
    out = table.copy()
    out["stroke_ratio"] = ratio
    out["outside_stroke"] = (ratio > 1.0 + ENVELOPE_TOLERANCE).to_numpy()
    return out


def envelope_left(run: Mapping[str, object]) -> str:
    """The training-envelope dimensions a run (a :meth:`~mrdamper.control.loop.fidelity.
    FidelityResult.runs_frame` row) leaves, largest first (``"stroke x2.3, velocity x1.2"``;
    beyond ``1 +`` :data:`~mrdamper.models.envelope.ENVELOPE_TOLERANCE`); ``""`` within it or
    when the model carries no envelope. A switching input the training never had reads
    ``"switching while moving (new)"``."""
    out = []
    for key, value in run.items():
        if not str(key).startswith("excursion_"):
            continue
        v = float(value)  # type: ignore[arg-type]
        if v == np.inf:
            out.append((np.inf, f"{str(key).removeprefix('excursion_')} while moving (new)"))
        elif np.isfinite(v) and v > 1.0 + ENVELOPE_TOLERANCE:
            out.append((v, f"{str(key).removeprefix('excursion_')} x{v:.2g}"))
    return ", ".join(text for _, text in sorted(out, key=lambda t: -t[0]))


def stroke_note(flagged: pd.DataFrame) -> str | None:
    """One line on the cells outside the training stroke (None when there are none)."""
    cells = flagged.drop_duplicates(list(CELL)).reset_index(drop=True)
    out = cells[cells["outside_stroke"]]
    if out.empty:
        return None
    worst = out.loc[out["stroke_ratio"].idxmax()]
    return (
        f"{len(out)} of {len(cells)} cells move the damper over more than its training records "
        f"span (at most x{worst['stroke_ratio']:.2g}: {worst['controller']} ISO {worst['road']} @ "
        f"{worst['speed_m_s']:g} m/s); a rig cannot replay them beyond its stroke (the control "
        "extension's stroke test spans 90 % of it), so their errors extrapolate: column "
        "outside_stroke of closed_loop.csv"
    )


def _worst(rows: pd.DataFrame) -> tuple[float, str]:
    rows = rows.reset_index(drop=True)
    err = rows["error_pct"].abs()
    if not err.notna().any():
        return float("nan"), ""
    r = rows.loc[err.idxmax()]
    where = f"{r['controller']} {r['road']} @ {r['speed_m_s']:g} m/s"
    if "seed" in rows.columns:
        where += f" seed {int(r['seed'])}"
    return float(abs(r["error_pct"])), where


def fidelity_summary(
    table: pd.DataFrame, targets: Mapping[str, float] | None = None
) -> pd.DataFrame:
    """Per metric: the worst |error| [%] over the covered cells and over the cells outside the
    training stroke, where each lies, and whether the target holds on the covered cells.

    Parameters
    ----------
    table : DataFrame
        :func:`flag_cells`'s table, possibly of several runs (a ``seed`` column names the run).
    targets : mapping, optional
        Target |error| [%] per metric (default :data:`TARGETS`; a metric without one gets NaN
        and ``holds`` empty).

    Returns
    -------
    DataFrame
        Columns ``metric, target_pct, covered_cells, worst_covered_pct, where_covered,
        outside_cells, worst_outside_pct, where_outside, holds``.
    """
    targets = TARGETS if targets is None else targets
    rows = []
    for metric, group in table.groupby("metric", sort=False):
        inside = group[~group["outside_stroke"].astype(bool)]
        outside = group[group["outside_stroke"].astype(bool)]
        w_in, at_in = _worst(inside)
        w_out, at_out = _worst(outside)
        target = float(targets.get(str(metric), np.nan))
        rows.append(
            {
                "metric": metric,
                "target_pct": target,
                "covered_cells": len(inside),
                "worst_covered_pct": w_in,
                "where_covered": at_in,
                "outside_cells": len(outside),
                "worst_outside_pct": w_out,
                "where_outside": at_out,
                "holds": "" if np.isnan(target) else ("yes" if w_in <= target else "no"),
            }
        )
    return pd.DataFrame(rows)
