"""The report's "Control relevance" section (:mod:`mrdamper.study.control_step`).

With a known truth (virtual rig): predicted against achieved metrics per model and controller,
the worst errors per model and the gains each model's controllers were tuned to on the model
(with what they achieve). On measured data: the statement that no truth is in the loop and the
spread of the models' predictions about their median.
"""

from __future__ import annotations

import html
import re
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.loop.fronts import gap_size
from mrdamper.study.control_step import STUDY_LEVELS, ControlRelevance
from mrdamper.study.report_control_rank import outside_cells, rankings
from mrdamper.study.result import StudyResult

__all__ = ["IMPLAUSIBLE_FACTOR", "control_section", "in_words", "wide_table"]

#: Metrics shown in the report's wide tables (all of them are in ``control.csv``), with a scale
#: and the unit shown.
_SHOWN: dict[str, tuple[float, str]] = {
    "a_w": (1.0, "m/s²"),
    "rms_tyre_load": (1.0, "N"),
    "rms_travel": (1e3, "mm"),
    "mean_current": (1.0, ""),
}
_NAMES = {
    "a_w": "a_w",
    "rms_tyre_load": "tyre load",
    "rms_travel": "travel",
    "mean_current": "mean input",
}


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


#: A prediction off by more than this factor (either way) from what was achieved, or from the
#: models' median without a truth, is flagged in its row as implausible.
IMPLAUSIBLE_FACTOR = 2.0
#: Metrics whose size is compared (the mean input may be near zero, so only its difference counts).
_FLAGGED = ("a_w", "rms_tyre_load", "rms_travel")
#: ``SomeError: `` and an upper-case field (``MODEL: ``) at the start of a stored reason.
_CLASS_NAME = re.compile(r"\b[A-Z][A-Za-z]*(?:Error|Exception|Warning): ")
_FIELD = re.compile(r"(^|: )[A-Z][A-Z_]+: ")


def in_words(reason: str, capital: bool = True) -> str:
    """A stored one-line reason as the user reads it: no exception class names
    (``DataValidationError: MODEL: kind 'lti' has no inverse`` reads ``Kind 'lti' has no
    inverse``), starting with a capital letter unless ``capital`` is False (a note that starts
    with a model's label)."""
    text = _FIELD.sub(r"\1", _CLASS_NAME.sub("", str(reason))).strip()
    return text[:1].upper() + text[1:] if capital else text


def _num(v: float) -> str:
    if not np.isfinite(v):
        return "-"
    return f"{v:.0f}" if abs(v) >= 1000 else f"{v:.3g}"


def _pct(v: float) -> str:
    return f"{v:+.1f} %" if abs(v) < 10 else f"{v:+.0f} %"


def _implausible(name: str, u: str, pred: float, ref: float, truth: bool) -> str:
    """Why ``pred`` is implausible against ``ref`` (achieved, or the median), or ``""``."""
    if not (np.isfinite(pred) and np.isfinite(ref) and ref > 0):
        return ""
    if max(pred / ref, ref / pred if pred > 0 else np.inf) <= IMPLAUSIBLE_FACTOR:
        return ""
    against = "achieved" if truth else "the models' median"
    return (
        f"implausible: {name} predicted {_num(pred)} {u} against {_num(ref)} {u} {against} "
        f"({_pct(100 * (pred - ref) / ref)})"
    )


def wide_table(cr: ControlRelevance, unit: str) -> pd.DataFrame:
    """One row per model, controller, road and speed; per shown metric one cell, ``predicted /
    achieved (error)`` with a truth, else ``predicted (deviation from the median)``; ``note``:
    why the row has no numbers, or which prediction is implausible (off by more than
    :data:`IMPLAUSIBLE_FACTOR`)."""
    t = cr.table
    truth = cr.truth is not None
    rows: list[dict[str, Any]] = []
    order = list(dict.fromkeys(zip(t["model"], t["controller"])))
    for model, ctrl in order:
        part = t[(t["model"] == model) & (t["controller"] == ctrl)]
        if part["metric"].isna().all():  # the pair did not run: one row, its reason
            reasons = part["reason"].dropna() if "reason" in part else pd.Series(dtype=str)
            why = in_words(reasons.iloc[0]) if len(reasons) else "Did not run"
            rows.append({"model": model, "controller": ctrl, "note": why})
            continue
        for (road, sp), g in part[part["metric"].notna()].groupby(
            ["road", "speed_m_s"], sort=False
        ):
            row: dict[str, Any] = {
                "model": model,
                "controller": ctrl,
                "road": f"ISO {road}, {sp:g} m/s",
            }
            notes: list[str] = []
            said = g["reason"].dropna() if "reason" in g else pd.Series(dtype=str)
            if len(said):  # a refused or diverged run of this road
                notes.append(in_words(said.iloc[0]))
            for metric, (scale, u) in _SHOWN.items():
                m = g[g["metric"] == metric]
                if m.empty:
                    continue
                u = u or unit
                pred = scale * float(m["predicted"].iloc[0])
                if truth:
                    ach, err = scale * float(m["achieved"].iloc[0]), float(m["error_pct"].iloc[0])
                    cell = f"{_num(pred)} / {_num(ach)}"
                    ref = ach
                else:
                    err = float(m["vs_median_pct"].iloc[0])
                    cell = _num(pred)
                    ref = pred / (1 + err / 100) if np.isfinite(err) and err > -100 else np.nan
                if np.isfinite(err):
                    cell += f" ({_pct(err)})"
                row[f"{_NAMES[metric]} [{u}]"] = cell
                flag = _implausible(_NAMES[metric], u, pred, ref, truth)
                if metric in _FLAGGED and flag:
                    notes.append(flag)
            row["note"] = "; ".join(notes)
            rows.append(row)
    df = pd.DataFrame(rows)
    cols = [c for c in df.columns if c not in ("model", "controller", "road", "note")]
    return (
        df.reindex(columns=["model", "controller", "road", *cols, "note"]).astype(object).fillna("")
    )


def _worst(cr: ControlRelevance, column: str) -> pd.DataFrame:
    """Largest |``column``| [%] per model and shown metric over controllers and roads."""
    t = cr.table[cr.table["metric"].isin(list(_SHOWN))]
    t = t.assign(abs_pct=t[column].abs())
    out = t.pivot_table(index="model", columns="metric", values="abs_pct", aggfunc="max")
    order = [m for m in dict.fromkeys(cr.table["model"]) if m in out.index]
    out = out.reindex(index=order, columns=[m for m in _SHOWN if m in out.columns])
    return out.rename(columns={m: f"{_NAMES[m]} [%]" for m in _SHOWN}).reset_index()


def _chosen(cr: ControlRelevance) -> pd.DataFrame:
    rows = []
    for label, fr in cr.fronts.items():
        if isinstance(fr, str):
            rows.append({"model": label, "note": in_words(fr)})
            continue
        for r in fr.chosen().to_dict("records"):
            gain = r["c_ground"] if r["controller"] == "groundhook" else r["c_sky"]
            rows.append(
                {
                    "model": label,
                    "controller": r["controller"],
                    "gain [N s/m]": gain,
                    "alpha [-]": r["alpha"],
                    "a_w gain pred. [%]": r["aw_gain_pct_predicted"],
                    "a_w gain ach. [%]": r["aw_gain_pct_achieved"],
                    "tyre gain pred. [%]": r["tyre_gain_pct_predicted"],
                    "tyre gain ach. [%]": r["tyre_gain_pct_achieved"],
                    "note": "",
                }
            )
    return pd.DataFrame(rows).reindex(
        columns=[
            "model",
            "controller",
            "gain [N s/m]",
            "alpha [-]",
            "a_w gain pred. [%]",
            "a_w gain ach. [%]",
            "tyre gain pred. [%]",
            "tyre gain ach. [%]",
            "note",
        ]
    )


def _gaps(cr: ControlRelevance, unit: str) -> pd.DataFrame:
    """Per model with a sweep and metric, the point of the widest model-plant gap
    (:meth:`~mrdamper.control.loop.fronts.FrontsResult.widest_gaps`): one row each, so the table
    stays
    narrow."""
    rows = []
    for label, fr in cr.fronts.items():
        if isinstance(fr, str):
            continue
        for r in fr.widest_gaps().to_dict("records"):
            rows.append(
                {
                    "model": label,
                    "metric": _GAP_NAMES[r["metric"]],
                    "widest gap": gap_size(r, unit),
                    "where": _point(r),
                }
            )
    return pd.DataFrame(rows).reindex(columns=["model", "metric", "widest gap", "where"])


#: Column of :func:`_gaps` per metric.
_GAP_NAMES = {
    "a_w": "a_w error",
    "rms_tyre_load": "tyre load error",
    "rms_travel": "travel error",
    "mean_current": "mean input difference",
}


def _point(r: Mapping[str, Any]) -> str:
    """``skyhook 8000 N s/m``, ``hybrid 3000 N s/m, alpha 0.5`` or ``passive 20 %``."""
    if r["controller"] == "passive":
        return f"passive {r['level']:.0%}"
    gain = r["c_ground"] if r["controller"] == "groundhook" else r["c_sky"]
    alpha = f", alpha {r['alpha']:g}" if r["controller"] == "hybrid" else ""
    return f"{r['controller']} {gain:g} N s/m{alpha}"


def _truth_text(truth: str) -> str:
    if truth == "rig":
        from mrdamper.rig.reference import DEFAULT_REFERENCE

        return f"{DEFAULT_REFERENCE}, the rig's default reference damper"
    return truth.removeprefix("rig:")


def _no_truth(res: StudyResult) -> str:
    if str(res.info.get("data_origin", "")).startswith("virtual rig"):
        return "the virtual rig's damper is not one of the shipped reference dampers"
    return "the records are measured and no model is the real damper"


def _wide_html(wide: pd.DataFrame) -> str:
    """The wide table as HTML that fits the page: each metric cell's error on a line of its own
    under ``predicted / achieved``, the note wrapped (no sideways scrolling at 1280 px)."""
    head = "".join(f"<th>{_e(c)}</th>" for c in wide.columns)
    body = []
    for row in wide.itertuples(index=False):
        cells = []
        for col, v in zip(wide.columns, row):
            text = str(v)
            if col == "note":
                cells.append(f'<td style="white-space:normal;min-width:12em">{_e(text)}</td>')
                continue
            value, _, err = text.partition(" (")
            tail = f'<br><span class="small">{_e(err.rstrip(")"))}</span>' if err else ""
            cells.append(f"<td>{_e(value)}{tail}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return (
        f'<div class="tablewrap"><table class="left"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table></div>"
    )


def _flagged(wide: pd.DataFrame) -> int:
    return int(wide["note"].astype(str).str.contains("implausible: ").sum()) if len(wide) else 0


def _ranking_block(res: StudyResult, cr: ControlRelevance, table: Callable[..., str]) -> str:
    """The open-loop ranking beside the closed-loop one, and the cells outside the envelope."""
    ranks = rankings(res.summary, cr)
    if cr.truth is not None:
        head = (
            "<p><b>Which model for a controller?</b> The open-loop ranking (mean free-run ESR on "
            "the left-out records) beside the closed-loop one (worst |error| of a_w, RMS "
            "acceleration, tyre load, travel and tracking against the rig's damper over the "
            "cells, and apart over those whose loop stays within the model's training "
            "envelope):</p>"
        )
    else:
        head = (
            "<p><b>Which model for a controller?</b> Without the damper in the loop only the "
            "open-loop ranking is known; <code>mrdamper select DATA --for control</code> ranks "
            "the kinds on held-out records of the loop's motions (the control extension, "
            "<code>mrdamper rig doe --extension control</code>):</p>"
        )
    out = [head, table(ranks, cls="left", digits=3)]
    cells = outside_cells(cr)
    if cells:
        out.append(
            f"<details><summary>{len(cells)} cell(s) whose loop leaves the model's training "
            "envelope (their errors extrapolate; records of the loop's motions, <code>mrdamper "
            "rig doe --extension control</code>, bring them in)</summary><ul>"
            + "".join(f"<li>{_e(c)}</li>" for c in cells)
            + "</ul></details>"
        )
    elif cr.truth is not None:
        out.append("<p>Every cell's loop stays within its model's training envelope.</p>")
    return "\n".join(out)


def control_section(res: StudyResult, table: Callable[..., str], unit: str) -> str:
    """HTML of the section; ``table`` renders a DataFrame (the report's table helper)."""
    cr = res.control
    if cr is None:
        return (
            "<p>The control-relevance step was switched off for this study "
            "(<code>run_study(..., control=None)</code>, <code>--no-control</code>).</p>"
        )
    wide = wide_table(cr, unit)
    n_flag = _flagged(wide)
    flags = (
        f" {n_flag} row(s) hold a prediction off by more than a factor "
        f"{IMPLAUSIBLE_FACTOR:g}, flagged <i>implausible</i> in their note."
        if n_flag
        else ""
    )
    how = (
        f"Each model of fold <code>{_e(cr.fold)}</code> is the controller's model (the "
        "semi-active controllers ask its inverse for the input) on the quarter car "
        f"(default car; {_e(cr.settings.describe())}); every run is checked by halving the plant "
        "step. a_w: ISO 2631 weighted RMS body acceleration; tyre load, travel: RMS of the "
        f"dynamic tyre load and suspension travel; mean input [{_e(unit)}]. Every metric, "
        "with RMS acceleration and RMS force tracking, is in <code>control.csv</code>."
    )
    out = []
    if cr.truth is not None:
        out.append(
            "<p><b>The truth is known</b>: what each model promises in the loop against what "
            f"the rig's damper (<code>{_e(_truth_text(cr.truth))}</code>) achieves.{flags}</p>"
        )
        out.append(_wide_html(wide))
        out.append(
            '<p class="small">Each cell: predicted / achieved (error), predicted with the model '
            "as the damper, achieved with the rig's damper driven by the same controller; error "
            f"= 100 (pred. &minus; ach.) / ach. {how}</p>"
        )
        out.append("<p>Largest |error| per model over the controllers and roads:</p>")
        out.append(table(_worst(cr, "error_pct"), digits=3))
        if cr.fronts:
            out.append(
                '<p>Gain fronts (figure <a href="#control_fronts"><code>control_fronts'
                "</code></a>, points in <code>control_fronts/</code>): on the first road, passive "
                f"inputs at {len(STUDY_LEVELS)} levels and a coarse grid of "
                "gains, single runs at the road's step (not checked by halving, unlike the "
                "table above). Each controller's gain is chosen on the model (skyhook: best a_w, "
                "groundhook: best tyre load, hybrid: the mean of both, each as the gain over the "
                "passive front at equal RMS travel, positive = better than passive) and run "
                "with the reference damper:</p>"
            )
            out.append(table(_chosen(cr), cls="left", digits=3))
            gaps = _gaps(cr, unit)
            if len(gaps):
                out.append(
                    "<p>Where on its sweep each model is furthest from the reference damper "
                    "(a_w, tyre load, travel: 100 (pred. &minus; ach.) / ach.; mean input: "
                    "pred. &minus; ach.). A gain chosen on the model is worth what the model "
                    "predicts only where this gap is small:</p>"
                )
                out.append(table(gaps, cls="left"))
    else:
        out.append(
            f"<p><b>No truth is available</b>: {_e(_no_truth(res))}; how much the models "
            f"disagree in the loop.{flags}</p>"
        )
        out.append(_wide_html(wide))
        out.append(
            '<p class="small">Without the real damper in the loop, which model is right cannot '
            "be said. Each cell: the model's predicted metric (its deviation from the median of "
            "the models on the same controller and road, 100 (model &minus; median) / median). "
            f"{how}</p>"
        )
        out.append("<p>Largest |deviation from the median| per model:</p>")
        out.append(table(_worst(cr, "vs_median_pct"), digits=3))
    out.append(_ranking_block(res, cr, table))
    if cr.notes:
        uniq = list(dict.fromkeys(in_words(n, capital=False) for n in cr.notes))
        out.append(
            f"<details><summary>{len(uniq)} warning(s) of the loop runs</summary><ul>"
            + "".join(f"<li>{_e(n)}</li>" for n in uniq)
            + "</ul></details>"
        )
    n_failed = int(np.sum(wide["road"].astype(str) == "")) if "road" in wide else 0
    if n_failed:
        out.append(
            f'<p class="small">{n_failed} model/controller pair(s) could not run; their rows '
            "say why.</p>"
        )
    return "\n".join(out)
