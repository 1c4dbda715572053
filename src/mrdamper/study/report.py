"""``report.html``: one self-contained page (no external files, scripts or fonts) with the protocol,
the tables and every figure embedded as a base64 PNG, readable offline in any browser.

Layout rules: the page is at most 1100 px wide; every table sits in a box that scrolls sideways when
the table is wider than the page (the page itself never does); figures are shown at the size they
are drawn for print (at most 7 in wide) and shrink with a narrower window. Numbers are rounded to
four significant digits (:func:`~mrdamper.study.report_tables.format_number`). The wording depends
on the data: records from the virtual rig (whose damper is a known model) or measured ones
(:func:`~mrdamper.study.runner.data_origin`).
"""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from mrdamper import kinds
from mrdamper.study.figures import (
    FIGURE_DPI,
    FIGURES,
    failed_models,
    overlay_models,
    time_window,
)
from mrdamper.study.provenance import records_text
from mrdamper.study.report_control import control_section
from mrdamper.study.report_tables import (
    analysis_table,
    energy_display,
    energy_table,
    esr_by_table,
    format_number,
    grouping_keys,
    laws_table,
    selection_table,
    study_failed_note,
    summary_table,
)
from mrdamper.study.result import StudyResult
from mrdamper.study.tables import PAPER_HEADLINE, TIMING_COLUMNS

__all__ = ["figure_captions", "render_report"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;max-width:1100px;\
margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em}\
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.8em}
h3{font-size:1.05em;margin:1.2em 0 .3em}
.tablewrap{max-width:100%;overflow-x:auto;margin:.6em 0}
table{border-collapse:collapse;font-size:.85em}\
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right;
vertical-align:top}
th{background:#f2f2f2;font-weight:600}td{white-space:nowrap}\
td:first-child,th:first-child{text-align:left}
.left td,.left th{text-align:left}\
td.text{text-align:left;white-space:normal;min-width:14em;max-width:40em;overflow-wrap:anywhere}
.headline{background:#f5f9ff;border-left:4px solid #3b73b9;padding:.6em 1em;font-size:1.05em}
.warn{background:#fff6e5;border-left:4px solid #e0a020;padding:.4em 1em}
figure{margin:1.4em 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}
figcaption{font-size:.9em;color:#333;max-width:7in}
code{background:#f4f4f4;padding:0 .25em;overflow-wrap:anywhere}details{margin:.6em 0}\
.small{font-size:.85em;color:#555}
pre{white-space:pre-wrap;overflow-wrap:anywhere}
@media print{body{max-width:none;margin:0}.tablewrap{overflow:visible}table{font-size:7.5pt}
figure{break-inside:avoid}details{display:block}}
"""

#: Columns whose cells are free text (wrapped, left-aligned).
_TEXT_COLUMNS = frozenset(
    {"error", "note", "first_error", "example", "status", "reason", "failure"}
)


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _table(df: pd.DataFrame, cls: str = "", digits: int = 4) -> str:
    """HTML table in a sideways-scrolling box; numbers to ``digits`` significant digits."""
    head = "".join(f"<th>{_e(c)}</th>" for c in df.columns)
    text_cols = [str(c) in _TEXT_COLUMNS for c in df.columns]
    body = []
    for row in df.itertuples(index=False):
        cells = []
        for v, is_text in zip(row, text_cols):
            attr = ' class="text"' if is_text and isinstance(v, str) and len(v) > 30 else ""
            cells.append(f"<td{attr}>{_e(format_number(v, digits))}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return (
        f'<div class="tablewrap"><table class="{cls}"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table></div>"
    )


def _unit(res: StudyResult) -> str:
    return "A" if res.protocol.input == "i" else "V"


def _virtual(res: StudyResult) -> bool:
    return str(res.info.get("data_origin", "")).startswith("virtual rig")


def _model_text(p: Any, spec: Any) -> str:
    settings = p.settings_for(spec)
    extra = [spec.kind] if spec.label != spec.kind else []
    extra += [f"{k}={v!r}" for k, v in settings.items()]
    which = kinds.input_text(spec.kind, settings)
    if which:
        extra.append(f"input: {which}")
    return str(spec.label) + (f" ({', '.join(extra)})" if extra else "")


def _protocol_section(res: StudyResult) -> str:
    p = res.protocol
    rows = [
        ("name", p.name),
        ("description", p.description or "-"),
        ("data", res.info.get("data_origin", "not recorded")),
        ("electrical input", p.input),
        (
            "force-velocity analysis records",
            "none" if p.analysis is None else p.analysis.describe(),
        ),
        ("identification records", p.train.describe()),
        ("scored records", p.score.describe()),
        ("split", p.split.describe()),
        ("records used in training are not scored", "yes" if p.exclude_trained else "no"),
        ("out-of-range policy when scoring", p.range_policy),
        ("models", ", ".join(_model_text(p, s) for s in res.specs)),
    ]
    out = ['<div class="tablewrap"><table class="left">']
    out += [f'<tr><th>{_e(k)}</th><td class="text">{_e(v)}</td></tr>' for k, v in rows]
    out.append("</table></div>")
    roles = res.roles.groupby(["fold", "role"], sort=False).agg(
        records=("record", "count"), samples=("samples", "sum")
    )
    roles = roles.reset_index().rename(columns={"samples": "samples [-]"})
    out.append("<p>Records per role and fold:</p>" + _table(roles))
    ov = res.overlap()
    if ov.empty:
        out.append(
            "<p><b>Train/score overlap:</b> none. No scored record trained a model or the analysis "
            "in its fold: every score is on unseen data.</p>"
        )
    else:
        out.append(
            f'<p class="warn"><b>Train/score overlap:</b> {len(ov)} scored record(s) also trained '
            "in the same fold; their scores are not on unseen data:</p>" + _table(ov)
        )
    out.append(
        "<details><summary>protocol file (JSON)</summary><pre>"
        + _e(p.to_json())
        + "</pre></details>"
    )
    return "\n".join(out)


def _headline_text(res: StudyResult) -> tuple[str, str]:
    hls = res.headlines()
    cls = "headline" if any(h.get("available") for h in hls) else "warn"
    lines = []
    for h in hls:
        spec = next((s for s in res.specs if s.label == h["model"]), None)
        which = (
            kinds.input_text(spec.kind, res.protocol.settings_for(spec)) if spec is not None else ""
        )
        lines.append(_e(h["text"]) + (f" (input: {_e(which)})" if which else ""))
    text = (
        "<b>Headline</b> (LPV against the best of the paper's classical models, P-15 and "
        "SP-1..SP-4; the paper's LPV first, as the paper compares it, then the default's): "
        + "; ".join(lines)
        + ". "
        + _e(PAPER_HEADLINE["text"])
    )
    return cls, text


def _data_note(res: StudyResult) -> str:
    origin = str(res.info.get("data_origin", ""))
    if _virtual(res):
        damper = (
            origin[origin.find("(") + 1 : origin.rfind(" damper)")] if "(" in origin else "a known"
        )
        what = (
            "reference model (its kind is not recorded in the files)"
            if damper == "unknown"
            else f"{damper} model"
        )
        note = (
            f"The records come from the virtual rig, whose damper is a {what} with noise and "
            "sensor dynamics added."
        )
        if damper == "spencer":
            note += (
                " The <code>spencer</code> estimator therefore has the true structure here: it is "
                "a reference, not a competitor."
            )
        return note
    return (
        "The records are measured data: no model has the damper's true structure. Spencer, "
        "Bingham and NARX are extra reference models beside the paper's (LPV, P-15, SP-1..SP-4, "
        "LTI)."
    )


def _summary_section(res: StudyResult, summary: pd.DataFrame, failed: dict[str, str]) -> str:
    cls, text = _headline_text(res)
    out = [f'<p class="{cls}">{text}</p>']
    ref = res.headline().get("model", "lpv")
    out.append(_table(summary_table(summary, ref, failed)))
    if failed:
        out.append(
            '<p class="small">Failed: '
            + "; ".join(f"<b>{_e(k)}</b>: {_e(v)}" for k, v in failed.items())
            + ".</p>"
        )
    out.append(
        '<p class="small">ESR (eq. 24, mean squared error over the variance of the measured '
        "force) [-] and SSSE "
        "(eq. 23, an RMS error) [N] over the scored records with status <code>ok</code>; q1-q3 is "
        "the interquartile range (- for a single score, which has no spread). "
        f"<i>{_e(ref)} ESR vs this model</i>: how much lower (or higher) "
        f"{_e(ref)}'s mean ESR is than the row model's mean, 100 (other - "
        + _e(ref)
        + ") / other, the way the headline and the "
        "paper state 51 % and 36.8 %; likewise for SSSE. A model whose mean ESR exceeds 1 (an "
        "error larger than the signal) or that never simulated is marked failed; its row stays. "
        "Fit and simulation times are in <code>timings.csv</code> and <code>timings.json</code>, "
        "not here: the same study gives the same report, byte for byte. " + _data_note(res) + "</p>"
    )
    return "\n".join(out)


def _selection_section(res: StudyResult) -> str:
    sel = res.selection
    if sel is None:
        return "<p>No model-selection table: this study result carries none.</p>"
    n_scores = len(sel.scores)
    rec = (
        f"<p><b>Recommended: {_e(sel.recommended)}.</b> {_e(sel.reason)}.</p>"
        if sel.recommended is not None
        else f"<p><b>No recommendation:</b> {_e(sel.reason)}.</p>"
    )
    return "\n".join(
        [
            rec,
            _table(selection_table(sel)),
            (
                '<p class="small">The table of <code>mrdamper select</code>, computed from this '
                "study's "
                f"own held-out scores ({n_scores} model &times; record scores over the protocol's "
                f"{sel.n_folds} {_e(sel.split)} fold(s)), not by fitting again: only scored "
                "records that trained neither the models nor the analysis of their fold count. "
                "ESR in free run [-]; a model whose fit or any held-out simulation failed in a "
                "fold fails that fold and is not recommended. The recommendation is the lowest "
                "mean ESR among the models that passed every fold, as <code>mrdamper "
                "select</code> decides (models within 5 % of it tie, and the one with the lowest "
                "worst held-out record is recommended when that record is more than 5 % lower). "
                "<i>Outside "
                "range</i>: held-out records whose electrical input leaves the range the model "
                "was identified on (handled by the protocol's range policy, "
                f"<code>{_e(res.protocol.range_policy)}</code>). <code>mrdamper select</code> "
                "itself chooses its own folds (by condition, record or time) and clips "
                "out-of-range inputs, so its numbers can differ.</p>"
            ),
        ]
    )


def _by_group_section(res: StudyResult) -> str:
    keys = grouping_keys(res.results)
    if not keys:
        return (
            "<p>The scored records carry no condition, experiment or current metadata with two or "
            "more values, so there is no breakdown; every row is in the table at the end.</p>"
        )
    titles = {
        "condition": "Mean ESR [-] per test condition (amplitude and frequency)",
        "experiment": "Mean ESR [-] per experiment (Table II)",
        "current": f"Mean ESR [-] per current level [{_unit(res)}]",
    }
    out = []
    for key in keys:
        out.append(
            f"<h3>{_e(titles[key])}</h3>"
            + _table(esr_by_table(res.results, key, res.labels, _unit(res)), digits=3)
        )
    if "current" not in keys:
        out.append(
            '<p class="small">No per-current table: the scored records have no constant current '
            "level "
            "(the current varies within each record).</p>"
        )
    return "\n".join(out)


def _failures_section(res: StudyResult) -> str:
    fits = res.fits[["fold", "model", "status", "n_train", "train_samples", "error", "note"]]
    fits = fits.rename(
        columns={
            "n_train": "training records",
            "train_samples": "training samples",
        }
    )
    out = ["<p>Identification, one row per fold and model:</p>", _table(fits, cls="left")]
    bad = res.results[res.results["status"] != "ok"]
    if bad.empty:
        out.append("<p>Every simulation of every scored record succeeded.</p>")
    else:
        grp = bad.groupby(["model", "status"], sort=False).agg(
            rows=("record", "count"), first_error=("error", "first")
        )
        out.append(
            f"<p>{len(bad)} row(s) without scores (kept in <code>results.csv</code>):</p>"
            + _table(grp.reset_index(), cls="left")
        )
    notes = res.results[(res.results["status"] == "ok") & (res.results["note"].astype(str) != "")]
    if not notes.empty:
        out.append(
            "<p>Warnings while simulating (e.g. extrapolation outside the identified range), the "
            "same warning of several models on one row:</p>"
            + _table(_merged_notes(notes), cls="left")
        )
    return "\n".join(out)


def _merged_notes(notes: pd.DataFrame) -> pd.DataFrame:
    """One row per distinct warning (the model's name taken out of its text): the models that
    gave it, the number of result rows and one example."""
    first = notes.groupby("model", sort=False).agg(rows=("record", "count"), note=("note", "first"))
    merged: dict[str, dict[str, Any]] = {}
    for model, row in first.iterrows():
        key = str(row["note"]).replace(f" {model} ", " <model> ")
        slot = merged.setdefault(key, {"models": [], "rows": 0})
        slot["models"].append(str(model))
        slot["rows"] += int(row["rows"])
    return pd.DataFrame(
        [
            {"models": ", ".join(v["models"]), "rows": v["rows"], "example": k}
            for k, v in merged.items()
        ]
    )


def _laws_users_note(an: Any, users: Mapping[str, str]) -> str:
    """Which model of the study uses which laws of fold analysis ``an`` ("" when none does)."""
    if not users:
        return ""
    post: Any = getattr(an, "post_yield_laws", None)
    has_post = post is not None and hasattr(post, "m")
    paper = [k for k, v in users.items() if v == "zones" or not has_post]
    post_users = [k for k, v in users.items() if v == "post-yield" and has_post]
    parts = []
    if paper:
        parts.append(f"These are the paper's laws; {_e(', '.join(paper))} use(s) them.")
    if post_users:
        lv = np.asarray(an.laws.levels, dtype=float)
        parts.append(
            f"{_e(', '.join(post_users))} use(s) the same laws with each level's outer slopes "
            "re-estimated on its post-yield samples (beyond three zone limits, "
            '<code>outer_slopes="post-yield"</code>): m3 '
            + ", ".join(f"{a:.4g}" for a in post.m(lv)[:, 2])
            + " N s/m at the levels above, against "
            + ", ".join(f"{a:.4g}" for a in an.laws.m(lv)[:, 2])
            + "."
        )
    return '<p class="small">' + " ".join(parts) + "</p>"


def _analysis_section(res: StudyResult) -> str:
    from mrdamper.study.runner import laws_users

    unit = _unit(res)
    users = laws_users(res.protocol)
    out = []
    shown = 0
    for fold, an in res.analyses.items():
        if an.laws is None or not hasattr(an.laws, "levels"):
            out.append(f"<p>Fold <code>{_e(fold)}</code>: {_e(an.error or 'no analysis')}</p>")
            continue
        body = [
            (
                f"<p>{len(an.fits)} level(s), grouped by {_e(an.by)}. Fitted laws across current "
                "(eq. 18), with the largest distance of a per-level fit from its law:</p>"
            )
        ]
        for title, df in laws_table(an.laws, unit).items():
            body.append(f"<p><b>{_e(title)}</b></p>" + _table(df))
        body.append(
            "<p>Three-zone fit (eq. 17) at each level:</p>" + _table(analysis_table(an.laws, unit))
        )
        if users:
            body.append(_laws_users_note(an, users))
        if an.notes:
            body.append(f'<p class="small">Warnings of the analysis: {_e(an.notes)}</p>')
        if shown == 0:
            out.append(f"<h3>Fold <code>{_e(fold)}</code></h3>" + "\n".join(body))
        else:
            out.append(
                f"<details><summary>Fold <code>{_e(fold)}</code></summary>"
                + "\n".join(body)
                + "</details>"
            )
        shown += 1
    out.append(
        '<p class="small">Every fold\'s laws are also in '
        "<code>analysis/&lt;fold&gt;_zone_laws.json</code>.</p>"
    )
    return "\n".join(out)


def _record_text(res: StudyResult, which: str) -> str:
    sc = res.showcase if which == "showcase" else res.hysteresis
    if sc is None:
        return ""
    el = np.asarray(sc.record.electrical(res.protocol.input), dtype=float)
    lo, hi = float(np.min(el)), float(np.max(el))
    unit = _unit(res)
    level = (
        f"{res.protocol.input} from {lo:.3g} to {hi:.3g} {unit}"
        if hi - lo > 0.05 * max(abs(hi), 1e-9)
        else f"{res.protocol.input} = {float(np.mean(el)):.3g} {unit}"
    )
    why = (
        "the protocol's choice"
        if (res.protocol.showcase if which == "showcase" else res.protocol.hysteresis_record)
        else (
            "the scored record with varying current if any, else the highest current level and "
            "widest velocity range"
        )
    )
    t = sc.record.t
    win = time_window(sc)
    shown = (
        f"drawn from t = {win[0]:.3g} to {win[1]:.3g} s (the middle {win[1] - win[0]:.3g} s of "
        f"{float(t[-1] - t[0]):.3g} s)"
        if win is not None
        else f"drawn whole, t = {float(t[0]):.3g} to {float(t[-1]):.3g} s"
    )
    return (
        f"Record <code>{_e(sc.record.name)}</code> ({_e(level)}; fold {_e(sc.fold)}; {_e(why)}; "
        f"{_e(shown)})."
    )


def figure_captions(res: StudyResult, failed: dict[str, str] | None = None) -> dict[str, str]:
    """Caption (HTML) of each figure for this study: the base text plus what depends on the data."""
    failed = failed_models(res) if failed is None else failed
    caps = {name: _e(text) for name, (_, text) in FIGURES.items()}
    caps["fig06_lpv_tracking"] += " " + _record_text(res, "showcase")
    caps["fig04_lti_hysteresis"] += " " + _record_text(res, "hysteresis")
    over = overlay_models(res, failed) if res.showcase is not None else []
    rule = (
        f" {_record_text(res, 'showcase')} Top: the measured force with "
        f"{_e(', '.join(over) or 'no model')} (rule: LPV, the best of the paper's classical models "
        "and the best other model by mean ESR over the study, none of them failed). Below: every "
        "model in its own panel on a shared force scale, with its ESR on this record."
    )
    if failed:
        rule += (
            " Failed models ("
            + _e(", ".join(failed))
            + ") have a panel of their own with their own force "
            "scale, outlined in red."
        )
    for name in ("fig09_force_time", "fig10_fv_models", "fig11_fx_loops"):
        caps[name] += rule
    if _virtual(res):
        caps["fig01_fv_map"] += " Virtual rig records."
    return caps


def _figures_section(res: StudyResult, saved: Mapping[str, Any], failed: dict[str, str]) -> str:
    out = []
    skipped = []
    caps = figure_captions(res, failed)
    number = 0
    for name, (paper, _) in FIGURES.items():
        item = saved.get(name)
        if item is None:
            continue
        ref = f"paper Fig. {paper}" if paper is not None else "not in the paper"
        if isinstance(item, str):
            skipped.append(
                f'<li id="{_e(name)}">{_e(ref[0].upper() + ref[1:])}: {_e(FIGURES[name][1])} '
                f'<span class="warn">Not drawn: {_e(item)}</span></li>'
            )
            continue
        number += 1
        label = f"<b>Figure {number}</b> ({ref})."
        png = Path(item["png"]).read_bytes()
        data = base64.b64encode(png).decode("ascii")
        width_in = (
            int.from_bytes(png[16:20], "big") / FIGURE_DPI
        )  # IHDR width [px] at the saved resolution
        out.append(
            f'<figure id="{_e(name)}"><img src="data:image/png;base64,{data}" '
            f'style="width:{width_in:.2f}in" alt="Figure {number}: {_e(FIGURES[name][1])}">'
            f"<figcaption>{label} {caps[name]} (<code>figures/{_e(name)}.png</code>, "
            "<code>.svg</code>)</figcaption></figure>"
        )
        if name == "fig11_fx_loops":
            tab = energy_table(res.showcase)
            if not tab.empty:
                out.append(
                    "<p>Energy dissipated on this record, W = &int; F v dt: the mean over the "
                    "complete cycles of the measured displacement, or the whole record when it "
                    "holds less than one (every force integrated over the same cycles with the "
                    "measured velocity):</p>" + _table(energy_display(tab, failed), digits=3)
                )
    if skipped:
        out.insert(
            0, "<p>Figures that this study cannot draw:</p><ul>" + "".join(skipped) + "</ul>"
        )
    if not out:
        return "<p>Figures were not requested.</p>"
    note = study_failed_note(res, failed)
    if note:
        out.insert(0, f'<p class="warn">{_e(note)}</p>')
    return "\n".join(out)


def _provenance_section(info: Mapping[str, Any]) -> str:
    """The mrdamper version, commit and settings of the study (also in ``study.json``)."""
    prov = info.get("provenance") or {}
    settings = dict(prov.get("settings") or {})
    models = settings.pop("models", {})
    rows = [
        ("mrdamper", prov.get("mrdamper_version", "not recorded")),
        ("commit", prov.get("git_commit") or "not run from a git checkout"),
        *((k.replace("_", " "), v) for k, v in settings.items()),
        *(
            (f"model {label}", ", ".join(f"{k}={v!r}" for k, v in spec.items()))
            for label, spec in models.items()
        ),
    ]
    body = "".join(f'<tr><th>{_e(k)}</th><td class="text">{_e(v)}</td></tr>' for k, v in rows)
    return (
        "<details><summary>Provenance: mrdamper "
        f"{_e(prov.get('mrdamper_version', '?'))}, commit "
        f"{_e((prov.get('git_commit') or 'none')[:12])}, settings</summary>"
        f'<div class="tablewrap"><table class="left">{body}</table></div></details>'
    )


def render_report(res: StudyResult, summary: pd.DataFrame, saved: Mapping[str, Any]) -> str:
    """Return the HTML text of the report.

    Parameters
    ----------
    res : StudyResult
        The study.
    summary : DataFrame
        Its per-model summary.
    saved : mapping
        Figure name -> ``{"png": path, "svg": path}`` or the reason it was not drawn.
    """
    info = res.info
    failed = failed_models(res)
    what = records_text(info.get("n_records", "?"), str(info.get("data_origin", "")))
    title = f"Which damper model? {len(res.specs)} models compared on {what}"
    results_cols = [c for c in res.results.columns if c not in ("note", *TIMING_COLUMNS)]
    all_rows = res.results[results_cols].rename(
        columns={
            "esr": "ESR [-]",
            "ssse": "SSSE [N]",
            "nrmse": "NRMSE [-]",
            "fit_pct": "fit [%]",
            "current": f"current [{_unit(res)}]",
            "amplitude": "amplitude [m]",
            "frequency": "frequency [Hz]",
        }
    )
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1>",
        (
            f'<p class="small">Protocol <code>{_e(res.protocol.name)}</code>: '
            f"{_e(res.protocol.description or 'no description')} {_e(info.get('n_folds', '?'))} "
            f"fold(s); seed {_e(info.get('seed'))}; run on {_e(info.get('executor', '?'))}.</p>"
        ),
        _provenance_section(info),
        "<h2>Summary</h2>",
        _summary_section(res, summary, failed),
        "<h2>Which model for this damper?</h2>",
        _selection_section(res),
        "<h2>Control relevance</h2>",
        control_section(res, _table, _unit(res)),
        "<h2>ESR per condition and per current level</h2>",
        _by_group_section(res),
        "<h2>Protocol</h2>",
        _protocol_section(res),
        "<h2>Figures</h2>",
        _figures_section(res, saved, failed),
        "<h2>Identification and failures</h2>",
        _failures_section(res),
        "<h2>Force-velocity analysis and fitted laws</h2>",
        _analysis_section(res),
        "<h2>All results</h2>",
        (
            f"<details><summary>{len(res.results)} rows (also in "
            "<code>results.csv</code>)</summary>" + _table(all_rows, cls="left") + "</details>"
        ),
        (
            f'<p class="small">Python {_e(info.get("python", ""))} on '
            f"{_e(info.get('platform', ''))}. Files next to "
            "this report: results.csv, summary.csv, fits.csv, roles.csv, protocol.json, "
            "study.json, control.csv, control_fronts/ (when the control step ran), models/, "
            "analysis/, figures/.</p>"
        ),
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"
