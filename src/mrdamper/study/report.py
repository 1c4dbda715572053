"""``report.html``: one self-contained page (no external files, scripts or fonts) with the protocol,
the tables and every figure embedded as a base64 PNG, readable offline in any browser."""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from mrdamper.study.figures import FIGURES

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.study.result import StudyResult

__all__ = ["render_report"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.8em}
table{border-collapse:collapse;font-size:.85em;margin:.6em 0}th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right}
th{background:#f2f2f2}td:first-child,th:first-child{text-align:left}.left td{text-align:left}
.headline{background:#f5f9ff;border-left:4px solid #3b73b9;padding:.6em 1em;font-size:1.05em}
.warn{background:#fff6e5;border-left:4px solid #e0a020;padding:.4em 1em}
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.9em;color:#444}
code{background:#f4f4f4;padding:0 .25em}details{margin:.6em 0}.small{font-size:.85em;color:#555}
"""


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _table(df: pd.DataFrame, floatfmt: str = "{:.4g}", cls: str = "") -> str:
    def fmt(v: Any) -> str:
        if isinstance(v, (float, np.floating)):
            return "" if not np.isfinite(v) else floatfmt.format(v)
        return "" if v is None else str(v)

    head = "".join(f"<th>{_e(c)}</th>" for c in df.columns)
    body = "".join("<tr>" + "".join(f"<td>{_e(fmt(v))}</td>" for v in row) + "</tr>" for row in df.itertuples(index=False))
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def _model_text(p: Any, spec: Any) -> str:
    settings = p.settings_for(spec)
    extra = [spec.kind] if spec.label != spec.kind else []
    extra += [f"{k}={v!r}" for k, v in settings.items()]
    return spec.label + (f" ({', '.join(extra)})" if extra else "")


def _protocol_section(res: StudyResult) -> str:
    p = res.protocol
    rows = [
        ("name", p.name),
        ("description", p.description or "-"),
        ("electrical input", p.input),
        ("force-velocity analysis records", "none" if p.analysis is None else p.analysis.describe()),
        ("identification records", p.train.describe()),
        ("scored records", p.score.describe()),
        ("split", p.split.describe()),
        ("records used in training are not scored", "yes" if p.exclude_trained else "no"),
        ("out-of-range policy when scoring", p.range_policy),
        ("models", ", ".join(_model_text(p, s) for s in res.specs)),
    ]
    out = ['<table class="left">'] + [f"<tr><th>{_e(k)}</th><td>{_e(v)}</td></tr>" for k, v in rows] + ["</table>"]
    roles = res.roles.groupby(["fold", "role"], sort=False).agg(records=("record", "count"), samples=("samples", "sum"))
    out.append("<p>Records per role and fold:</p>" + _table(roles.reset_index(), "{:.0f}"))
    ov = res.overlap()
    if ov.empty:
        out.append("<p><b>Train/score overlap:</b> none. No scored record trained a model or the analysis "
                   "in its fold: every score is on unseen data.</p>")
    else:
        out.append(f'<p class="warn"><b>Train/score overlap:</b> {len(ov)} scored record(s) also trained '
                   "in the same fold; their scores are not on unseen data:</p>" + _table(ov))
    out.append("<details><summary>protocol file (JSON)</summary><pre>" + _e(p.to_json()) + "</pre></details>")
    return "\n".join(out)


def _summary_section(res: StudyResult, summary: pd.DataFrame) -> str:
    hl = res.headline()
    cls = "headline" if hl.get("available") else "warn"
    text = ('<b>Headline</b> (LPV against the best of the paper\'s classical models, P-15 and SP-1..SP-4). '
            + _e(hl["text"]))
    out = [f'<p class="{cls}">{text}</p>']
    cols = ["model", "n_ok", "n_failed", "esr_mean", "esr_median", "esr_q1", "esr_q3",
            "ssse_mean", "ssse_median", "ssse_q1", "ssse_q3", "esr_gain_of_best_pct", "ssse_gain_of_best_pct",
            "fit_time_s", "sim_time_s"]
    out.append(_table(summary[cols]))
    out.append('<p class="small">ESR (eq. 24) [-] and SSSE (eq. 23, an RMS error) [N] over the rows with status '
               "<code>ok</code>. <code>*_gain_of_best_pct</code>: improvement of the model with the lowest mean over "
               "this model, 100 (mean - best) / mean, as the paper states its 51 % and 36.8 %. Times in seconds, "
               "summed over folds and records. On the virtual rig the damper itself is a Spencer model: the "
               "<code>spencer</code> estimator has the true structure there and is a reference, not a competitor.</p>")
    return "\n".join(out)


def _failures_section(res: StudyResult) -> str:
    fits = res.fits[["fold", "model", "status", "fit_time_s", "n_train", "train_samples", "error", "note"]]
    out = ["<p>Identification, one row per fold and model:</p>", _table(fits, cls="left")]
    bad = res.results[res.results["status"] != "ok"]
    if bad.empty:
        out.append("<p>Every simulation of every scored record succeeded.</p>")
    else:
        grp = bad.groupby(["model", "status"], sort=False).agg(rows=("record", "count"), first_error=("error", "first"))
        out.append(f"<p>{len(bad)} row(s) without scores (kept in <code>results.csv</code>):</p>" + _table(grp.reset_index(), cls="left"))
    notes = res.results[(res.results["status"] == "ok") & (res.results["note"].astype(str) != "")]
    if not notes.empty:
        grp = notes.groupby("model", sort=False).agg(rows=("record", "count"), example=("note", "first"))
        out.append("<p>Warnings while simulating (e.g. extrapolation outside the identified range):</p>"
                   + _table(grp.reset_index(), cls="left"))
    return "\n".join(out)


def _analysis_section(res: StudyResult) -> str:
    out = []
    for fold, an in res.analyses.items():
        if an.laws is not None and hasattr(an.laws, "to_frame"):
            cols = [c for c in an.laws.to_frame().columns if not c.endswith("_law")]
            out.append(f"<p>Fold <code>{_e(fold)}</code>: {len(an.fits)} level(s), grouped by {_e(an.by)}.</p>"
                       + _table(an.laws.to_frame()[cols]))
        else:
            out.append(f"<p>Fold <code>{_e(fold)}</code>: {_e(an.error or 'no analysis')}</p>")
        if an.notes:
            out.append(f'<p class="small">Notes: {_e(an.notes)}</p>')
        if len(res.analyses) > 3:
            out.append(f'<p class="small">({len(res.analyses) - 1} more folds in <code>analysis/</code>.)</p>')
            break
    return "\n".join(out)


def _figures_section(saved: Mapping[str, Any]) -> str:
    out = []
    for name, caption in FIGURES.items():
        item = saved.get(name)
        if item is None:
            continue
        if isinstance(item, str):
            out.append(f'<figure><figcaption>{_e(caption)} <span class="warn">Not drawn: {_e(item)}</span></figcaption></figure>')
            continue
        data = base64.b64encode(Path(item["png"]).read_bytes()).decode("ascii")
        out.append(
            f'<figure id="{_e(name)}"><img src="data:image/png;base64,{data}" alt="{_e(caption)}">'
            f"<figcaption>{_e(caption)} (<code>figures/{_e(name)}.png</code>, <code>.svg</code>)</figcaption></figure>"
        )
    return "\n".join(out) if out else "<p>Figures were not requested.</p>"


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
    results_cols = [c for c in res.results.columns if c not in ("note",)]
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>mrdamper study: {_e(res.protocol.name)}</title><style>{_CSS}</style></head><body>",
        f"<h1>MR damper model comparison: {_e(res.protocol.name)}</h1>",
        (f'<p class="small">{_e(info.get("n_records", "?"))} records, {_e(info.get("n_folds", "?"))} fold(s), '
         f'{len(res.specs)} models; seed {_e(info.get("seed"))}; run on {_e(info.get("executor", "?"))} in '
         f'{float(info.get("wall_time_s", float("nan"))):.1f} s.</p>'),
        "<h2>Summary</h2>", _summary_section(res, summary),
        "<h2>Protocol</h2>", _protocol_section(res),
        "<h2>Figures</h2>", _figures_section(saved),
        "<h2>Identification and failures</h2>", _failures_section(res),
        "<h2>Force-velocity analysis</h2>", _analysis_section(res),
        "<h2>All results</h2>",
        (f"<details><summary>{len(res.results)} rows (also in <code>results.csv</code>)</summary>"
         + _table(res.results[results_cols], cls="left") + "</details>"),
        (f'<p class="small">Python {_e(info.get("python", ""))} on {_e(info.get("platform", ""))}. Files next to '
         "this report: results.csv, summary.csv, fits.csv, roles.csv, protocol.json, study.json, models/, figures/.</p>"),
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"
