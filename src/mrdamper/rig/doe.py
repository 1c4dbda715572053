"""The paper's design of experiments (Table II) on the virtual rig.

Table II of the paper lists eight training sequences (displacement pattern, current pattern,
duration, replicates, maximum excitation frequency)::

    exp  displacement        current  duration [s]  replicates  max. freq. [Hz]
    1    Road Profile        ICPS     30            11          5.5
    2    Road Profile        APRBS    30            11          4.5
    3    Road Profile        PRBS     30            11          4.2
    4    Long Road Profile   APRBS    600           3           4.5
    5    Long Road Profile   ICPS     600           4           5.5
    6    Road Profile        SC       30            7           5.5
    7    Road Profile        SC       30            7           4.5
    8    Road Profile        SC       30            7           4.5

61 records, 5820 s in all (5.82 million samples at 1 kHz). The paper gives no more detail; the
settings this module adds (documented in ``docs/rig.md``) are:

* The maximum frequency is the upper band limit of the road displacement (ISO 8608 class C at
  20 m/s for "Road Profile"; class B-D sections at 10-30 m/s for "Long Road Profile"; band from
  0.2 Hz; scaled to 90 % of half the 0.04 m stroke).
* Current range: 0 to the upper bound of the damper's identified input range. The shipped
  reference damper is calibrated on 0-1 A, so the DoE spans 0-1 A, not the paper's 0-4 A.
* PRBS: clock period 0.1 s, two levels (range ends). APRBS: minimum hold 0.2 s. ICPS (reading of
  ``paper/READING-NOTES.md`` item 8): clock period 1 s, 5 equally spaced levels. SC: 5 equally
  spaced levels, upwards (exp 6), downwards (exp 7), up and back down (exp 8).
* Seeds: ``numpy.random.SeedSequence(seed)`` is split into one child per record (in table order);
  each child gives a 63-bit record seed (metadata ``seed``), from which the displacement, current
  and rig streams are split in turn. :func:`make_record` rebuilds one record from it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.rig.virtual_rig import VirtualRig
from mrdamper.signals import (
    aprbs,
    constant,
    icps,
    long_road_profile,
    prbs,
    road_profile,
    stepped_current,
)
from mrdamper.signals.common import check_positive, child_seeds

__all__ = [
    "APRBS_MIN_HOLD",
    "ICPS_CLOCK",
    "ICPS_LEVELS",
    "PRBS_CLOCK",
    "SC_LEVELS",
    "TABLE_II",
    "DoeSequence",
    "constant_current_sweep",
    "make_record",
    "record_seeds",
    "table_ii",
]

Pattern = Literal["ICPS", "APRBS", "PRBS", "SC"]
Displacement = Literal["Road Profile", "Long Road Profile"]

#: PRBS clock period [s].
PRBS_CLOCK = 0.1
#: APRBS minimum hold [s].
APRBS_MIN_HOLD = 0.2
#: ICPS increased clock period [s] and number of levels.
ICPS_CLOCK = 1.0
ICPS_LEVELS = 5
#: Number of SC levels.
SC_LEVELS = 5
#: Shortest record the DoE accepts after scaling [s].
MIN_DURATION = 2.0


@dataclass(frozen=True)
class DoeSequence:
    """One row of Table II.

    Attributes
    ----------
    experiment : int
        Sequence number 1-8.
    displacement : {"Road Profile", "Long Road Profile"}
        Displacement pattern.
    pattern : {"ICPS", "APRBS", "PRBS", "SC"}
        Current pattern.
    duration : float
        Record length [s] (before ``scale``).
    replicates : int
        Number of replicates.
    max_frequency : float
        Maximum excitation frequency [Hz].
    direction : str
        SC staircase direction (``"up"``, ``"down"``, ``"up-down"``; unused otherwise).
    """

    experiment: int
    displacement: Displacement
    pattern: Pattern
    duration: float
    replicates: int
    max_frequency: float
    direction: str = "up"


#: The paper's Table II.
TABLE_II: tuple[DoeSequence, ...] = (
    DoeSequence(1, "Road Profile", "ICPS", 30.0, 11, 5.5),
    DoeSequence(2, "Road Profile", "APRBS", 30.0, 11, 4.5),
    DoeSequence(3, "Road Profile", "PRBS", 30.0, 11, 4.2),
    DoeSequence(4, "Long Road Profile", "APRBS", 600.0, 3, 4.5),
    DoeSequence(5, "Long Road Profile", "ICPS", 600.0, 4, 5.5),
    DoeSequence(6, "Road Profile", "SC", 30.0, 7, 5.5, "up"),
    DoeSequence(7, "Road Profile", "SC", 30.0, 7, 4.5, "down"),
    DoeSequence(8, "Road Profile", "SC", 30.0, 7, 4.5, "up-down"),
)


def current_range(damper: FittedModel, rig: VirtualRig) -> tuple[float, float]:
    """Current range of the DoE: 0 (or the range's lower bound) to the damper's upper bound."""
    lo, hi = (float(b) for b in damper.input_range)
    lo = max(lo, rig.driver.limits[0], 0.0)
    hi = min(hi, rig.driver.limits[1])
    if not hi > lo:
        raise DataValidationError(
            "damper",
            f"input_range {damper.input_range} within driver limits {rig.driver.limits} leaves no "
            f"current range for the DoE",
        )
    return lo, hi


def _seed_int(ss: np.random.SeedSequence) -> int:
    a, b = (int(w) for w in ss.generate_state(2, np.uint32))
    return ((a << 32) | b) >> 1  # 63 bits: fits a signed 64-bit integer in any table


def record_seeds(seed: int, n: int) -> list[int]:
    """The per-record seeds of a DoE built from ``seed`` (record order)."""
    return [_seed_int(c) for c in child_seeds(seed, n)]


def _current(
    spec: DoeSequence, fs: float, duration: float, lo: float, hi: float, ss: np.random.SeedSequence
) -> np.ndarray:
    if spec.pattern == "PRBS":
        return prbs(fs, duration, clock_period=PRBS_CLOCK, levels=(lo, hi), seed=ss)
    if spec.pattern == "APRBS":
        return aprbs(fs, duration, low=lo, high=hi, min_hold=APRBS_MIN_HOLD, seed=ss)
    if spec.pattern == "ICPS":
        return icps(
            fs, duration, low=lo, high=hi, clock_period=ICPS_CLOCK, n_levels=ICPS_LEVELS, seed=ss
        )
    if spec.pattern == "SC":
        return stepped_current(
            fs,
            duration,
            low=lo,
            high=hi,
            n_levels=SC_LEVELS,
            direction=spec.direction,  # type: ignore[arg-type]
        )
    raise DataValidationError("pattern", f"expected ICPS, APRBS, PRBS or SC, got {spec.pattern!r}")


def _displacement(
    spec: DoeSequence, fs: float, duration: float, stroke: float, ss: np.random.SeedSequence
) -> np.ndarray:
    if spec.displacement == "Road Profile":
        return road_profile(
            fs,
            duration,
            seed=ss,
            road_class="C",
            speed=20.0,
            max_frequency=spec.max_frequency,
            stroke=stroke,
        )
    if spec.displacement == "Long Road Profile":
        return long_road_profile(
            fs, duration, seed=ss, max_frequency=spec.max_frequency, stroke=stroke
        )
    raise DataValidationError(
        "displacement", f"expected 'Road Profile' or 'Long Road Profile', got {spec.displacement!r}"
    )


def _check_scale(scale: float, specs: Sequence[DoeSequence]) -> float:
    scale = check_positive("scale", scale, "-")
    shortest = min(s.duration for s in specs) * scale
    if shortest < MIN_DURATION:
        raise DataValidationError(
            "scale",
            f"{scale:g} makes the shortest record {shortest:g} s; at least {MIN_DURATION:g} s is "
            "needed",
        )
    return scale


def make_record(
    spec: DoeSequence, replicate: int, record_seed: int, rig: VirtualRig, scale: float = 1.0
) -> Experiment:
    """Build one DoE record from its sequence, replicate number and record seed.

    Parameters
    ----------
    spec : DoeSequence
        The Table II row.
    replicate : int
        Replicate number (1-based), used in the name and metadata.
    record_seed : int
        The record's seed (metadata ``seed`` of a :func:`table_ii` record).
    rig : VirtualRig
        The rig (damper, sampling rate, hardware).
    scale : float
        Duration factor [-].

    Returns
    -------
    Experiment
        Named ``exp{experiment}_rep{replicate:02d}``.
    """
    fs = rig.fs
    duration = spec.duration * check_positive("scale", scale, "-")
    lo, hi = current_range(rig.model, rig)
    s_x, s_i, s_rig = child_seeds(record_seed, 3)
    x_cmd = _displacement(spec, fs, duration, rig.actuator.stroke, s_x)
    i_cmd = _current(spec, fs, duration, lo, hi, s_i)
    meta = {
        "experiment": spec.experiment,
        "replicate": int(replicate),
        "pattern": spec.pattern,
        "displacement": spec.displacement,
        "duration": duration,
        "max_frequency": spec.max_frequency,
        "current_range": (lo, hi),
    }
    name = f"exp{spec.experiment}_rep{int(replicate):02d}"
    return rig.run(x_cmd, i_cmd, seed=s_rig, name=name, metadata=meta, seed_label=int(record_seed))


def resolve_rig(rig: VirtualRig | None, damper: FittedModel | None, fs: float) -> VirtualRig:
    """The rig a DoE generator runs on: ``rig`` itself, or a new rig with ``damper`` (default:
    the shipped reference damper) sampled at ``fs`` [Hz]; giving both ``rig`` and ``damper`` is
    refused in one line."""
    if rig is None:
        return VirtualRig(damper=damper, fs=check_positive("fs", fs, "Hz"))
    if damper is not None:
        raise DataValidationError("damper", "give either damper or rig, not both")
    return rig


def table_ii(
    seed: int = 0,
    scale: float = 1.0,
    fs: float = 1000.0,
    damper: FittedModel | None = None,
    *,
    rig: VirtualRig | None = None,
    experiments: Sequence[int] | None = None,
    workers: int = 1,
    progress: Callable[[Experiment], None] | None = None,
) -> ExperimentSet:
    """Generate the paper's Table II design of experiments on the virtual rig.

    Parameters
    ----------
    seed : int
        Root seed; same seed, same bytes.
    scale : float
        Duration factor (0.1 gives 3 s and 60 s records). Clock periods and dwell limits are not
        scaled.
    fs : float
        Sampling rate [Hz].
    damper : FittedModel, optional
        Damper under test (default: the shipped reference damper).
    rig : VirtualRig, optional
        A fully configured rig instead of ``fs`` and ``damper`` (its own ``fs`` and damper are
        used).
    experiments : sequence of int, optional
        Generate only these sequence numbers (seeds stay those of the full table).
    workers : int
        Worker processes (default 1: in this process). Records are independent and fully
        determined by their seeds, so any number of workers gives the same bytes.
    progress : callable, optional
        Called with each record as it is finished (in completion order), e.g. to show progress.

    Returns
    -------
    ExperimentSet
        61 records named ``exp{k}_rep{r:02d}``, with metadata ``experiment``, ``replicate``,
        ``pattern``, ``duration``, ``max_frequency``, ``seed``, ``source="virtual rig"``.

    Examples
    --------
    >>> doe = table_ii(seed=0, scale=0.1)  # doctest: +SKIP
    >>> len(doe), doe[0].name  # doctest: +SKIP
    (61, 'exp1_rep01')
    """
    scale = _check_scale(scale, TABLE_II)
    rig = resolve_rig(rig, damper, fs)
    rows = [(spec, r) for spec in TABLE_II for r in range(1, spec.replicates + 1)]
    wanted = None if experiments is None else {int(k) for k in experiments}
    if wanted is not None and not wanted <= {s.experiment for s in TABLE_II}:
        raise DataValidationError("experiments", f"expected numbers 1-8, got {sorted(wanted)}")
    seeds = record_seeds(seed, len(rows))
    jobs = [
        (spec, r, s)
        for (spec, r), s in zip(rows, seeds)
        if wanted is None or spec.experiment in wanted
    ]
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise DataValidationError("workers", f"expected an int >= 1, got {workers!r}")
    if workers == 1 or len(jobs) < 2:
        records = []
        for spec, r, s in jobs:
            records.append(make_record(spec, r, s, rig, scale))
            if progress is not None:
                progress(records[-1])
    else:
        records = _make_parallel(jobs, rig, scale, int(workers), progress)
    return ExperimentSet(records, name=f"table_ii_seed{seed}")


def _payload(job: tuple[DoeSequence, int, int], rig: VirtualRig, scale: float) -> dict[str, Any]:
    """One record as plain, picklable data (Experiment metadata is a read-only mapping proxy)."""
    rec = make_record(job[0], job[1], job[2], rig, scale)
    out: dict[str, Any] = {c: getattr(rec, c) for c in rec.channel_names}
    out.update(name=rec.name, metadata=dict(rec.metadata))
    return out


def _make_parallel(
    jobs: list[tuple[DoeSequence, int, int]],
    rig: VirtualRig,
    scale: float,
    workers: int,
    progress: Callable[[Experiment], None] | None = None,
) -> list[Experiment]:
    """Records in worker processes; each is fully determined by its seed, so order and bytes are
    those of the serial run. Long records go first so the workers finish together."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor, as_completed

    order = sorted(range(len(jobs)), key=lambda k: -jobs[k][0].duration)
    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("fork" if "fork" in methods else None)
    from mrdamper._io.processes import init_worker, stop_pool

    pool = ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=init_worker, initargs=(os.getpid(),)
    )
    try:
        futures = {pool.submit(_payload, jobs[k], rig, scale): k for k in order}
        records: dict[int, Experiment] = {}
        for f in as_completed(futures):
            records[futures[f]] = Experiment(**f.result())
            if progress is not None:
                progress(records[futures[f]])
    except BaseException:
        stop_pool(pool)  # interrupted or failed: no worker keeps running
        raise
    pool.shutdown(wait=True)
    return [records[k] for k in range(len(jobs))]


def constant_current_sweep(
    currents: Sequence[float] | None = None,
    *,
    seed: int = 0,
    duration: float = 30.0,
    fs: float = 1000.0,
    max_frequency: float = 5.0,
    replicates: int = 1,
    damper: FittedModel | None = None,
    rig: VirtualRig | None = None,
) -> ExperimentSet:
    """Road-profile records at constant current levels (for the F-v zone analysis).

    Parameters
    ----------
    currents : sequence of float, optional
        Current levels [A]; default 5 equally spaced levels over the DoE current range.
    seed : int
        Root seed (one child per record).
    duration : float
        Record length [s].
    fs : float
        Sampling rate [Hz].
    max_frequency : float
        Road band limit [Hz].
    replicates : int
        Records per level.
    damper, rig
        As in :func:`table_ii`.

    Returns
    -------
    ExperimentSet
        Records ``cc_{level}A_rep{r:02d}`` with metadata ``pattern="constant"``, ``current``,
        ``replicate``, ``seed``.
    """
    if rig is None:
        rig = VirtualRig(damper=damper, fs=fs)
    lo, hi = current_range(rig.model, rig)
    levels = np.linspace(lo, hi, 5) if currents is None else np.asarray(currents, dtype=float)
    if levels.ndim != 1 or levels.size == 0:
        raise DataValidationError(
            "currents", f"expected a non-empty list of levels [A], got {currents!r}"
        )
    if (
        isinstance(replicates, bool)
        or not isinstance(replicates, (int, np.integer))
        or replicates < 1
    ):
        raise DataValidationError("replicates", f"expected an int >= 1, got {replicates!r}")
    seeds = record_seeds(seed, levels.size * int(replicates))
    out = []
    k = 0
    for level in levels:
        for r in range(1, int(replicates) + 1):
            s_x, _, s_rig = child_seeds(seeds[k], 3)
            x_cmd = road_profile(
                rig.fs, duration, seed=s_x, max_frequency=max_frequency, stroke=rig.actuator.stroke
            )
            i_cmd = constant(rig.fs, duration, value=float(level))
            meta = {
                "pattern": "constant",
                "current": float(level),
                "replicate": r,
                "duration": float(duration),
                "max_frequency": float(max_frequency),
            }
            out.append(
                rig.run(
                    x_cmd,
                    i_cmd,
                    seed=s_rig,
                    name=f"cc_{float(level):g}A_rep{r:02d}",
                    metadata=meta,
                    seed_label=int(seeds[k]),
                )
            )
            k += 1
    return ExperimentSet(out, name=f"constant_current_seed{seed}")
