"""The control-oriented extension of the design of experiments: the loop's motions on the rig.

A model identified on Table II is extrapolated in a quarter-car loop: the loop moves the damper
several times faster and switches the current while it moves. :func:`control_extension` measures
where the loop goes: it runs the quarter car (:func:`~mrdamper.control.loop.closed_loop.
simulate_closed_loop`) with a first model of the damper as controller model and damper, one run
per row of :data:`~mrdamper.rig.doe_control.CONTROL_EXTENSION` (ISO 8608 roads B, C, D, the five
controllers), and replays each run's damper travel on the rig with the run's current and with an
APRBS current (:func:`~mrdamper.rig.doe_control.replay_loop_motion`), and adds the stroke test
(:func:`~mrdamper.rig.doe_control.stroke_test`: slow sines over the rig's stroke, where a
damper's stiffness shows). On a physical rig the first
model is one fitted on Table II (any kind that can be the quarter car's damper and controller
model; a static map fits in seconds: :func:`first_model`, the command line's default); the
library function defaults to the rig's own damper, which only the virtual rig has.

Seeds: ``numpy.random.SeedSequence(seed)`` split into one child per row (as
:func:`~mrdamper.rig.doe.table_ii` does), each split into the road, the APRBS current and the two
rig runs; the stroke test's records take the children after the rows' (a row's records do not
depend on whether the stroke test is run); a different root seed gives held-out records.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.control.damper import DamperModel
from mrdamper.control.loop.car import QuarterCar, iso_road
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.quarter_car_study import default_rate
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.levels import check_levels
from mrdamper.rig.doe import current_range, record_seeds, resolve_rig
from mrdamper.rig.doe_control import (
    CONTROL_EXTENSION,
    HIGHPASS,
    STROKE_TEST,
    ControlRow,
    StrokeRow,
    replay_loop_motion,
    stroke_test,
)
from mrdamper.rig.virtual_rig import VirtualRig
from mrdamper.signals.common import check_positive, child_seeds

__all__ = ["FIRST_KIND", "control_extension", "first_model", "loop_motion"]

#: Plant steps per control sample of the loop runs (the motion only has to be the loop's).
SUBSTEPS = 2
#: Kind of the default first model: fitted on Table II in seconds, monotone in velocity by
#: default, and the first model of the closed-loop results (``docs/results.md``).
FIRST_KIND = "sp1"


def first_model(records: Sequence[Experiment], kind: str = FIRST_KIND, input: str = "i") -> Any:
    """The extension's first model: ``kind`` fitted with its defaults on ``records``.

    This is what a physical rig's user has before the extension: a model identified on the
    damper's Table II records (the rig's own damper is known only on the virtual rig).

    Parameters
    ----------
    records : sequence of Experiment
        The Table II records of the damper.
    kind : str
        Model kind (default :data:`FIRST_KIND`).
    input : {"i", "voltage"}
        The rig's electrical input.

    Returns
    -------
    FittedModel
        The fitted first model.
    """
    from mrdamper.models.registry import get_estimator

    return get_estimator(kind, input=input).fit(list(records))


def loop_motion(
    model: DamperModel,
    row: ControlRow,
    duration: float,
    road_seed: int,
    rig_fs: float,
    car: QuarterCar,
) -> tuple[np.ndarray, np.ndarray]:
    """Damper travel [m] and electrical input [A or V] of one loop run at the rig's rate.

    The quarter car ``car`` runs on the row's ISO 8608 road (``duration`` [s], phases from
    ``road_seed``) with ``model`` as controller model and damper, at the model's loop rate
    (:func:`~mrdamper.control.loop.quarter_car_study.default_rate`) with :data:`SUBSTEPS` plant
    steps
    per control sample; the travel (times the motion ratio) and the applied input are
    interpolated onto the rig's sampling grid.
    """
    fs = default_rate(model)
    road = iso_road(row.road_class, speed=row.speed, duration=duration, fs=fs, seed=road_seed)
    r = simulate_closed_loop(model, road, row.controller, car, substeps=SUBSTEPS)
    t = np.arange(round(duration * rig_fs)) / rig_fs
    travel = np.interp(t, r.t, r.travel * car.motion_ratio)
    # the input is held per control sample: take the held value, not an interpolation
    idx = np.minimum(np.searchsorted(r.t, t, side="right") - 1, r.t.size - 1)
    return travel, r.i[np.maximum(idx, 0)]


def control_extension(
    seed: int = 1,
    scale: float = 1.0,
    fs: float = 1000.0,
    damper: FittedModel | None = None,
    *,
    rig: VirtualRig | None = None,
    model: DamperModel | None = None,
    rows: tuple[ControlRow, ...] = CONTROL_EXTENSION,
    car: QuarterCar | None = None,
    highpass: float = HIGHPASS,
    stroke_rows: tuple[StrokeRow, ...] = STROKE_TEST,
) -> ExperimentSet:
    """Generate the control-oriented extension on the virtual rig (see the module docstring).

    Parameters
    ----------
    seed : int
        Root seed (default 1: not the seed of Table II's default 0); same seed, same bytes.
    scale : float
        Duration factor [-] of the rows' roads (records at least 2 s).
    fs : float
        Sampling rate [Hz].
    damper : FittedModel, optional
        Damper under test (default: the shipped reference damper).
    rig : VirtualRig, optional
        A configured rig instead of ``fs`` and ``damper``.
    model : FittedModel, optional
        The first model whose loop gives the motions (default: the rig's damper itself). Its
        input must be the rig's (current or voltage), and it must have been identified at more
        than one level of it (else its loop never switches the input).
    rows : tuple of ControlRow
        The loop runs (default :data:`~mrdamper.rig.doe_control.CONTROL_EXTENSION`).
    car : QuarterCar, optional
        The car of the loop runs (default :class:`~mrdamper.control.loop.car.QuarterCar`).
    highpass : float
        High-pass corner of the replayed travel [Hz] (default
        :data:`~mrdamper.rig.doe_control.HIGHPASS`).
    stroke_rows : tuple of StrokeRow
        The stroke test's records (default :data:`~mrdamper.rig.doe_control.STROKE_TEST`; an
        empty tuple leaves it out).

    Returns
    -------
    ExperimentSet
        Records ``ctrl{k:02d}``, two per row (loop current, then APRBS current), with metadata
        ``pattern``, ``displacement`` (road, controller, loop model), ``duration``, ``seed``;
        then the stroke test's ``stroke{k:02d}``.
    """
    scale = check_positive("scale", scale, "-")
    rig = resolve_rig(rig, damper, fs)
    loop_model = rig.model if model is None else model
    if model is not None:
        check_levels(model, "its loop never switches the input")
    if str(getattr(loop_model, "input", rig.model.input)) != str(rig.model.input):
        raise DataValidationError(
            "model",
            f"expected a model driven by the rig's input {rig.model.input!r}, got "
            f"{getattr(loop_model, 'input', None)!r}",
        )
    car = QuarterCar() if car is None else car
    lo, hi = current_range(rig.model, rig)
    out = []
    seeds = record_seeds(seed, len(rows) + len(stroke_rows))
    for k, (row, s) in enumerate(zip(rows, seeds[: len(rows)], strict=True)):
        duration = row.duration * scale
        if duration < 2.0:
            raise DataValidationError(
                "scale", f"{scale:g} makes row {k + 1} {duration:g} s; at least 2 s is needed"
            )
        s_road, s_aprbs, s_loop, s_rand = child_seeds(s, 4)
        road_seed = int(s_road.generate_state(1)[0])
        travel, current = loop_motion(loop_model, row, duration, road_seed, rig.fs, car)
        meta = {
            "displacement": (
                f"quarter car ({row.controller}, {loop_model.kind} model), "
                f"ISO {row.road_class} @ {row.speed:g} m/s"
            ),
            "duration": duration,
        }
        out += replay_loop_motion(
            rig,
            travel,
            current,
            current_range=(lo, hi),
            seeds=(s_aprbs, s_loop, s_rand),
            names=(f"ctrl{2 * k + 1:02d}", f"ctrl{2 * k + 2:02d}"),
            metadata=meta,
            seed_label=s,
            highpass=highpass,
        )
    out += stroke_test(
        rig, current_range=(lo, hi), seeds=seeds[len(rows) :], scale=scale, rows=stroke_rows
    )
    return ExperimentSet(out, name=f"control_extension_seed{seed}")
