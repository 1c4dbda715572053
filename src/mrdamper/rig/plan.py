"""A rig test plan: the commands of the design of experiments, for a physical rig.

The virtual rig turns a displacement command and a current command into a measured record
(:class:`~mrdamper.rig.virtual_rig.VirtualRig`). A laboratory that wants to run the same design
on its own damper needs the commands, not the virtual measurement: :class:`PlanRig` is a rig that
records the commands it is given instead of running them, so the generators of Table II
(:func:`~mrdamper.rig.doe.table_ii`) and of the control-oriented extension
(:func:`~mrdamper.control.loop.doe_extension.control_extension`) produce the plan with the same
code,
seeds and scaling rules as the virtual records.

Each planned record carries the displacement command ``x`` [m], its velocity (central difference
of the command) [m/s], the electrical command [A or V] and, as ``F``, the force the damper
estimate (the rig's ``damper``: for a physical rig, a model of *that* damper, e.g. fitted on its
Table II records) predicts for the command [N]. :func:`plan_limits` checks every record against
the rig's limits (:class:`RigLimits`: stroke, velocity, electrical range, load cell) and reports
the margins; nothing is rescaled silently.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.data import Experiment
from mrdamper.data.experiment import CHANNELS
from mrdamper.errors import DataValidationError
from mrdamper.rig.virtual_rig import VirtualRig, commands
from mrdamper.signals.common import SeedLike

__all__ = ["PLAN_NAME", "PLAN_SOURCE", "PlanRig", "RigLimits", "plan_limits", "write_plan"]

#: Metadata ``source`` of a planned record.
PLAN_SOURCE = "rig test plan"
#: File name of the plan's table (one row per record, see :func:`plan_limits`).
PLAN_NAME = "plan.csv"


class PlanRig(VirtualRig):
    """A rig that returns its commands instead of a measurement (see the module docstring).

    Same parameters as :class:`~mrdamper.rig.virtual_rig.VirtualRig`; its actuator's stroke, its
    driver's limits and its load cell's range are the limits the generators respect, and its
    damper is the estimate that gives the planned force.
    """

    def run(
        self,
        x_command: Any,
        i_command: Any,
        *,
        seed: SeedLike,
        name: str = "rig",
        metadata: Mapping[str, Any] | None = None,
        seed_label: int | str | None = None,
    ) -> Experiment:
        """The planned record of one test: the commands and the estimated force.

        Parameters
        ----------
        x_command : array_like
            Displacement command about mid-stroke [m], one value per sample at ``fs``.
        i_command : array_like
            Current command [A] (or voltage [V] for a voltage-driven damper), same length.
        seed : int or numpy.random.SeedSequence
            Unused by the plan (the generators pass the seed of the rig run).
        name : str
            Record name.
        metadata : mapping, optional
            Metadata of the record; ``source`` is set to :data:`PLAN_SOURCE`.
        seed_label : int or str, optional
            Stored as metadata ``seed``.

        Returns
        -------
        Experiment
            ``x`` the command [m], ``v`` its central difference [m/s], the electrical command,
            ``F`` the damper estimate's force for the command [N].
        """
        x, e = commands(x_command, i_command)
        t = np.arange(x.size) / self.fs
        v = np.gradient(x) * self.fs
        elec: dict[str, Any] = {self.electrical_channel: e}
        record = Experiment(t=t, x=x, v=v, F=np.zeros_like(x), name=name, **elec)
        force = np.asarray(self.model.predict(record), dtype=np.float64)
        meta: dict[str, Any] = dict(metadata or {})
        meta.update(source=PLAN_SOURCE, damper=self.model.kind, fs=self.fs)
        if seed_label is not None:
            meta["seed"] = seed_label
        return Experiment(t=t, x=x, v=v, F=force, name=name, metadata=meta, **elec)


@dataclass(frozen=True)
class RigLimits:
    """The limits a physical rig imposes on a test plan.

    Parameters
    ----------
    stroke : float
        Total actuator stroke [m]; commands must stay within ``+-stroke / 2``.
    velocity : float or None
        Largest actuator velocity [m/s] (None: not checked, only reported).
    electrical : (float, float)
        Range of the current (or voltage) driver [A or V].
    load_cell : float
        Largest force the load cell reads [N].
    """

    stroke: float
    velocity: float | None
    electrical: tuple[float, float]
    load_cell: float

    @classmethod
    def of(cls, rig: VirtualRig, velocity: float | None = None) -> RigLimits:
        """The limits of ``rig`` (its actuator, driver and load cell), with ``velocity`` [m/s]."""
        if velocity is not None and not (np.isfinite(velocity) and velocity > 0):
            raise DataValidationError(
                "velocity", f"expected a positive velocity limit in m/s, got {velocity!r}"
            )
        return cls(
            stroke=float(rig.actuator.stroke),
            velocity=None if velocity is None else float(velocity),
            electrical=(float(rig.driver.limits[0]), float(rig.driver.limits[1])),
            load_cell=float(min(abs(b) for b in rig.sensors.force.range)),
        )


def plan_limits(records: Iterable[Experiment], limits: RigLimits) -> pd.DataFrame:
    """Check every planned record against the rig's limits.

    Parameters
    ----------
    records : iterable of Experiment
        Planned records (:class:`PlanRig`).
    limits : RigLimits
        The rig's limits.

    Returns
    -------
    pandas.DataFrame
        One row per record: ``record``, ``pattern`` and ``displacement`` (from the metadata),
        ``duration [s]``, ``peak travel [mm]``,
        ``stroke limit [mm]`` (half the stroke), ``peak velocity [m/s]``,
        ``velocity limit [m/s]`` (empty when not given), ``input min`` and ``input max`` (in the
        record's unit), ``input unit``, ``peak force [N]`` (the damper estimate's),
        ``load cell [N]`` and ``exceeds`` (the limits the record exceeds, comma-separated; empty
        when it is within all of them).
    """
    rows = []
    lo, hi = limits.electrical
    for rec in records:
        channel = rec.electrical_channel
        e = rec.electrical(channel)
        travel = float(np.max(np.abs(rec.x)))
        speed = float(np.max(np.abs(rec.v)))
        force = float(np.max(np.abs(rec.F)))
        exceeds = []
        if travel > limits.stroke / 2:
            exceeds.append("stroke")
        if limits.velocity is not None and speed > limits.velocity:
            exceeds.append("velocity")
        if float(np.min(e)) < lo or float(np.max(e)) > hi:
            exceeds.append("current" if channel == "i" else "voltage")
        if force > limits.load_cell:
            exceeds.append("load cell")
        rows.append(
            {
                "record": rec.name,
                "pattern": rec.metadata.get("pattern", ""),
                "displacement": rec.metadata.get("displacement", ""),
                "duration [s]": rec.n / rec.fs,
                "peak travel [mm]": 1e3 * travel,
                "stroke limit [mm]": 1e3 * limits.stroke / 2,
                "peak velocity [m/s]": speed,
                "velocity limit [m/s]": limits.velocity,
                "input min": float(np.min(e)),
                "input max": float(np.max(e)),
                "input unit": CHANNELS[channel],
                "peak force [N]": force,
                "load cell [N]": limits.load_cell,
                "exceeds": ", ".join(exceeds),
            }
        )
    return pd.DataFrame(rows)


def write_plan(
    records: Iterable[Experiment],
    table: pd.DataFrame,
    out_dir: str | os.PathLike[str],
    *,
    force: bool = False,
    progress: Callable[[Path], None] | None = None,
) -> Path:
    """Write a test plan: one command file per record and the limits table.

    Each ``<name>.csv`` has the columns ``t [s]``, ``x [m]`` (displacement command about
    mid-stroke) and ``i [A]`` (or ``voltage [V]``), the commands a rig controller replays;
    :data:`PLAN_NAME` is ``table`` (:func:`plan_limits`). Written into a private folder and
    moved into place (:func:`mrdamper._io.write_folder`), so a failure leaves nothing behind.

    Parameters
    ----------
    records : iterable of Experiment
        Planned records (:class:`PlanRig`).
    table : pandas.DataFrame
        Their limits table.
    out_dir : path-like
        Output folder (the caller has checked it with :func:`mrdamper._io.check_output`).
    force : bool
        Merge into an earlier output of mrdamper.
    progress : callable, optional
        Called with the path of each command file once it is written.

    Returns
    -------
    Path
        The plan table.
    """
    from mrdamper._io import atomic_write_text, write_folder

    planned = list(records)

    def build(tmp: Path) -> None:
        for rec in planned:
            channel = rec.electrical_channel
            unit = CHANNELS[channel]
            frame = pd.DataFrame(
                {"t [s]": rec.t, "x [m]": rec.x, f"{channel} [{unit}]": rec.electrical(channel)}
            )
            atomic_write_text(
                tmp / f"{rec.name}.csv", frame.to_csv(index=False, float_format="%.9g")
            )
            if progress is not None:
                progress(tmp / f"{rec.name}.csv")
        atomic_write_text(tmp / PLAN_NAME, table.to_csv(index=False, float_format="%.6g"))

    out = Path(out_dir)
    write_folder(out, build, force=force, mode="merge")
    return out / PLAN_NAME
