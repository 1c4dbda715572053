"""Model comparison figures: box plots of ESR and SSSE per model with the mean written under each
box (paper Figs. 7 and 8), force against time for all models (Fig. 9) and the F-v plane for all
models (Fig. 10)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError

__all__ = ["plot_force_time", "plot_fv_models", "plot_index_boxes"]

_INDEX_LABELS = {"esr": "ESR [-]", "ssse": "SSSE [N]", "nrmse": "NRMSE [-]", "fit_pct": "fit [%]"}


def plot_index_boxes(
    results: pd.DataFrame,
    index: str = "esr",
    *,
    order: Sequence[str] | None = None,
    ax: Any = None,
    log: bool | None = None,
) -> Any:
    """Paper Figs. 7 (ESR) and 8 (SSSE): one box per model, its mean written under the box.

    Parameters
    ----------
    results : DataFrame
        Per-record table with columns ``model``, ``status`` and ``index``; only rows with
        status ``"ok"`` enter the boxes. A model without any successful row gets an empty slot
        marked "failed".
    index : {"esr", "ssse", "nrmse", "fit_pct"}
        Column drawn.
    order : sequence of str, optional
        Model labels in display order (default: order of appearance).
    ax : Axes, optional
        Where to draw; a new figure when None.
    log : bool, optional
        Logarithmic y axis; default when the means span more than two decades.

    Returns
    -------
    Axes
        One box per model (x tick labels = models) and one text per model (``mean <value>``).

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame(
    ...     {"model": ["a", "a", "b", "b"], "status": "ok", "esr": [0.1, 0.2, 0.3, 0.5]}
    ... )
    >>> ax = plot_index_boxes(df, "esr")
    >>> [t.get_text() for t in ax.get_xticklabels()]
    ['a', 'b']
    """
    for col in ("model", "status", index):
        if col not in results.columns:
            raise DataValidationError(
                col, f"results table has no column {col!r} (columns: {list(results.columns)})"
            )
    from mrdamper.plotting._common import model_color, new_axes

    labels = list(order) if order is not None else list(dict.fromkeys(results["model"]))
    if not labels:
        raise DataValidationError("results", "no model rows to plot")
    # about 0.6 in per box: labels and means under the boxes stay apart (14 kinds: 9.9 in)
    ax = new_axes(ax, (min(10.0, max(4.5, 0.62 * len(labels) + 1.2)), 3.8))
    ok = results[results["status"] == "ok"]
    data = [ok.loc[ok["model"] == m, index].to_numpy(dtype=float) for m in labels]
    means = [float(np.mean(d)) if d.size else float("nan") for d in data]
    pos = np.arange(1, len(labels) + 1)
    filled = [k for k, d in enumerate(data) if d.size]
    if filled:
        bp = ax.boxplot(
            [data[k] for k in filled],
            positions=pos[filled],
            widths=0.6,
            patch_artist=True,
            medianprops={"color": "k"},
            flierprops={"markersize": 3},
        )
        for k, patch in zip(filled, bp["boxes"]):
            patch.set_facecolor(model_color(labels[k], k))
            patch.set_alpha(0.55)
    ax.set_xticks(pos)
    ax.set_xticklabels(labels)
    ax.set_xlim(0.4, len(labels) + 0.6)
    finite = [m for m in means if np.isfinite(m) and m > 0]
    if log is None:
        log = bool(finite) and max(finite) / min(finite) > 100
    if log:
        ax.set_yscale("log")
    for p, m in zip(pos, means):
        text = "failed" if not np.isfinite(m) else f"mean\n{m:.3g}"
        ax.annotate(
            text,
            (p, 0),
            xycoords=("data", "axes fraction"),
            xytext=(0, -16),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=7.5,
        )
    ax.set_ylabel(_INDEX_LABELS.get(index, index))
    ax.set_title(
        f"{index.upper() if index in ('esr', 'ssse') else index} per model (mean under each box)"
    )
    if len(labels) > 7:
        ax.tick_params(axis="x", labelsize=7.5)
    ax.grid(True, axis="y", lw=0.3)
    return ax


def _predictions(predictions: Mapping[str, Any], n: int) -> dict[str, np.ndarray]:
    from mrdamper.plotting._common import check_same_length

    if not predictions:
        raise DataValidationError(
            "predictions", "expected at least one model label -> force array, got none"
        )
    return {k: check_same_length(f"predictions[{k!r}]", v, n) for k, v in predictions.items()}


def _clip_to_measured(
    ax: Any, F: np.ndarray, preds: Mapping[str, np.ndarray], mask: np.ndarray, margin: float
) -> list[str]:
    """Limit the force axis to the measured span (+ ``margin`` of it); return models drawn beyond
    it."""
    lo, hi = float(F[mask].min()), float(F[mask].max())
    pad = margin * max(hi - lo, 1e-9)
    lo, hi = lo - pad, hi + pad
    ax.set_ylim(lo, hi)
    beyond = [k for k, v in preds.items() if float(v[mask].min()) < lo or float(v[mask].max()) > hi]
    if beyond:
        ax.text(
            0.01,
            0.98,
            "beyond the axes: " + ", ".join(beyond),
            transform=ax.transAxes,
            fontsize=7,
            va="top",
            color="tab:red",
        )
    return beyond


def _measured_and_models(
    experiment: Experiment,
    predictions: Mapping[str, Any],
    abscissa: np.ndarray,
    *,
    ax: Any,
    window: Sequence[float] | None,
    clip_margin: float | None,
    figsize: tuple[float, float],
    widths: tuple[float, float],
    alpha: float | None = None,
) -> Any:
    """Draw the measured force, then every model's force, against ``abscissa`` (one per sample).

    Shared by :func:`plot_force_time` (abscissa ``t``) and :func:`plot_fv_models` (``v``);
    ``widths`` are the line widths of the measured and the model lines [pt]. Sets the force
    label and the grid; the caller adds the abscissa label, the title and the legend.
    """
    from mrdamper.plotting._common import model_color, new_axes, window_mask

    preds = _predictions(predictions, experiment.n)
    mask = window_mask(experiment.t, window)
    ax = new_axes(ax, figsize)
    xs = abscissa[mask]
    ax.plot(xs, experiment.F[mask], lw=widths[0], color="0.15", label="measured")
    for k, (label, F) in enumerate(preds.items()):
        ax.plot(xs, F[mask], lw=widths[1], color=model_color(label, k), label=label, alpha=alpha)
    if clip_margin is not None:
        _clip_to_measured(ax, experiment.F, preds, mask, clip_margin)
    ax.set_ylabel("F [N]")
    ax.grid(True, lw=0.3)
    return ax


def plot_force_time(
    experiment: Experiment,
    predictions: Mapping[str, Any],
    *,
    ax: Any = None,
    window: Sequence[float] | None = None,
    clip_margin: float | None = 0.5,
) -> Any:
    """Paper Fig. 9: measured force and every model's free-run force against time.

    Parameters
    ----------
    experiment : Experiment
        The record.
    predictions : mapping
        Model label -> predicted force [N] (one value per sample).
    ax : Axes, optional
        Where to draw; a new figure when None.
    window : (float, float), optional
        Time span drawn [s]; the whole record when None.
    clip_margin : float or None
        Limit the force axis to the measured span widened by this fraction of it, so one wildly
        wrong model does not hide the others (models that leave the axes are named in the plot);
        None lets the axis fit every line.

    Returns
    -------
    Axes
        Lines: ``measured`` then one per model, labelled by model.
    """
    ax = _measured_and_models(
        experiment,
        predictions,
        experiment.t,
        ax=ax,
        window=window,
        clip_margin=clip_margin,
        figsize=(6.2, 3.4),
        widths=(1.6, 0.8),
    )
    ax.set_xlabel("t [s]")
    ax.set_title(f"Measured and computed damper force ({experiment.name})")
    from mrdamper.plotting._common import legend_outside

    legend_outside(ax, fontsize=7.5)
    return ax


def plot_fv_models(
    experiment: Experiment,
    predictions: Mapping[str, Any],
    *,
    ax: Any = None,
    window: Sequence[float] | None = None,
    clip_margin: float | None = 0.5,
) -> Any:
    """Paper Fig. 10: the force-velocity plane, measured and every model.

    Parameters
    ----------
    experiment : Experiment
        The record.
    predictions : mapping
        Model label -> predicted force [N].
    ax : Axes, optional
        Where to draw; a new figure when None.
    window : (float, float), optional
        Time span drawn [s]; the whole record when None.
    clip_margin : float or None
        As in :func:`plot_force_time`.

    Returns
    -------
    Axes
        Lines: ``measured`` then one per model.
    """
    ax = _measured_and_models(
        experiment,
        predictions,
        experiment.v,
        ax=ax,
        window=window,
        clip_margin=clip_margin,
        figsize=(5.6, 4.2),
        widths=(1.4, 0.7),
        alpha=0.85,
    )
    ax.set_xlabel("v [m/s]")
    ax.set_title(f"F-v plane, measured and computed ({experiment.name})")
    from mrdamper.plotting._common import legend_outside

    legend_outside(ax, fontsize=7.5)
    return ax
