"""Replaying quarter-car damper motions on the rig: the rows and the rig side of the
control-oriented extension of the design of experiments.

Table II moves the damper at up to about 0.15 m/s; a quarter car on ISO 8608 roads moves it at
up to about 1.2 m/s and a semi-active controller switches the current while it moves fast. A
model identified on Table II alone is extrapolated there. The extension
(:func:`mrdamper.control.loop.doe_extension.control_extension`) runs the quarter car in the loop
with a
first model of the damper, one run per row of :data:`CONTROL_EXTENSION` (an ISO 8608 road at a
speed, one controller), and this module replays each run's damper travel on the rig
(:func:`replay_loop_motion`):

* the travel is high-passed at :data:`HIGHPASS` (2.5 Hz; zero-phase Butterworth, second order:
  the body motion, near 1.2 Hz, carries most of the stroke and less of the velocity than the
  wheel hop near 10 Hz), given 0.5 s raised-cosine fades and scaled down, if needed, to 90 % of
  half the rig's stroke (velocities shrink by the same factor), and
  further if the rig's damper would need more than :data:`LOAD_SHARE` of the load cell's range
  (the shipped reference damper exceeds the 5 kN load cell near 1.2 m/s at 1 A);
* it is replayed twice: with the loop's own current history (the current a controller applies
  while the damper moves, correlated with the motion as in use) and with an APRBS current over
  the DoE range with a minimum hold of :data:`HOLD` (50 ms: switching as fast as a skyhook
  controller at 1 kHz does, uncorrelated with the motion).

The high-pass takes the body band out of the replays, and with it most of the stroke. The
extension therefore also puts a *stroke test* on the rig (:func:`stroke_test`, rows
:data:`STROKE_TEST`): slow sines over 90 % of half the stroke at body-band frequencies (0.5, 1
and 1.5 Hz) at three constant currents. There a force in phase with the travel (a gas
accumulator's stiffness, ``k1 (x - x0)`` in the Spencer model) is a visible share of the
force; in the replays and in Table II it is under 2 %, and a model identified on them cannot tell
a damper with the stiffness from one without (``docs/results.md``, "Parallel stiffness").

Rig time: 2 x 15 rows x 30 s = 900 s at ``scale=1`` (15 % of Table II's 5820 s), plus the stroke
test's 55 s (33 s at ``scale=0.1``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.signal import butter, sosfiltfilt

from mrdamper.controller_names import BUILTIN_CONTROLLERS
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError
from mrdamper.rig.virtual_rig import VirtualRig
from mrdamper.signals import aprbs, ramped_sine

__all__ = [
    "CONTROLLERS",
    "CONTROL_EXTENSION",
    "HIGHPASS",
    "HOLD",
    "STROKE_TEST",
    "ControlRow",
    "StrokeRow",
    "replay_loop_motion",
    "stroke_test",
]

#: High-pass corner of the replayed travel [Hz]. At 1 Hz (the corner before) the body motion kept
#: most of the stroke, the stroke limit scaled the rougher rows' replays down (0.11-0.17 m/s RMS
#: velocity against 0.20-0.24 m/s at 2.5 Hz), and an LPV model trained on them gave the soft
#: damper 6-8 % too much force in the loop (``docs/results.md``, "Full-length DoE").
HIGHPASS = 2.5
#: APRBS minimum hold of the current [s].
HOLD = 0.05
#: Share of half the rig's stroke the replayed travel may use [-].
FILL = 0.9
#: Largest share of the load cell's range the damper may need [-].
LOAD_SHARE = 0.9
#: Raised-cosine fade at each end of a record [s].
FADE = 0.5
#: The controllers of the loop runs (the built-in controllers' names, read without loading the
#: loops: :mod:`mrdamper.controller_names`).
CONTROLLERS = BUILTIN_CONTROLLERS


@dataclass(frozen=True)
class ControlRow:
    """One loop run of the extension: ISO 8608 class, speed [m/s], controller, road length [s]
    (before ``scale``). Each row gives two records (loop current, APRBS current)."""

    road_class: str
    speed: float
    controller: str
    duration: float = 30.0


#: The extension's rows: three roads (ISO B at 25 m/s, C at 20 m/s, D at 10 m/s) x the five
#: controllers.
CONTROL_EXTENSION: tuple[ControlRow, ...] = tuple(
    ControlRow(cls, speed, c)
    for cls, speed in (("B", 25.0), ("C", 20.0), ("D", 10.0))
    for c in CONTROLLERS
)


@dataclass(frozen=True)
class StrokeRow:
    """One record of the stroke test: sine frequency [Hz], constant current as a share of the
    DoE's range [-] (0: its lower end, 1: its upper end), cycles at full amplitude (before
    ``scale``)."""

    frequency: float
    level: float
    cycles: int = 4


#: The stroke test's rows: the body band (0.5, 1, 1.5 Hz) x the soft end, a quarter and the hard
#: end of the current range.
STROKE_TEST: tuple[StrokeRow, ...] = tuple(
    StrokeRow(f, level) for f in (0.5, 1.0, 1.5) for level in (0.0, 0.25, 1.0)
)


def stroke_test(
    rig: VirtualRig,
    *,
    current_range: tuple[float, float],
    seeds: list[int],
    scale: float = 1.0,
    rows: tuple[StrokeRow, ...] = STROKE_TEST,
    first: int = 1,
) -> list[Experiment]:
    """The stroke test: one slow sine over 90 % of half the rig's stroke per row.

    Parameters
    ----------
    rig : VirtualRig
        The rig.
    current_range : tuple of float
        DoE current range [A or V]; a row's constant current is ``lo + level (hi - lo)``.
    seeds : list of int
        One rig-run seed per row.
    scale : float
        Duration factor [-]: ``max(2, round(cycles * scale))`` cycles per record.
    rows : tuple of StrokeRow
        The records (default :data:`STROKE_TEST`).
    first : int
        Number of the first record's name, ``stroke{first:02d}``.

    Returns
    -------
    list of Experiment
        One record per row, metadata ``pattern`` ("stroke test"), ``displacement``,
        ``frequency`` [Hz] and ``current_range`` (no ``current`` key: Table II's records and the
        replays carry none, and the LPV zone laws group records by it only when every record
        has it); each scaled down, if needed, to the load cell's range as the replays are.
    """
    if len(seeds) != len(rows):
        raise DataValidationError("seeds", f"expected {len(rows)} seeds, got {len(seeds)}")
    lo, hi = current_range
    amplitude = FILL * rig.actuator.stroke / 2.0
    out = []
    for k, (row, s) in enumerate(zip(rows, seeds, strict=True)):
        cycles = max(2, round(row.cycles * scale))
        x = ramped_sine(rig.fs, amplitude=amplitude, frequency=row.frequency, cycles=cycles)
        e = np.full(x.size, lo + row.level * (hi - lo))
        x = _within_load_cell(x, rig, e)
        meta = {
            "pattern": "stroke test",
            "displacement": f"sine {1e3 * np.max(np.abs(x)):.1f} mm @ {row.frequency:g} Hz",
            "frequency": row.frequency,
            "current_range": (lo, hi),
            "duration": x.size / rig.fs,
        }
        out.append(
            rig.run(x, e, seed=s, name=f"stroke{first + k:02d}", metadata=meta, seed_label=s)
        )
    return out


def _fade(x: np.ndarray, fs: float) -> np.ndarray:
    n = min(int(FADE * fs), x.size // 4)
    w = np.ones(x.size)
    w[:n] = 0.5 - 0.5 * np.cos(np.pi * np.arange(n) / n)
    w[x.size - n :] = w[:n][::-1]
    return x * w


def _within_load_cell(x: np.ndarray, rig: VirtualRig, e: np.ndarray) -> np.ndarray:
    """``x`` scaled down until the rig's damper, driven by ``e``, needs at most
    :data:`LOAD_SHARE` of the load cell's range (as an operator's trial run)."""
    limit = LOAD_SHARE * min(abs(b) for b in rig.sensors.force.range)
    for _ in range(8):
        v = np.gradient(x) * rig.fs
        t = np.arange(x.size) / rig.fs
        channels: dict[str, Any] = {"t": t, "x": x, "v": v, "F": np.zeros_like(x)}
        channels[str(rig.model.input)] = e
        peak = float(np.max(np.abs(rig.model.predict(Experiment(**channels)))))
        if peak <= limit:
            break
        x = x * 0.95 * limit / peak
    return x


def replay_loop_motion(
    rig: VirtualRig,
    travel: np.ndarray,
    current: np.ndarray,
    *,
    current_range: tuple[float, float],
    seeds: tuple[np.random.SeedSequence, np.random.SeedSequence, np.random.SeedSequence],
    names: tuple[str, str],
    metadata: dict[str, Any],
    seed_label: int,
    highpass: float = HIGHPASS,
) -> list[Experiment]:
    """Replay one loop run's damper travel on the rig, with its current and with an APRBS one.

    Parameters
    ----------
    rig : VirtualRig
        The rig.
    travel : ndarray
        Damper travel [m] at the rig's rate.
    current : ndarray
        The loop's electrical input [A or V] at the rig's rate (clipped to ``current_range``).
    current_range : tuple of float
        DoE current range [A or V].
    seeds : tuple of SeedSequence
        APRBS current, rig run with the loop current, rig run with the APRBS current.
    names : tuple of str
        Record names (loop current, APRBS current).
    metadata : dict
        Metadata of both records (``pattern`` is added).
    seed_label : int
        Record seed stored in the metadata.
    highpass : float
        High-pass corner of the replayed travel [Hz], below the rig's Nyquist frequency.

    Returns
    -------
    list of Experiment
        The two records.
    """
    if not (np.isfinite(highpass) and 0 < highpass < rig.fs / 2):
        raise DataValidationError(
            "highpass",
            f"expected a corner frequency in (0, {rig.fs / 2:g}) Hz (the rig's Nyquist "
            f"frequency), got {highpass!r}",
        )
    lo, hi = current_range
    x = sosfiltfilt(butter(2, highpass, btype="high", fs=rig.fs, output="sos"), travel)
    x = _fade(x, rig.fs)
    peak = float(np.max(np.abs(x)))
    limit = FILL * rig.actuator.stroke / 2.0
    if peak > limit:
        x = x * (limit / peak)
    e_loop = np.clip(current, lo, hi)
    duration = x.size / rig.fs
    e_aprbs = aprbs(rig.fs, duration, low=lo, high=hi, min_hold=HOLD, seed=seeds[0])[: x.size]
    out = []
    for e, pattern, name, s_rig in (
        (e_loop, "loop current", names[0], seeds[1]),
        (e_aprbs, "APRBS", names[1], seeds[2]),
    ):
        x_e = _within_load_cell(x, rig, e)
        meta = {**metadata, "pattern": pattern, "current_range": (lo, hi)}
        out.append(rig.run(x_e, e, seed=s_rig, name=name, metadata=meta, seed_label=seed_label))
    return out
