"""The report's tables, as DataFrames whose headers carry their units.

Every function here returns values for :mod:`mrdamper.study.report` to render; nothing is
written. Numbers stay numbers (rounding is the renderer's job, :func:`format_number`), except
comparison cells that read as a sentence ("74.8 % lower").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.study.result import Showcase, StudyResult
from mrdamper.study.selection import SelectionResult
from mrdamper.study.tables import improvement_pct

__all__ = [
    "analysis_table",
    "energy_display",
    "energy_table",
    "esr_by_table",
    "format_number",
    "grouping_keys",
    "laws_table",
    "study_failed_note",
    "summary_table",
]

_ZONES = ("I", "II", "III")


def format_number(v: Any, digits: int = 4) -> str:
    """Text of a table cell: integers as integers, floats to ``digits`` significant digits.

    Examples
    --------
    >>> xs = (1.0000000000000002, 0.024431, 1834.2, 123456.7, 3, float("nan"), 2.5e-6)
    >>> [format_number(x) for x in xs]
    ['1', '0.02443', '1834', '123457', '3', '', '2.5e-06']
    """
    if v is None:
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if not np.isfinite(x):
            return ""
        if x == 0.0:
            return "0"
        mag = int(np.floor(np.log10(abs(x))))
        if not -4 <= mag < 6:
            return f"{x:.{digits}g}"
        text = f"{x:.{max(digits - 1 - mag, 0)}f}"
        return text.rstrip("0").rstrip(".") if "." in text else text
    return str(v)


def _vs(reference: float, other: float) -> str:
    """``reference`` against ``other`` as the paper words it: "51.0 % lower" / "12.0 % higher"."""
    g = improvement_pct(reference, other)
    if not np.isfinite(g):
        return ""
    return f"{abs(g):.1f} % {'lower' if g >= 0 else 'higher'}"


def selection_table(selection: SelectionResult) -> pd.DataFrame:
    """The model-selection table (``mrdamper select``'s columns) with units, for the report.

    Parameters
    ----------
    selection : SelectionResult
        The study's selection (:attr:`StudyResult.selection`).

    Returns
    -------
    DataFrame
        Columns: model, recommended (``yes`` on the recommended row), mean, median and worst ESR
        over the held-out records [-], folds ok / failed, held-out records outside the model's
        identified range and the first failure (no times: the report is the same for the same
        study; fit times are in ``timings.json``).
    """
    t = selection.table
    return pd.DataFrame(
        {
            "model": [str(k) for k in t.index],
            "recommended": ["yes" if k == selection.recommended else "" for k in t.index],
            "ESR mean [-]": t["mean_esr"].to_numpy(),
            "ESR median [-]": t["median_esr"].to_numpy(),
            "ESR worst [-]": t["worst_esr"].to_numpy(),
            "folds ok / failed": [
                f"{int(a)} / {int(b)}" for a, b in zip(t["folds_ok"], t["folds_failed"])
            ],
            "outside range": t["clipped"].astype(int).to_numpy(),
            "failure": [str(x) for x in t["error"]],
        }
    )


def summary_table(
    summary: pd.DataFrame, reference: str = "lpv", failed: dict[str, str] | None = None
) -> pd.DataFrame:
    """Per-model summary for the report, every header with its unit.

    Parameters
    ----------
    summary : DataFrame
        :func:`mrdamper.study.tables.summarize` output.
    reference : str
        Label of the model the comparison columns are about (the headline's model).
    failed : dict, optional
        Label -> reason for models treated as failed (kept as rows, marked in ``status``).

    Returns
    -------
    DataFrame
        Columns: model, status (``ok`` or ``failed``, see ``failed``), scored (ok / failed), mean,
        median and quartiles of ESR [-], mean and quartiles of SSSE [N] (the median is in
        ``summary.csv``), rank by mean ESR, ``<reference> ESR vs this model`` and the same for SSSE
        (the improvement of the reference's mean over the row model's mean, as the headline and
        the paper state it). No times: they go to ``timings.json``, so that the same study gives
        the same report.
    """
    failed = failed or {}
    ref = summary[summary["model"] == reference]
    ref_esr = float(ref["esr_mean"].iloc[0]) if not ref.empty else float("nan")
    ref_ssse = float(ref["ssse_mean"].iloc[0]) if not ref.empty else float("nan")
    ranks = summary["esr_mean"].rank(method="min")
    rows = []
    for k, r in summary.iterrows():
        label = str(r["model"])
        is_ref = label == reference
        rows.append(
            {
                "model": label,
                "status": "failed" if label in failed else "ok",
                "scored (ok / failed)": f"{int(r['n_ok'])} / {int(r['n_failed'])}",
                "ESR mean [-]": r["esr_mean"],
                "ESR median [-]": r["esr_median"],
                "ESR q1-q3 [-]": _span(r["esr_q1"], r["esr_q3"], r["n_ok"]),
                "SSSE mean [N]": r["ssse_mean"],
                "SSSE q1-q3 [N]": _span(r["ssse_q1"], r["ssse_q3"], r["n_ok"]),
                "rank (mean ESR)": int(ranks[k]) if np.isfinite(ranks[k]) else None,
                f"{reference} ESR vs this model": "reference"
                if is_ref
                else _vs(ref_esr, float(r["esr_mean"])),
                f"{reference} SSSE vs this model": "reference"
                if is_ref
                else _vs(ref_ssse, float(r["ssse_mean"])),
            }
        )
    out = pd.DataFrame(rows)
    if ref.empty:
        out = out.drop(columns=[c for c in out.columns if c.endswith(" vs this model")])
    return out


def _natural(x: Any) -> tuple[Any, ...]:
    """Sort key: numbers by value, text with its numbers read as numbers (5mm before 10mm)."""
    import re

    if isinstance(x, (int, float, np.integer, np.floating)):
        return (0, float(x))
    parts = re.split(r"(\d+(?:\.\d+)?)", str(x))
    return (1, *[(0, float(p), "") if k % 2 else (1, 0.0, p) for k, p in enumerate(parts)])


def _span(a: float, b: float, n: Any = 2) -> str:
    """``"a-b"``; ``"-"`` with fewer than two scores (``n`` of them: one has no spread)."""
    if not (np.isfinite(a) and np.isfinite(b)):
        return ""
    if not n >= 2:
        return "-"
    return f"{format_number(a, 3)}\u2013{format_number(b, 3)}"


def grouping_keys(results: pd.DataFrame) -> list[str]:
    """Record metadata columns worth a per-group ESR table: condition or experiment, and current.

    A key qualifies when the results have it and it takes at least two values.
    """
    out = []
    for key in ("condition", "experiment", "current"):
        if key in results.columns and results[key].dropna().nunique() >= 2:
            out.append(key)
    return out


def esr_by_table(
    results: pd.DataFrame, key: str, order: Sequence[str], unit: str = "A"
) -> pd.DataFrame:
    """Mean ESR [-] of each model per value of a metadata column (condition, experiment, current).

    Parameters
    ----------
    results : DataFrame
        The per-record results (with the column ``key``).
    key : str
        Metadata column to group by.
    order : sequence of str
        Model labels in display order.
    unit : str
        Unit of the electrical level, for ``key == "current"`` headers.

    Returns
    -------
    DataFrame
        One row per model, one column per value of ``key`` (mean ESR over its ``ok`` records;
        empty when none), and ``records ok / scored``.
    """
    vals = sorted(results[key].dropna().unique(), key=_natural)
    names: dict[str, Callable[[Any], str]] = {
        "current": lambda x: f"{format_number(x)} {unit}",
        "experiment": lambda x: f"exp {x}",
    }
    head: Callable[[Any], str] = names.get(key, str)
    if key == "experiment" and "pattern" in results.columns:
        pat = results.dropna(subset=["pattern"]).groupby(key)["pattern"].first().to_dict()

        def head(x: Any) -> str:
            return f"exp {x} ({pat[x]})" if x in pat else f"exp {x}"

    rows = []
    for label in order:
        sub = results[results["model"] == label]
        row: dict[str, Any] = {"model": label}
        for v in vals:
            grp = sub[(sub[key] == v) & (sub["status"] == "ok")]
            row[head(v)] = float(grp["esr"].mean()) if len(grp) else float("nan")
        row["records ok / scored"] = f"{int((sub['status'] == 'ok').sum())} / {len(sub)}"
        rows.append(row)
    return pd.DataFrame(rows)


def laws_table(laws: Any, unit: str = "A") -> dict[str, pd.DataFrame]:
    """The fitted laws across current (eq. 18) with their coefficients, one table per quantity.

    ``m_j(i) = gamma_0 + gamma_1 i + gamma_2 i^2`` (the degree of the fit), likewise ``c_j``; the
    zone limit is the straight line ``v_high(i) = gamma_0 + gamma_1 i`` (``v_low = -v_high`` when
    symmetric).

    Returns
    -------
    dict
        Title -> DataFrame: slopes, intercepts and zone limits, one row per zone with the
        coefficients ``gamma_k`` (headers with their units) and the largest distance between the
        per-level fits and the law.
    """
    gm, gc = np.asarray(laws.gamma_m, dtype=float), np.asarray(laws.gamma_c, dtype=float)
    lv = np.asarray(laws.levels, dtype=float)
    m_res = np.abs(np.asarray(laws.level_m) - np.asarray(laws.m(lv))).max(axis=0)
    c_res = np.abs(np.asarray(laws.level_c) - np.asarray(laws.c(lv))).max(axis=0)

    def per(base: str, p: int) -> str:
        if p == 0:
            return base
        den = unit if p == 1 else f"{unit}^{p}"
        return (
            f"{base}/{den}"
            if "/" not in base
            else f"{base.split('/')[0]}/({base.split('/')[1]} {den})"
        )

    out: dict[str, pd.DataFrame] = {}
    for title, name, base, g, res in (
        ("slopes m_j(i) [N s/m]", "m", "N s/m", gm, m_res),
        ("intercepts c_j(i) [N]", "c", "N", gc, c_res),
    ):
        rows = []
        for j in range(3):
            row: dict[str, Any] = {"law": f"{name}{j + 1} (zone {_ZONES[j]})"}
            for p in range(g.shape[1]):
                row[f"gamma_{p} [{per(base, p)}]"] = g[j, p]
            row[f"largest |fit - law| [{base}]"] = res[j]
            rows.append(row)
        out[title] = pd.DataFrame(rows)
    rows = []
    for name, mu, lev in (
        ("v_high", laws.mu_high, laws.level_v_high),
        ("v_low", laws.mu_low, laws.level_v_low),
    ):
        rows.append(
            {
                "law": name,
                "gamma_0 [m/s]": mu[1],
                f"gamma_1 [m/(s {unit})]": mu[0],
                "largest |fit - law| [m/s]": float(
                    np.max(np.abs(np.asarray(lev) - (mu[0] * lv + mu[1])))
                ),
            }
        )
    out["zone limits v(i) [m/s]"] = pd.DataFrame(rows)
    return out


def analysis_table(laws: Any, unit: str = "A") -> pd.DataFrame:
    """Three-zone fit at each level (eq. 17): slopes [N s/m], intercepts [N], zone limits [m/s]."""
    lv = np.asarray(laws.levels, dtype=float)
    df = pd.DataFrame({f"level [{unit}]": lv})
    for j in range(3):
        df[f"m{j + 1} [N s/m]"] = np.asarray(laws.level_m)[:, j]
    for j in range(3):
        df[f"c{j + 1} [N]"] = np.asarray(laws.level_c)[:, j]
    df["v_low [m/s]"] = np.asarray(laws.level_v_low)
    df["v_high [m/s]"] = np.asarray(laws.level_v_high)
    return df


def energy_table(sc: Showcase | None) -> pd.DataFrame:
    """Energy dissipated per displacement cycle on the showcase record, measured and each model.

    Cycles are those of the measured displacement (:func:`mrdamper.analysis.energy_per_cycle`);
    every force is integrated over the same cycles with the measured velocity. A record with
    less than one complete cycle (a random excitation that crosses its mid-range once) is
    integrated whole instead, and says so in ``basis``.

    Returns
    -------
    DataFrame
        Columns ``model``, ``energy_J`` (mean over complete cycles, or over the whole record [J]),
        ``diff_pct`` (relative to the measured force's [%]), ``cycles`` and ``basis``; the first
        row is ``measured``. Empty without a showcase.
    """
    from scipy.integrate import trapezoid

    from mrdamper.analysis import energy_per_cycle

    cols = ["model", "energy_J", "diff_pct", "cycles", "basis"]
    if sc is None:
        return pd.DataFrame(columns=cols)
    e = sc.record

    def energy(F: Any) -> tuple[float, int]:
        W = energy_per_cycle(e.t, e.x, e.v, F)
        if W.size:
            return float(np.mean(W)), int(W.size)
        return float(trapezoid(np.asarray(F, dtype=float) * e.v, e.t)), 0

    W0, n0 = energy(e.F)
    basis = f"mean of {n0} cycles" if n0 else "whole record (less than one complete cycle)"
    rows: list[dict[str, Any]] = [
        {"model": "measured", "energy_J": W0, "diff_pct": 0.0, "cycles": n0, "basis": basis}
    ]
    for label, F in sc.predictions.items():
        if isinstance(F, str):
            rows.append(
                {
                    "model": label,
                    "energy_J": float("nan"),
                    "diff_pct": float("nan"),
                    "cycles": n0,
                    "basis": "no prediction",
                }
            )
            continue
        Wm, _ = energy(F)
        rows.append(
            {
                "model": label,
                "energy_J": Wm,
                "diff_pct": 100.0 * (Wm - W0) / abs(W0) if W0 else float("nan"),
                "cycles": n0,
                "basis": basis,
            }
        )
    return pd.DataFrame(rows, columns=cols)


def energy_display(tab: pd.DataFrame, failed: dict[str, str] | None = None) -> pd.DataFrame:
    """:func:`energy_table` with headers carrying units and the failed models marked."""
    failed = failed or {}
    per_cycle = bool(len(tab)) and int(tab["cycles"].iloc[0]) > 0
    out = tab.drop(columns=["cycles"]).rename(
        columns={
            "energy_J": "energy per cycle [J]" if per_cycle else "energy over the record [J]",
            "diff_pct": "model - measured [%]",
        }
    )
    out.insert(
        1,
        "status",
        ["" if m == "measured" else ("failed" if m in failed else "ok") for m in tab["model"]],
    )
    return out


def study_failed_note(res: StudyResult, failed: dict[str, str]) -> str:
    """One sentence naming the models drawn apart in the shared figures (empty when none)."""
    if not failed:
        return ""
    return (
        "Drawn in panels of their own (own force scale), never overlaid: "
        + "; ".join(f"{k} ({v})" for k, v in failed.items())
        + ". Their rows stay in every table."
    )
