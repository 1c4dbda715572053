"""Every figure of the paper drawn from a :class:`~mrdamper.study.result.StudyResult`.

A figure that cannot be drawn (no analysis records, no LTI or LPV model, every model failed) is
returned as the text of the reason instead of a Figure, and the report shows that text.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from mrdamper.errors import interrupt_in_chain

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.study.result import Showcase, StudyResult

__all__ = ["FIGURES", "make_figures"]

#: Figure file name -> caption (paper figure number first).
FIGURES: dict[str, str] = {
    "fig01_fv_map": "Fig. 1. Force-velocity map at several currents (analysis records).",
    "fig02_zone_fit": "Fig. 2. Measured F-v samples and the three-zone straight-line regression (eq. 17) at one current.",
    "fig03_zone_laws": "Fig. 3. Slopes m_j and intercepts c_j of the three zones against current, with the fitted quadratic laws.",
    "fig04_lti_hysteresis": "Fig. 4. The LTI model (no scheduling) against the measured force: it cannot follow the hysteresis.",
    "fig06_lpv_tracking": "Fig. 6. Measured and LPV force (top), velocity (middle) and current (bottom).",
    "fig07_esr_boxes": "Fig. 7. ESR per model over the scored records; the mean is written under each box.",
    "fig08_ssse_boxes": "Fig. 8. SSSE [N] per model over the scored records; the mean is written under each box.",
    "fig09_force_time": "Fig. 9. Measured and computed damper force, all models.",
    "fig10_fv_models": "Fig. 10. Force-velocity plane, measured and computed, all models.",
}

#: Longest stretch drawn in time-domain figures [s].
_WINDOW = 6.0


def _window(sc: Showcase) -> tuple[float, float] | None:
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
        return "no force-velocity analysis data" + (f" ({'; '.join(sorted(reasons))})" if reasons else "")
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
    return plot_zone_laws(an.laws, unit="A" if res.protocol.input == "i" else "V")[0].figure


def _by_kind(sc: Showcase | None, kind: str) -> tuple[str, Any] | None:
    if sc is None:
        return None
    for label, F in sc.predictions.items():
        if sc.kinds.get(label) == kind:
            return label, F
    return None


def _fig4(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_lti_hysteresis

    hit = _by_kind(res.hysteresis, "lti")
    if hit is None:
        return "no LTI model in this study"
    label, F = hit
    if isinstance(F, str):
        return f"the LTI model failed on {res.hysteresis.record.name}: {F}"  # type: ignore[union-attr]
    sc = res.hysteresis
    return plot_lti_hysteresis(sc.record, F, label=label, window=_window(sc))[0].figure  # type: ignore[union-attr, arg-type]


def _fig6(res: StudyResult) -> Any:
    from mrdamper.plotting import plot_model_tracking

    hit = _by_kind(res.showcase, "lpv")
    if hit is None:
        return "no LPV model in this study"
    label, F = hit
    sc = res.showcase
    if isinstance(F, str):
        return f"the LPV model failed on {sc.record.name}: {F}"  # type: ignore[union-attr]
    return plot_model_tracking(sc.record, F, label=label, window=_window(sc), source=res.protocol.input)[0].figure  # type: ignore[union-attr, arg-type]


def _boxes(index: str) -> Callable[[StudyResult], Any]:
    def draw(res: StudyResult) -> Any:
        from mrdamper.plotting import plot_index_boxes

        return plot_index_boxes(res.results, index, order=res.labels).figure

    return draw


def _all_models(kind: str) -> Callable[[StudyResult], Any]:
    def draw(res: StudyResult) -> Any:
        from mrdamper.plotting import plot_force_time, plot_fv_models

        sc = res.showcase
        if sc is None or not sc.ok():
            return "no successful model prediction to draw"
        fn = plot_force_time if kind == "ft" else plot_fv_models
        ax = fn(sc.record, sc.ok(), window=_window(sc))
        failed = [k for k, v in sc.predictions.items() if isinstance(v, str)]
        if failed:
            ax.text(0.01, 0.01, "failed: " + ", ".join(failed), transform=ax.transAxes, fontsize=7, color="tab:red")
        return ax.figure

    return draw


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
}


def make_figures(res: StudyResult) -> dict[str, Any]:
    """Draw every figure; name -> Figure, or the reason (str) it was not drawn."""
    out: dict[str, Any] = {}
    for name, draw in _DRAW.items():
        try:
            out[name] = draw(res)
        except Exception as exc:
            if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
                raise KeyboardInterrupt from exc
            out[name] = f"figure could not be drawn: {type(exc).__name__}: {exc}"
    return out
