"""The report's "Control relevance" section (:mod:`mrdamper.study.control_step`).

With a known truth (virtual rig): predicted against achieved metrics per model and controller,
the worst errors per model and the gains each model's controllers were tuned to on the model
(with what they achieve). On measured data: the statement that no truth is in the loop and the
spread of the models' predictions about their median.
"""

from __future__ import annotations

import html
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.fronts import gap_size
from mrdamper.study.control_step import STUDY_LEVELS, ControlRelevance
from mrdamper.study.result import StudyResult

__all__ = ["control_section", "wide_table"]

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


def wide_table(cr: ControlRelevance, unit: str) -> pd.DataFrame:
    """One row per model, controller, road and speed; per shown metric the predicted value and,
    with a truth, the achieved one and the error [%], else the deviation from the median [%]."""
    t = cr.table
    keys = ["model", "controller", "road", "speed_m_s"]
    ok = t[t["metric"].notna()]
    rows: list[dict[str, Any]] = []
    order = list(dict.fromkeys(zip(t["model"], t["controller"])))
    for model, ctrl in order:
        part = t[(t["model"] == model) & (t["controller"] == ctrl)]
        reasons = part["reason"].dropna()
        if len(reasons):
            rows.append({"model": model, "controller": ctrl, "reason": str(reasons.iloc[0])})
            continue
        sub = ok[(ok["model"] == model) & (ok["controller"] == ctrl)]
        for (road, sp), g in sub.groupby(["road", "speed_m_s"], sort=False):
            row: dict[str, Any] = {
                "model": model,
                "controller": ctrl,
                "road": road,
                "speed_m_s": sp,
            }
            for metric, (scale, u) in _SHOWN.items():
                m = g[g["metric"] == metric]
                if m.empty:
                    continue
                name = f"{_NAMES[metric]} [{u or unit}]"
                row[f"{name} pred."] = scale * m["predicted"].iloc[0]
                if cr.truth is not None:
                    row[f"{name} ach."] = scale * m["achieved"].iloc[0]
                    row[f"{_NAMES[metric]} error [%]"] = m["error_pct"].iloc[0]
                else:
                    row[f"{_NAMES[metric]} vs median [%]"] = m["vs_median_pct"].iloc[0]
            row["reason"] = ""
            rows.append(row)
    df = pd.DataFrame(rows)
    cols = [c for c in df.columns if c not in ("reason", *keys)]
    return df.reindex(columns=[*keys, *cols, "reason"]).rename(columns={"speed_m_s": "speed [m/s]"})


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
            rows.append({"model": label, "reason": fr})
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
                    "reason": "",
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
            "reason",
        ]
    )


def _gaps(cr: ControlRelevance, unit: str) -> pd.DataFrame:
    """Per model with a sweep, the point of the widest model-plant gap per metric
    (:meth:`~mrdamper.control.fronts.FrontsResult.widest_gaps`)."""
    rows = []
    for label, fr in cr.fronts.items():
        if isinstance(fr, str):
            continue
        row: dict[str, Any] = {"model": label}
        for r in fr.widest_gaps().to_dict("records"):
            row[_GAP_NAMES[r["metric"]]] = f"{gap_size(r, unit)} ({_point(r)})"
        rows.append(row)
    return pd.DataFrame(rows).reindex(columns=["model", *_GAP_NAMES.values()])


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


def control_section(res: StudyResult, table: Callable[..., str], unit: str) -> str:
    """HTML of the section; ``table`` renders a DataFrame (the report's table helper)."""
    cr = res.control
    if cr is None:
        return (
            "<p>The control-relevance step was switched off for this study "
            "(<code>run_study(..., control=None)</code>, <code>--no-control</code>).</p>"
        )
    how = (
        f"Each model of fold <code>{_e(cr.fold)}</code> is the controller's model (the "
        "semi-active controllers ask its inverse for the input) on the quarter car "
        f"(default car; {_e(cr.settings.describe())}); every run is checked by halving the plant "
        "step. a_w: ISO 2631 weighted RMS body acceleration; tyre load, travel: RMS of the "
        f"dynamic tyre load and suspension travel; mean input [{_e(unit)}]. Every metric, "
        "with RMS acceleration and RMS force tracking, is in <code>control.csv</code>."
    )
    wide = wide_table(cr, unit)
    out = []
    if cr.truth is not None:
        out.append(
            f"<p><b>The truth is known</b>: the records come from the virtual rig, whose damper "
            f"(<code>{_e(_truth_text(cr.truth))}</code>) each controller also drives in the car. "
            "<i>pred.</i>: the model as the damper (what the model promises); "
            "<i>ach.</i>: the reference damper (what the controller achieves); error = 100 "
            f"(pred. &minus; ach.) / ach. {how}</p>"
        )
        out.append(table(wide, cls="left"))
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
            f"<p><b>No truth is available</b>: {_e(_no_truth(res))}, so the loop cannot say "
            "which model's prediction is right. What it shows is "
            "how much the models disagree with one another in the loop: each model's predicted "
            "metric against the median of the models on the same controller and road, "
            f"<i>vs median</i> = 100 (model &minus; median) / median. {how}</p>"
        )
        out.append(table(wide, cls="left"))
        out.append("<p>Largest |deviation from the median| per model:</p>")
        out.append(table(_worst(cr, "vs_median_pct"), digits=3))
    if cr.notes:
        uniq = list(dict.fromkeys(cr.notes))
        out.append(
            f"<details><summary>{len(uniq)} warning(s) of the loop runs</summary><ul>"
            + "".join(f"<li>{_e(n)}</li>" for n in uniq)
            + "</ul></details>"
        )
    n_failed = int(np.sum(wide["reason"].astype(str) != "")) if "reason" in wide else 0
    if n_failed:
        out.append(
            f'<p class="small">{n_failed} model/controller pair(s) could not run; their rows '
            "give the reason.</p>"
        )
    return "\n".join(out)
