"""Result tables of a study: the per-record table's columns, the per-model summary and the headline.

The summary states, per model, the mean, median and quartiles of ESR (paper eq. 24) and SSSE
(eq. 23, an RMS error in N) over the scored records it simulated successfully, how many rows
failed, and the improvement of the best model over it in percent, computed as the paper does:
``100 * (mean_other - mean_best) / mean_other`` (LPV 0.036 vs SP-1 0.074 -> 51 %).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

__all__ = [
    "PAPER_CLASSICAL",
    "PAPER_HEADLINE",
    "PAPER_LPV",
    "RESULT_COLUMNS",
    "TIMING_COLUMNS",
    "headline",
    "headlines",
    "improvement_pct",
    "summarize",
]

#: Columns of ``results.csv`` in order (record metadata columns follow).
RESULT_COLUMNS: tuple[str, ...] = (
    "fold",
    "model",
    "kind",
    "record",
    "status",
    "esr",
    "ssse",
    "nrmse",
    "fit_pct",
    "fit_time_s",
    "sim_time_s",
    "note",
    "error",
)
#: Columns that hold wall-clock times (they differ between otherwise identical runs).
TIMING_COLUMNS: tuple[str, ...] = ("fit_time_s", "sim_time_s")
#: The paper's classical models (Section V): the headline compares LPV with the best of these.
#: Spencer and Bingham are extra reference models; on the virtual rig the damper itself is a
#: Spencer model, so that estimator has the true structure and is not a fair competitor.
PAPER_CLASSICAL: frozenset[str] = frozenset({"p15", "sp1", "sp2", "sp3", "sp4"})

#: The paper's own headline (its abstract and Section V): LPV against its best classical model,
#: SP-1, on the paper's test rig: mean ESR 0.036 vs 0.074 and mean SSSE lower by 36.8 %.
PAPER_HEADLINE: dict[str, Any] = {
    "best_classical": "sp1",
    "esr_improvement_pct": 51.0,
    "ssse_improvement_pct": 36.8,
    "text": (
        "The paper reports LPV 51 % lower mean ESR and 36.8 % lower mean SSSE than its best "
        "classical model (SP-1), on its own test rig."
    ),
}

#: Label of the paper's own LPV model (static input) in the study's default model set.
PAPER_LPV = "lpv-paper"

_SUMMARY_COLUMNS = (
    "model",
    "kind",
    "n_ok",
    "n_failed",
    "esr_mean",
    "esr_median",
    "esr_q1",
    "esr_q3",
    "ssse_mean",
    "ssse_median",
    "ssse_q1",
    "ssse_q3",
    "esr_gain_of_best_pct",
    "ssse_gain_of_best_pct",
    "fit_time_s",
    "sim_time_s",
)


def improvement_pct(best: float, other: float) -> float:
    """Improvement of ``best`` over ``other`` in percent: ``100 * (other - best) / other``."""
    if not np.isfinite(best) or not np.isfinite(other) or other == 0.0:
        return float("nan")
    return float(100.0 * (other - best) / other)


def summarize(results: pd.DataFrame, order: Sequence[str] | None = None) -> pd.DataFrame:
    """Per-model statistics of a results table.

    Parameters
    ----------
    results : DataFrame
        The per-record table (columns :data:`RESULT_COLUMNS`).
    order : sequence of str, optional
        Model labels in display order (default: order of first appearance).

    Returns
    -------
    DataFrame
        One row per model: ``n_ok``, ``n_failed``, ESR and SSSE mean / median / quartiles [-], [N],
        ``esr_gain_of_best_pct`` and ``ssse_gain_of_best_pct`` (improvement of the model with the
        lowest mean over this one [%]; 0 for the best itself, NaN when undefined), total fit time
        and total simulation time [s].
    """
    labels = list(order) if order is not None else list(dict.fromkeys(results["model"]))
    rows: list[dict[str, Any]] = []
    for label in labels:
        sub = results[results["model"] == label]
        ok = sub[sub["status"] == "ok"]
        row: dict[str, Any] = {
            "model": label,
            "kind": sub["kind"].iloc[0] if len(sub) else "",
            "n_ok": len(ok),
            "n_failed": int(len(sub) - len(ok)),
        }
        for idx in ("esr", "ssse"):
            vals = ok[idx].to_numpy(dtype=float)
            if vals.size:
                row[f"{idx}_mean"] = float(np.mean(vals))
                row[f"{idx}_median"] = float(np.median(vals))
                row[f"{idx}_q1"] = float(np.quantile(vals, 0.25))
                row[f"{idx}_q3"] = float(np.quantile(vals, 0.75))
            else:
                for s in ("mean", "median", "q1", "q3"):
                    row[f"{idx}_{s}"] = float("nan")
        fits = sub.drop_duplicates("fold")["fit_time_s"].to_numpy(dtype=float)
        row["fit_time_s"] = float(np.nansum(fits)) if fits.size else float("nan")
        row["sim_time_s"] = float(np.nansum(sub["sim_time_s"].to_numpy(dtype=float)))
        rows.append(row)
    out = pd.DataFrame(
        rows,
        columns=[
            c
            for c in _SUMMARY_COLUMNS
            if c not in ("esr_gain_of_best_pct", "ssse_gain_of_best_pct")
        ],
    )
    for idx in ("esr", "ssse"):
        means = out[f"{idx}_mean"].to_numpy(dtype=float)
        gains = np.full(len(out), np.nan)
        if np.isfinite(means).any():
            best = float(np.nanmin(means))
            gains = np.array([improvement_pct(best, m) for m in means])
        out[f"{idx}_gain_of_best_pct"] = gains
    return out[list(_SUMMARY_COLUMNS)]


def headline(summary: pd.DataFrame, model: str = "lpv") -> dict[str, Any]:
    """The paper's headline: ``model`` against the best of the paper's classical models.

    The classical models are P-15 and SP-1..SP-4 (:data:`PAPER_CLASSICAL`), as in the paper's
    Section V; every other model's comparison is in the summary's gain columns.

    Parameters
    ----------
    summary : DataFrame
        :func:`summarize` output.
    model : str
        Label of the model compared (LPV by default).

    Returns
    -------
    dict
        ``model``, ``best_classical_esr`` (label), ``esr`` and ``esr_classical`` means,
        ``esr_improvement_pct``; the same for SSSE (the best classical model by SSSE may differ);
        ``available`` False when either side has no successful row (then the text says why).
        ``text`` is a one-line human summary.
    """
    out: dict[str, Any] = {"model": model, "available": False}
    mine = summary[summary["model"] == model]
    classical = summary[summary["kind"].isin(PAPER_CLASSICAL)]
    if mine.empty or not np.isfinite(mine["esr_mean"].iloc[0]):
        out["text"] = f"no successful {model} result: no headline comparison"
        return out
    classical = classical[np.isfinite(classical["esr_mean"].to_numpy(dtype=float))]
    if classical.empty:
        out["text"] = "no successful P-15 / SP-1..SP-4 result: no headline comparison"
        return out
    parts = []
    for idx, unit in (("esr", ""), ("ssse", " N")):
        best = classical.loc[classical[f"{idx}_mean"].idxmin()]
        mine_v = float(mine[f"{idx}_mean"].iloc[0])
        theirs = float(best[f"{idx}_mean"])
        gain = improvement_pct(mine_v, theirs)
        out[f"best_classical_{idx}"] = str(best["model"])
        out[idx] = mine_v
        out[f"{idx}_classical"] = theirs
        out[f"{idx}_improvement_pct"] = gain
        word = "lower" if gain >= 0 else "higher"
        parts.append(
            f"mean {idx.upper()} {mine_v:.4g}{unit} vs {best['model']} {theirs:.4g}{unit} "
            f"({abs(gain):.1f} % {word})"
        )
    out["available"] = True
    out["text"] = f"{model}: " + "; ".join(parts)
    return out


def headlines(summary: pd.DataFrame) -> list[dict[str, Any]]:
    """The headline as the paper states it, then the default's: :func:`headline` of the paper's
    LPV (label :data:`PAPER_LPV`, static input) when the study ran it, then of the default LPV
    (label ``lpv``, hysteretic input).

    Parameters
    ----------
    summary : DataFrame
        :func:`summarize` output.

    Returns
    -------
    list of dict
        One :func:`headline` per LPV the study ran (at least the default's, possibly unavailable).
    """
    labels = set(summary["model"])
    out = [headline(summary, PAPER_LPV)] if PAPER_LPV in labels else []
    return out + [headline(summary, "lpv")]
