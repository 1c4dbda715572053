"""A control-oriented extension of the design of experiments, beside the paper's Table II.

Table II moves the damper at up to about 0.15 m/s; a quarter car on ISO 8608 roads moves it at up
to about 1.2 m/s and a semi-active controller switches the current while it moves fast. A model
identified on Table II alone is extrapolated there. The extension replays quarter-car damper
motions on the rig:

* the damper travel of a quarter car with a linear damper (the project's default car: m_s 300 kg,
  m_u 40 kg, k_s 20 kN/m, k_t 200 kN/m; damping ``c`` per row) on an ISO 8608 road at physical
  amplitude (band 0.3-30 Hz) at a speed, computed exactly for the piecewise-linear road
  (zero-order-hold discretisation of the car on its road derivative);
* high-passed at :data:`HIGHPASS` (3 Hz: the slow body motion carries stroke, not velocity, and
  the wheel-hop motion is kept; zero-phase Butterworth, second order; with 1 Hz the scaled records
  reached only 0.5 m/s) and scaled down, if needed, to 90 % of half the rig's stroke
  (velocities shrink by the same factor), with 0.5 s raised-cosine fades, and further if the
  rig's damper with the record's current would need more than :data:`LOAD_SHARE` of the load
  cell's range (the shipped reference damper exceeds the 5 kN load cell near 1.2 m/s at 1 A);
* the current is an APRBS over the DoE current range with a minimum hold of :data:`HOLD` (50 ms:
  the switching of a skyhook controller at 1 kHz is that fast while the damper moves).

:data:`CONTROL_EXTENSION` lists the rows (180 s of rig time at ``scale=1``, 3 % of Table II's
5820 s). Seeds: ``numpy.random.SeedSequence(seed)`` split into one child per record, as
:func:`~mrdamper.rig.doe.table_ii` does; a different root seed gives held-out records.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm
from scipy.signal import butter, sosfiltfilt

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.rig.doe import current_range, record_seeds
from mrdamper.rig.virtual_rig import VirtualRig
from mrdamper.signals import aprbs, road_profile
from mrdamper.signals.common import check_positive, child_seeds

__all__ = ["CAR", "CONTROL_EXTENSION", "HIGHPASS", "HOLD", "ControlRow", "control_extension"]

#: Quarter car (m_s [kg], m_u [kg], k_s [N/m], k_t [N/m]) whose damper motion is replayed.
CAR = (300.0, 40.0, 20e3, 200e3)
#: High-pass corner of the replayed travel [Hz].
HIGHPASS = 3.0
#: APRBS minimum hold of the current [s].
HOLD = 0.05
FILL = 0.9
#: Largest share of the load cell's range the damper may need (at the highest current).
LOAD_SHARE = 0.9


@dataclass(frozen=True)
class ControlRow:
    """One row of the extension: ISO 8608 class, speed [m/s], linear damping [N s/m], record
    length [s] (before ``scale``)."""

    road_class: str
    speed: float
    c: float
    duration: float = 30.0


#: The extension's rows (one record each).
CONTROL_EXTENSION: tuple[ControlRow, ...] = (
    ControlRow("B", 25.0, 1500.0),
    ControlRow("C", 10.0, 1500.0),
    ControlRow("C", 25.0, 3000.0),
    ControlRow("D", 10.0, 3000.0),
    ControlRow("D", 25.0, 1500.0),
    ControlRow("C", 20.0, 800.0),
)


def _travel(z_r: np.ndarray, fs: float, c: float) -> np.ndarray:
    """Damper travel ``z_s - z_u`` [m] of :data:`CAR` with damping ``c`` on the road ``z_r``."""
    m_s, m_u, k_s, k_t = CAR
    A = np.array(
        [
            [0.0, 1.0, 0.0, 0.0],
            [-k_s / m_s, -c / m_s, k_s / m_s, c / m_s],
            [0.0, 0.0, 0.0, 1.0],
            [k_s / m_u, c / m_u, -(k_s + k_t) / m_u, -c / m_u],
        ]
    )
    B = np.array([0.0, 0.0, 0.0, k_t / m_u])
    # augmented with the road (integrator of its piecewise-constant slope): exact for a
    # piecewise-linear road
    M = np.zeros((6, 6))
    M[:4, :4] = A
    M[:4, 4] = B
    M[4, 5] = 1.0
    E = expm(M / fs)
    slope = np.diff(z_r) * fs
    s = np.zeros(6)
    s[4] = z_r[0]
    out = np.empty(z_r.size)
    out[0] = 0.0
    for k in range(slope.size):
        s[5] = slope[k]
        s = E @ s
        out[k + 1] = s[0] - s[2]
    return out


def _motion(row: ControlRow, fs: float, duration: float, stroke: float, ss: object) -> np.ndarray:
    z_r = road_profile(
        fs,
        duration,
        seed=ss,  # type: ignore[arg-type]
        road_class=row.road_class,
        speed=row.speed,
        max_frequency=30.0,
        min_frequency=0.3,
        stroke=1e3,
        fill=None,
    )
    x = sosfiltfilt(butter(2, HIGHPASS, btype="high", fs=fs, output="sos"), _travel(z_r, fs, row.c))
    n_fade = min(int(0.5 * fs), x.size // 4)
    w = np.ones(x.size)
    w[:n_fade] = 0.5 - 0.5 * np.cos(np.pi * np.arange(n_fade) / n_fade)
    w[x.size - n_fade :] = w[:n_fade][::-1]
    x = x * w
    peak = float(np.max(np.abs(x)))
    limit = FILL * stroke / 2.0
    return x * (limit / peak) if peak > limit else x


def _within_load_cell(x: np.ndarray, rig: VirtualRig, e: np.ndarray) -> np.ndarray:
    """``x`` scaled down until the rig's damper, driven by ``e``, needs at most
    :data:`LOAD_SHARE` of the load cell's range (as an operator's trial run)."""
    limit = LOAD_SHARE * min(abs(b) for b in rig.sensors.force.range)
    for _ in range(8):
        v = np.gradient(x) * rig.fs
        t = np.arange(x.size) / rig.fs
        channels: dict[str, Any] = {"t": t, "x": x, "v": v, "F": np.zeros_like(x)}
        channels[str(rig.model.input)] = e
        probe = Experiment(**channels)
        peak = float(np.max(np.abs(rig.model.predict(probe))))
        if peak <= limit:
            break
        x = x * 0.95 * limit / peak
    return x


def control_extension(
    seed: int = 1,
    scale: float = 1.0,
    fs: float = 1000.0,
    damper: FittedModel | None = None,
    *,
    rig: VirtualRig | None = None,
    rows: tuple[ControlRow, ...] = CONTROL_EXTENSION,
) -> ExperimentSet:
    """Generate the control-oriented extension on the virtual rig (see the module docstring).

    Parameters
    ----------
    seed : int
        Root seed (default 1: not the seed of Table II's default 0); same seed, same bytes.
    scale : float
        Duration factor [-] (records at least 2 s).
    fs : float
        Sampling rate [Hz].
    damper : FittedModel, optional
        Damper under test (default: the shipped reference damper).
    rig : VirtualRig, optional
        A configured rig instead of ``fs`` and ``damper``.
    rows : tuple of ControlRow
        The rows (default :data:`CONTROL_EXTENSION`).

    Returns
    -------
    ExperimentSet
        Records ``ctrl{k:02d}`` with metadata ``pattern="APRBS"``,
        ``displacement="quarter car, ISO <class> @ <speed> m/s"``, ``duration``, ``seed``.
    """
    scale = check_positive("scale", scale, "-")
    if rig is None:
        rig = VirtualRig(damper=damper, fs=check_positive("fs", fs, "Hz"))
    elif damper is not None:
        raise DataValidationError("damper", "give either damper or rig, not both")
    lo, hi = current_range(rig.model, rig)
    out = []
    for k, (row, s) in enumerate(zip(rows, record_seeds(seed, len(rows)), strict=True), start=1):
        duration = row.duration * scale
        if duration < 2.0:
            raise DataValidationError(
                "scale", f"{scale:g} makes record {k} {duration:g} s; at least 2 s is needed"
            )
        s_x, s_i, s_rig = child_seeds(s, 3)
        i_cmd = aprbs(rig.fs, duration, low=lo, high=hi, min_hold=HOLD, seed=s_i)
        x_cmd = _motion(row, rig.fs, duration, rig.actuator.stroke, s_x)
        x_cmd = _within_load_cell(x_cmd, rig, i_cmd)
        meta = {
            "pattern": "APRBS",
            "displacement": f"quarter car, ISO {row.road_class} @ {row.speed:g} m/s",
            "duration": duration,
            "current_range": (lo, hi),
        }
        out.append(
            rig.run(x_cmd, i_cmd, seed=s_rig, name=f"ctrl{k:02d}", metadata=meta, seed_label=s)
        )
    return ExperimentSet(out, name=f"control_extension_seed{seed}")
