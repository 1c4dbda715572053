"""Every figure of the paper drawn from a :class:`~mrdamper.study.result.StudyResult`.

A figure that cannot be drawn (no analysis records, no LTI or LPV model, every model failed) is
returned as the text of the reason instead of a Figure, and the report shows that text.

Figures with every model on one record (Figs. 9, 10 and the force-displacement loops) follow two
rules, stated in their captions:

* **Failed models** (:func:`failed_models`: no successful simulation, a mean ESR above
  :data:`FAILED_ESR` over the study, or a failed / ESR > 1 prediction of the drawn record) get a
  panel of their own with their own force scale; they are never overlaid on the others.
* **Overlay** (:func:`overlay_models`): the measured force with at most three models, LPV, the
  best of the paper's classical models (P-15, SP-1..SP-4) and the best of the others by mean ESR
  over the study, none of them failed. Every model, overlaid or not, also has its own panel.

All figures are drawn at print size (7 in wide at most, text of 7 pt or more; see
:data:`mrdamper.plotting.PRINT_STYLE`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from mrdamper.errors import interrupt_in_chain
from mrdamper.study.result import Showcase, StudyResult

__all__ = [
    "FAILED_ESR",
    "FIGURES",
    "FIGURE_DPI",
    "FIGURE_FORMATS",
    "failed_models",
    "make_figures",
    "overlay_models",
    "record_esr",
    "time_window",
]

#: File formats every figure is saved in.
FIGURE_FORMATS: tuple[str, ...] = ("png", "svg")
#: Resolution of the PNG figures [dots per inch]: sharp when printed at their drawn size.
FIGURE_DPI = 150

#: Figure file name -> (paper figure number or None, caption). The report numbers its figures
#: consecutively and names the paper's number beside each.
FIGURES: dict[str, tuple[int | None, str]] = {
    "fig01_fv_map": (1, "Force-velocity map at each current level (analysis records)."),
    "fig02_zone_fit": (
        2,
        (
            "Measured F-v samples and the three-zone straight-line regression (eq. 17) at the "
            "highest current level."
        ),
    ),
    "fig03_zone_laws": (
        3,
        (
            "Slopes m_j and intercepts c_j of the three zones against current (points) with the "
            "fitted quadratic laws (lines, eq. 18); one panel and scale per quantity."
        ),
    ),
    "fig04_lti_hysteresis": (
        4,
        (
            "The LTI model (no scheduling) against the measured force: it cannot follow "
            "the hysteresis."
        ),
    ),
    "fig06_lpv_tracking": (
        6,
        "Measured and LPV force (top), velocity (middle) and current (bottom).",
    ),
    "fig07_esr_boxes": (
        7,
        "ESR per model over the scored records; the mean is written under each box.",
    ),
    "fig08_ssse_boxes": (
        8,
        "SSSE [N] per model over the scored records; the mean is written under each box.",
    ),
    "fig09_force_time": (9, "Measured and computed damper force against time."),
    "fig10_fv_models": (10, "Force-velocity plane, measured and computed."),
    "fig11_fx_loops": (
        None,
        (
            "Force-displacement loops, measured and computed; the loop area is the energy "
            "dissipated per cycle (table below)."
        ),
    ),
    "control_fronts": (
        None,
        (
            "Control relevance: comfort (ISO 2631 weighted RMS body acceleration a_w) against "
            "road holding (RMS dynamic tyre load) on the quarter car, per model as the "
            "controller's model: passive inputs (line, soft to hard) and the semi-active "
            "controllers' gains (points), predicted with the model as the damper (open "
            "markers, dashed) and achieved with the rig's reference damper (filled, solid)."
        ),
    ),
}

#: A model whose mean ESR over the study, or whose ESR on the drawn record, exceeds this [-] is
#: treated as failed in the shared figures (its error is larger than the measured force's spread).
FAILED_ESR = 1.0

#: Longest stretch drawn in time-domain figures [s].
_WINDOW = 6.0


def time_window(sc: Showcase) -> tuple[float, float] | None:
    """The stretch ``(t0, t1)`` [s] of the record the time-domain figures draw: its middle
    :data:`_WINDOW` seconds, or None for the whole record when it is not much longer."""
    t = sc.record.t
    d = float(t[-1] - t[0])
    if d <= 1.5 * _WINDOW:
        return None
    mid = float(t[0]) + d / 2
    return (mid - _WINDOW / 2, mid + _WINDOW / 2)


def _first_analysis(res: StudyResult) -> Any:
    for an in res.analyses.values():
        if an.curves or an.laws is not None:
            return an
    return None


def _fig1(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_fv_map

    an = _first_analysis(res)
    if an is None or not an.curves:
        reasons = {a.error for a in res.analyses.values() if a.error}
        return "no force-velocity analysis data" + (
            f" ({'; '.join(sorted(reasons))})" if reasons else ""
        )
    return plot_fv_map(an.curves, unit="A" if res.protocol.input == "i" else "V").figure


def _fig2(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_zone_fit

    an = _first_analysis(res)
    if an is None or not an.fits or not an.curves:
        return "no zone fit (no analysis records or the analysis failed)"
    fit = an.fits[-1]  # the highest level: the clearest three zones
    keys = np.array(sorted(an.curves))
    lev = float(keys[np.argmin(np.abs(keys - (fit.level if fit.level is not None else keys[-1])))])
    v, F = an.curves[lev]
    return plot_zone_fit(v, F, fit, unit="A" if res.protocol.input == "i" else "V").figure


def _fig3(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_zone_laws

    an = _first_analysis(res)
    if an is None or an.laws is None:
        err = "" if an is None else an.error
        return "no laws across current" + (f" ({err})" if err else "")
    return plot_zone_laws(an.laws, unit="A" if res.protocol.input == "i" else "V").flat[0].figure


def _by_kind(sc: Showcase | None, kind: str) -> tuple[str, Any] | None:
    if sc is None:
        return None
    for label, F in sc.predictions.items():
        if sc.kinds.get(label) == kind:
            return label, F
    return None


def _fig4(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_lti_hysteresis

    sc = res.hysteresis
    hit = _by_kind(sc, "lti")
    if sc is None or hit is None:
        return "no LTI model in this study"
    label, F = hit
    if isinstance(F, str):
        return f"the LTI model failed on {sc.record.name}: {F}"
    return plot_lti_hysteresis(sc.record, F, label=label, window=time_window(sc))[0].figure


def _fig6(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_model_tracking

    hit = _by_kind(res.showcase, "lpv")
    if hit is None:
        return "no LPV model in this study"
    label, F = hit
    sc = res.showcase
    if sc is None:
        return "no showcase record in this study"
    if isinstance(F, str):
        return f"the LPV model failed on {sc.record.name}: {F}"
    return plot_model_tracking(
        sc.record, F, label=label, window=time_window(sc), source=res.protocol.input
    )[0].figure


def _boxes(index: str) -> Callable[[StudyResult], Any]:
    def draw(res: StudyResult) -> Any:
        from mrdamper.plotting import plot_index_boxes

        return plot_index_boxes(res.results, index, order=res.labels).figure

    return draw


def record_esr(sc: Showcase) -> dict[str, float]:
    """ESR [-] of each successful prediction on the showcase record (eq. 24)."""
    from mrdamper.metrics import esr

    out: dict[str, float] = {}
    for k, F in sc.ok().items():
        try:
            out[k] = float(esr(sc.record.F, F))
        except Exception:  # noqa: BLE001 - a degenerate record has no ESR; the panel says nothing
            out[k] = float("nan")
    return out


def failed_models(res: StudyResult, sc: Showcase | None = None) -> dict[str, str]:
    """Models treated as failed in the shared figures, with the reason.

    A model fails when it has no successful scored record, when its mean ESR over the study is
    above :data:`FAILED_ESR`, or (for the drawn record ``sc``) when its prediction of that record
    failed or has an ESR above :data:`FAILED_ESR`. Its rows stay in every table.

    Parameters
    ----------
    res : StudyResult
        The study.
    sc : Showcase, optional
        Record drawn (default: the study's showcase).

    Returns
    -------
    dict
        Label -> one-line reason, in display order.
    """
    sc = res.showcase if sc is None else sc
    summary = res.summary.set_index("model")
    per_record = record_esr(sc) if sc is not None else {}
    out: dict[str, str] = {}
    for label in res.labels:
        row = summary.loc[label] if label in summary.index else None
        n_ok = int(row["n_ok"]) if row is not None else 0
        mean = float(row["esr_mean"]) if row is not None else float("nan")
        if n_ok == 0:
            statuses = res.results.loc[res.results["model"] == label, "status"].value_counts()
            out[label] = (
                "no successful simulation ("
                + ", ".join(f"{n} {s}" for s, n in statuses.items())
                + ")"
            )
        elif np.isfinite(mean) and mean > FAILED_ESR:
            out[label] = f"mean ESR {mean:.3g} > {FAILED_ESR:g} over the study"
        elif sc is not None and isinstance(sc.predictions.get(label), str):
            out[label] = f"failed on this record: {sc.predictions[label]}"
        elif per_record.get(label, 0.0) > FAILED_ESR:
            out[label] = f"ESR {per_record[label]:.3g} > {FAILED_ESR:g} on this record"
    return out


def overlay_models(res: StudyResult, failed: Mapping[str, str] | None = None) -> list[str]:
    """Models overlaid on the measured force in Figs. 9-11 (at most three, none failed).

    LPV (the paper's model), the best of the paper's classical models (P-15, SP-1..SP-4) and the
    best of the remaining models, each by mean ESR over the study, in display order.
    """
    from mrdamper.study.tables import PAPER_CLASSICAL

    failed = failed_models(res) if failed is None else failed
    summary = res.summary
    ok = summary[
        ~summary["model"].isin(list(failed))
        & np.isfinite(summary["esr_mean"].to_numpy(dtype=float))
    ]
    if res.showcase is not None:
        ok = ok[ok["model"].isin(list(res.showcase.ok()))]
    chosen: list[str] = []
    lpv = ok[ok["kind"] == "lpv"]
    if not lpv.empty:
        chosen.append(str(lpv.sort_values("esr_mean")["model"].iloc[0]))
    for group in (ok[ok["kind"].isin(PAPER_CLASSICAL)], ok):
        rest = group[~group["model"].isin(chosen)]
        if not rest.empty and len(chosen) < 3:
            chosen.append(str(rest.sort_values("esr_mean")["model"].iloc[0]))
    return [k for k in res.labels if k in chosen]


def _all_models(plane: str) -> Callable[[StudyResult], Any]:
    def draw(res: StudyResult) -> Any:
        from mrdamper.plotting import plot_model_panels

        sc = res.showcase
        if sc is None or not sc.predictions:
            return "no model prediction to draw"
        failed = failed_models(res, sc)
        scores = record_esr(sc)
        titles = {k: f"ESR {v:.3g}" for k, v in scores.items() if np.isfinite(v)}
        if plane == "fx":
            titles = _energy_titles(sc, titles)
        preds = {k: sc.predictions[k] for k in res.labels if k in sc.predictions}
        fig = plot_model_panels(
            sc.record,
            preds,
            plane=plane,
            overlay=overlay_models(res, failed),
            failed=failed,
            titles=titles,
            window=time_window(sc),
        )
        fig.suptitle(f"Record {sc.record.name} (scored in fold {sc.fold})", fontsize=9.5)
        return fig

    return draw


def _energy_titles(sc: Showcase, titles: Mapping[str, str]) -> dict[str, str]:
    from mrdamper.study.report_tables import energy_table

    tab = energy_table(sc)
    out = dict(titles)
    if tab.empty:
        return out
    unit = "J/cycle" if int(tab["cycles"].iloc[0]) > 0 else "J"
    for row in tab.itertuples(index=False):
        if row.model in out and np.isfinite(row.energy_J):
            out[row.model] = f"{row.energy_J:.3g} {unit}"
    return out


def _control_fronts(res: StudyResult) -> Any:
    from mrdamper.study.control_step import plot_fronts

    if res.control is None:
        return "the control-relevance step was switched off"
    return plot_fronts(res.control)


_DRAW: dict[str, Callable[[StudyResult], Any]] = {
    "fig01_fv_map": _fig1,
    "fig02_zone_fit": _fig2,
    "fig03_zone_laws": _fig3,
    "fig04_lti_hysteresis": _fig4,
    "fig06_lpv_tracking": _fig6,
    "fig07_esr_boxes": _boxes("esr"),
    "fig08_ssse_boxes": _boxes("ssse"),
    "fig09_force_time": _all_models("ft"),
    "fig10_fv_models": _all_models("fv"),
    "fig11_fx_loops": _all_models("fx"),
    "control_fronts": _control_fronts,
}


def make_figures(res: StudyResult) -> dict[str, Any]:
    """Draw every figure; name -> Figure, or the reason (str) it was not drawn."""
    import matplotlib

    from mrdamper.plotting import PRINT_STYLE

    out: dict[str, Any] = {}
    with matplotlib.rc_context(PRINT_STYLE):  # type: ignore[arg-type]
        for name, draw in _DRAW.items():
            try:
                out[name] = draw(res)
            except Exception as exc:
                if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
                    raise KeyboardInterrupt from exc
                out[name] = f"figure could not be drawn: {type(exc).__name__}: {exc}"
    return out
