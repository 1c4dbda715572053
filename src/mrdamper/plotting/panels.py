"""All models on one record, readable however many there are: an overlay of a few chosen models
above small multiples with one panel per model (paper Figs. 9 and 10, and the force-displacement
loops).

A model marked as failed (it diverged, or its error is larger than the signal) is never drawn in
the overlay nor on the shared scale: it gets a panel of its own with its own force axis and a red
title saying why, so it cannot paint over the others.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError

__all__ = ["PLANES", "plot_model_panels"]

#: Abscissa of each plane: (record attribute, axis label, scale to the drawn unit).
PLANES: dict[str, tuple[str, str, float]] = {
    "ft": ("t", "t [s]", 1.0),
    "fv": ("v", "v [m/s]", 1.0),
    "fx": ("x", "x [mm]", 1e3),
}


def plot_model_panels(
    experiment: Experiment,
    predictions: Mapping[str, Any],
    *,
    plane: str = "ft",
    overlay: Sequence[str] | None = None,
    failed: Mapping[str, str] | None = None,
    titles: Mapping[str, str] | None = None,
    window: Sequence[float] | None = None,
    ncols: int = 3,
    clip_margin: float = 0.25,
    fig: Any = None,
) -> Any:
    """Measured force and each model's force: an overlay panel, then one small panel per model.

    Parameters
    ----------
    experiment : Experiment
        The record.
    predictions : mapping
        Model label -> predicted force [N] (one value per sample), or the error text (str) of a
        model that could not predict this record.
    plane : {"ft", "fv", "fx"}
        Force against time [s], velocity [m/s] or displacement [mm].
    overlay : sequence of str, optional
        Models drawn together with the measured force in the top panel (default: the first three
        that did not fail). Failed models are left out of it.
    failed : mapping, optional
        Model label -> reason it is considered failed; drawn in its own panel and own scale.
    titles : mapping, optional
        Model label -> text added to its panel title (e.g. its ESR on this record).
    window : (float, float), optional
        Time span drawn [s]; the whole record when None.
    ncols : int
        Columns of small panels.
    clip_margin : float
        The shared force axis spans the measured force widened by this fraction of its span [-];
        models that leave it are named in their panel.
    fig : Figure, optional
        Empty figure to draw on; a new one (7 in wide) when None.

    Returns
    -------
    Figure
        ``fig.axes[0]`` is the overlay (lines ``measured`` then the overlaid models), followed by
        one panel per model in the order of ``predictions`` (lines ``measured`` then the model).
    """
    from matplotlib.ticker import MaxNLocator

    from mrdamper.plotting._common import legend_outside, model_color, window_mask

    if plane not in PLANES:
        raise DataValidationError("plane", f"expected one of {sorted(PLANES)}, got {plane!r}")
    if not predictions:
        raise DataValidationError(
            "predictions", "expected at least one model label -> force array, got none"
        )
    if not isinstance(ncols, int) or ncols < 1:
        raise DataValidationError("ncols", f"expected a positive integer, got {ncols!r}")
    failed = dict(failed or {})
    titles = dict(titles or {})
    preds: dict[str, Any] = {}
    for k, F in predictions.items():
        if isinstance(F, str):
            preds[k] = F
            failed.setdefault(k, F)
            continue
        arr = np.asarray(F, dtype=float)
        if arr.shape != (experiment.n,):
            raise DataValidationError(
                f"predictions[{k!r}]",
                f"expected {experiment.n} samples like the record, got shape {arr.shape}",
            )
        preds[k] = arr
    unknown = [k for k in (overlay or ()) if k not in preds]
    if unknown:
        raise DataValidationError(
            "overlay", f"labels {unknown} are not in predictions ({list(preds)})"
        )
    good = [k for k in preds if k not in failed]
    over = [k for k in (overlay if overlay is not None else good[:3]) if k not in failed]

    attr, xlabel, scale = PLANES[plane]
    mask = window_mask(experiment.t, window)
    xs = np.asarray(getattr(experiment, attr), dtype=float)[mask] * scale
    Fm = experiment.F[mask]
    lo, hi = float(Fm.min()), float(Fm.max())
    pad = clip_margin * max(hi - lo, 1e-9)
    ylim = (lo - pad, hi + pad)
    style = {"ft": "-", "fv": "-", "fx": "-"}[plane]

    labels = list(preds)
    nrows = int(np.ceil(len(labels) / ncols))
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(7.0, 2.6 + 1.75 * nrows), layout="constrained")
    gs = fig.add_gridspec(1 + nrows, ncols, height_ratios=[1.6] + [1.0] * nrows)
    top = fig.add_subplot(gs[0, :])
    top.plot(xs, Fm, style, lw=1.4, color="0.15", label="measured")
    for k in over:
        top.plot(xs, preds[k][mask], style, lw=0.9, color=model_color(k, labels.index(k)), label=k)
    top.set_ylim(*ylim)
    top.set_xlabel(xlabel)
    top.set_ylabel("F [N]")
    left_out = [k for k in labels if k not in over]
    top.set_title(
        "Measured and "
        + (", ".join(over) if over else "no model")
        + " (every model in its own panel below)"
    )
    legend_outside(top)
    if left_out:
        top.text(
            1.01,
            0.0,
            "not overlaid:\n"
            + "\n".join(", ".join(left_out[k : k + 3]) for k in range(0, len(left_out), 3)),
            transform=top.transAxes,
            fontsize=7,
            va="bottom",
            ha="left",
            color="0.35",
        )
    shared: Any = None
    for n, k in enumerate(labels):
        r, c = divmod(n, ncols)
        is_failed = k in failed
        ax = fig.add_subplot(gs[1 + r, c], sharey=None if is_failed else shared)
        if not is_failed and shared is None:
            shared = ax
        ax.plot(xs, Fm, style, lw=1.5, color="0.8", label="measured")
        if isinstance(preds[k], str):
            ax.text(
                0.5,
                0.5,
                "no prediction:\n" + _wrap(preds[k]),
                transform=ax.transAxes,
                ha="center",
                va="center",
                fontsize=7,
                color="tab:red",
            )
        else:
            y = preds[k][mask]
            ax.plot(xs, y, style, lw=0.8, color=model_color(k, n), label=k)
            if not is_failed:
                ax.set_ylim(*ylim)
                if float(y.min()) < ylim[0] or float(y.max()) > ylim[1]:
                    ax.text(
                        0.02,
                        0.96,
                        "leaves the axes",
                        transform=ax.transAxes,
                        fontsize=7,
                        va="top",
                        color="tab:red",
                    )
        extra = titles.get(k, "")
        if is_failed:
            ax.set_title(f"{k}: FAILED, own scale", color="tab:red", fontsize=8.5)
            ax.text(
                0.03,
                0.03,
                _wrap(failed[k], 30, 3),
                transform=ax.transAxes,
                fontsize=7,
                va="bottom",
                color="tab:red",
                bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1.0},
            )
            for side in ax.spines.values():
                side.set_edgecolor("tab:red")
        else:
            ax.set_title(k + (f" ({extra})" if extra else ""), fontsize=8.5)
        if c == 0:
            ax.set_ylabel("F [N]")
        if r == nrows - 1 or n + ncols >= len(labels):
            ax.set_xlabel(xlabel)
        ax.set_xlim(top.get_xlim())
        ax.xaxis.set_major_locator(MaxNLocator(nbins=4))
        ax.yaxis.set_major_locator(MaxNLocator(nbins=5))
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.3)
    return fig


def _wrap(text: str, width: int = 38, lines: int = 3) -> str:
    import textwrap

    out = textwrap.wrap(str(text), width)
    return "\n".join(out[:lines]) + ("..." if len(out) > lines else "")
