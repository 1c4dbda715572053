"""Time-domain figures of single models: the LTI model failing on hysteresis (paper Fig. 4) and
measured against LPV force with velocity and current below (Fig. 6)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource

__all__ = ["plot_lti_hysteresis", "plot_model_tracking"]


def plot_lti_hysteresis(
    experiment: Experiment,
    F_model: Any,
    *,
    label: str = "LTI",
    axes: Any = None,
    window: Sequence[float] | None = None,
) -> np.ndarray:
    """Paper Fig. 4: a linear time-invariant model against the measured force, F-v and F-t.

    Parameters
    ----------
    experiment : Experiment
        The record (the paper uses a stepped-current record, experiment 8).
    F_model : array_like
        The model's free-run force [N], one value per sample.
    label : str
        Model name in the legends.
    axes : sequence of 2 Axes, optional
        F-v panel and F-t panel; new side-by-side panels when None.
    window : (float, float), optional
        Time span drawn [s]; the whole record when None.

    Returns
    -------
    ndarray of 2 Axes
        Each with two lines, ``measured`` and ``label``.
    """
    from mrdamper.plotting._common import check_same_length, new_axes_column, window_mask

    Fm = check_same_length("F_model", F_model, experiment.n)
    mask = window_mask(experiment.t, window)
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(7.0, 3.2), sharey=True, layout="constrained")
    axes = new_axes_column(axes, 2, (7.0, 3.2))
    e = experiment
    axes[0].plot(e.v[mask], e.F[mask], lw=0.6, color="0.2", label="measured")
    axes[0].plot(e.v[mask], Fm[mask], lw=0.8, color="tab:gray", ls="--", label=label)
    axes[0].set_xlabel("v [m/s]")
    axes[0].set_ylabel("F [N]")
    axes[0].set_title("Force-velocity plane")
    axes[1].plot(e.t[mask], e.F[mask], lw=0.7, color="0.2", label="measured")
    axes[1].plot(e.t[mask], Fm[mask], lw=0.8, color="tab:gray", ls="--", label=label)
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("F [N]")
    axes[1].set_title(f"Force against time ({e.name})")
    for ax in axes:
        ax.grid(True, lw=0.3)
    fig = axes[0].figure
    handles, names = axes[0].get_legend_handles_labels()
    if fig.get_layout_engine() is not None:
        fig.legend(handles, names, loc="outside upper center", ncol=2, frameon=False)
    else:
        fig.legend(handles, names, loc="upper center", ncol=2, frameon=False)
    return axes


def plot_model_tracking(
    experiment: Experiment,
    F_model: Any,
    *,
    label: str = "LPV",
    axes: Any = None,
    window: Sequence[float] | None = None,
    source: ElectricalSource = "i",
) -> np.ndarray:
    """Paper Fig. 6: measured and model force (top), velocity (middle), electrical input (bottom).

    Parameters
    ----------
    experiment : Experiment
        The record.
    F_model : array_like
        The model's free-run force [N].
    label : str
        Model name in the legend.
    axes : sequence of 3 Axes, optional
        Stacked panels; new ones sharing the time axis when None.
    window : (float, float), optional
        Time span drawn [s]; the whole record when None.
    source : {"i", "voltage"}
        Electrical channel of the bottom panel.

    Returns
    -------
    ndarray of 3 Axes
        Top: lines ``measured`` and ``label``; middle: ``v``; bottom: the electrical input.
    """
    from mrdamper.plotting._common import check_same_length, new_axes_column, window_mask

    Fm = check_same_length("F_model", F_model, experiment.n)
    mask = window_mask(experiment.t, window)
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(
            3,
            1,
            sharex=True,
            figsize=(7.0, 5.2),
            layout="constrained",
            gridspec_kw={"height_ratios": [1.6, 1.0, 1.0]},
        )
    axes = new_axes_column(axes, 3, (7.0, 5.2))
    e = experiment
    t = e.t[mask]
    axes[0].plot(t, e.F[mask], lw=0.8, color="0.2", label="measured")
    axes[0].plot(t, Fm[mask], lw=0.8, color="tab:red", label=label)
    axes[0].set_ylabel("F [N]")
    axes[0].set_title(f"Measured and {label} force ({e.name})")
    from mrdamper.plotting._common import legend_outside

    legend_outside(axes[0])
    axes[1].plot(t, e.v[mask], lw=0.7, color="tab:blue", label="v")
    axes[1].set_ylabel("v [m/s]")
    el = e.electrical(source)
    axes[2].plot(t, el[mask], lw=0.8, color="tab:purple", label=source)
    axes[2].set_ylabel("i [A]" if source == "i" else "voltage [V]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, lw=0.3)
    return axes
