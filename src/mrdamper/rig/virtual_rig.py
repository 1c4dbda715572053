"""The virtual test rig: turns displacement and current commands into a measured record.

Signal path of one run (all on the sampling grid ``t = k / fs``)::

    x_command ──► ServoActuator ──► x_true, v_true ─┐
    i_command ──► CurrentDriver ──► i_true ─────────┼─► damper.predict ─► variation ─► F_true
                                                    │
    x_true ──► LVDT ──► x ──► zero-phase low-pass + central difference ──► v
    F_true ──► load cell ──► F          i_true ──► current transducer ──► i

The damper is any :class:`~mrdamper.models.FittedModel`; it sees the *true* actuator motion and
driver output. The record carries what a real rig would provide: measured x, F and i with sensor
noise and quantisation, and v differentiated from the measured LVDT signal (as the real-data
pipeline does, :func:`mrdamper.data.preprocessing.velocity_from_displacement`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
from scipy.signal import butter, sosfiltfilt

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models.base import FittedModel
from mrdamper.rig.actuator import ServoActuator
from mrdamper.rig.driver import CurrentDriver
from mrdamper.rig.sensors import SensorSuite
from mrdamper.rig.variation import ReplicateVariation
from mrdamper.signals.common import SeedLike, as_seed_sequence, check_positive, child_seeds

__all__ = ["VirtualRig"]


def _command(name: str, values: Any) -> np.ndarray:
    try:
        arr = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DataValidationError(name, f"could not be read as numbers ({exc})") from None
    if arr.ndim != 1 or arr.size < 2:
        raise DataValidationError(
            name, f"expected a 1-D array of at least 2 samples, got shape {arr.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise DataValidationError(name, f"non-finite value at sample {int(bad[0])}")
    return arr


def commands(x_command: Any, i_command: Any) -> tuple[np.ndarray, np.ndarray]:
    """The displacement [m] and electrical [A or V] commands of a run, checked: 1-D, finite, at
    least 2 samples, the same length (one-line errors naming the command)."""
    x_cmd = _command("x_command", x_command)
    i_cmd = _command("i_command", i_command)
    if i_cmd.size != x_cmd.size:
        raise DataValidationError(
            "i_command", f"has {i_cmd.size} samples but x_command has {x_cmd.size}"
        )
    return x_cmd, i_cmd


#: Order of one pass of the velocity low-pass (applied forward and backward).
VELOCITY_FILTER_ORDER = 4


def _velocity(x: np.ndarray, fs: float, cutoff: float) -> np.ndarray:
    """Velocity [m/s] as measured-data preprocessing computes it.

    Same steps as :func:`mrdamper.data.preprocessing.velocity_from_displacement`: zero-phase
    Butterworth low-pass of x, then central differences (one-sided at the ends); done here on the
    bare arrays so a rig run builds its record once.
    """
    if not cutoff < fs / 2:
        raise DataValidationError(
            "velocity_cutoff", f"{cutoff:g} Hz is not below the Nyquist frequency {fs / 2:g} Hz"
        )
    sos = butter(VELOCITY_FILTER_ORDER, cutoff, btype="low", fs=fs, output="sos")
    padlen = 3 * (2 * len(sos) + 1)
    if x.size <= padlen:
        raise DataValidationError(
            "x_command",
            f"{x.size} samples are too few for the velocity filter (need more than {padlen})",
        )
    return np.gradient(sosfiltfilt(sos, x), 1.0 / fs)


def _seed_label(seed: SeedLike) -> Any:
    if isinstance(seed, np.random.SeedSequence):
        return f"SeedSequence(entropy={seed.entropy}, spawn_key={tuple(seed.spawn_key)})"
    return int(seed)


@dataclass(frozen=True)
class VirtualRig:
    """A simulated servo-hydraulic MR-damper test rig.

    Parameters
    ----------
    damper : FittedModel, optional
        The damper under test. Default: the shipped reference damper
        (:func:`~mrdamper.rig.reference_damper`, ``"quiroz2022"``). The rig drives the damper's
        electrical input channel (``damper.input``: coil current ``i`` or command ``voltage``).
    fs : float
        Sampling rate of the data acquisition [Hz] (default 1 kHz). Commands are given on this grid
        and the plant is simulated on it.
    actuator : ServoActuator
        Displacement actuator (bandwidth, damping, stroke).
    driver : CurrentDriver
        Current driver (lag, output limits).
    sensors : SensorSuite
        LVDT, load cell and current transducer.
    variation : ReplicateVariation
        Per-run, seeded damper drift (temperature-like gain and offset, optional parameter drift).
    velocity_cutoff : float
        Cut-off of the zero-phase Butterworth low-pass (order 4, applied forward and backward)
        applied to the measured displacement before differentiation [Hz] (default 50 Hz).

    Examples
    --------
    >>> from mrdamper.signals import road_profile, aprbs
    >>> rig = VirtualRig()  # doctest: +SKIP
    >>> x = road_profile(1000.0, 30.0, seed=1)
    >>> i = aprbs(1000.0, 30.0, low=0.0, high=1.0, min_hold=0.2, seed=2)
    >>> record = rig.run(x, i, seed=3, name="demo")  # doctest: +SKIP
    """

    damper: FittedModel | None = None
    fs: float = 1000.0
    actuator: ServoActuator = field(default_factory=ServoActuator)
    driver: CurrentDriver = field(default_factory=CurrentDriver)
    sensors: SensorSuite = field(default_factory=SensorSuite)
    variation: ReplicateVariation = field(default_factory=ReplicateVariation)
    velocity_cutoff: float = 50.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "fs", check_positive("fs", self.fs, "Hz"))
        object.__setattr__(
            self, "velocity_cutoff", check_positive("velocity_cutoff", self.velocity_cutoff, "Hz")
        )
        if not self.velocity_cutoff < self.fs / 2:
            raise DataValidationError(
                "velocity_cutoff",
                f"{self.velocity_cutoff:g} Hz is not below the Nyquist frequency {self.fs / 2:g} "
                "Hz",
            )
        if self.damper is None:
            from mrdamper.rig.reference import reference_damper

            object.__setattr__(self, "damper", reference_damper())
        if not isinstance(self.damper, FittedModel):
            raise DataValidationError(
                "damper", f"expected a FittedModel, got {type(self.damper).__name__}"
            )

    @property
    def model(self) -> FittedModel:
        """The damper under test (never None after construction)."""
        return cast(FittedModel, self.damper)

    @property
    def electrical_channel(self) -> str:
        """Name of the electrical channel the rig drives and records (``"i"`` or ``"voltage"``)."""
        return self.model.input

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
        """Run one test and return the measured record.

        Parameters
        ----------
        x_command : array_like
            Displacement command about mid-stroke [m], one value per sample at ``fs``.
        i_command : array_like
            Current command [A] (or voltage [V] for a voltage-driven damper), same length.
        seed : int or numpy.random.SeedSequence
            Seeds the replicate variation and the sensor noise. Same seed, same bytes.
        name : str
            Record name.
        metadata : mapping, optional
            Extra metadata; the rig adds ``source="virtual rig"``, ``seed``, ``damper`` (kind),
            ``reference_damper`` (the name of the shipped reference damper, or ``"custom"`` for any
            other damper), ``fs`` and the drawn variation (``force_gain``, ``force_drift``,
            ``force_offset``).
        seed_label : int or str, optional
            Value stored as metadata ``seed`` (default: ``seed`` itself, or a description of it for
            a SeedSequence). The DoE stores the record seed the run's SeedSequence derives from.

        Returns
        -------
        Experiment
            The measured record (x, v, F and the electrical channel).

        Raises
        ------
        DataValidationError
            Malformed commands, a command outside the stroke or the driver range, or a sensor
            overload.
        OutOfRangeError
            If the current leaves the damper's identified range and its ``range_policy`` is
            ``"error"``.
        """
        x_cmd, i_cmd = commands(x_command, i_command)
        as_seed_sequence(seed)
        s_var, s_x, s_f, s_i = child_seeds(seed, 4)
        fs = self.fs
        n = x_cmd.size
        t = np.arange(n) / fs
        x_true, v_true = self.actuator.track(x_cmd, fs)
        e_true = self.driver.drive(i_cmd, fs)
        drawn = self.variation.draw(self.model, np.random.default_rng(s_var))
        ch = self.electrical_channel
        zeros = np.zeros(n)
        elec: dict[str, Any] = {ch: e_true}
        plant = Experiment(t=t, x=x_true, v=v_true, F=zeros, name=name, **elec)
        F_model = np.asarray(drawn.damper.predict(plant), dtype=np.float64)
        if F_model.shape != (n,):
            raise DataValidationError(
                "damper",
                f"{self.model.kind}.predict returned shape {F_model.shape}, expected ({n},)",
            )
        bad = np.flatnonzero(~np.isfinite(F_model))
        if bad.size:
            raise SimulationDivergedError(
                self.model.kind, int(bad[0]), "non-finite damper force on the virtual rig"
            )
        F_true = drawn.apply(F_model, t)
        x_meas = self.sensors.displacement.measure(x_true, np.random.default_rng(s_x))
        F_meas = self.sensors.force.measure(F_true, np.random.default_rng(s_f))
        e_meas = self.sensors.electrical.measure(e_true, np.random.default_rng(s_i))
        meta: dict[str, Any] = dict(metadata or {})
        meta.update(
            source="virtual rig",
            seed=_seed_label(seed) if seed_label is None else seed_label,
            damper=self.model.kind,
            fs=fs,
            **drawn.to_metadata(),
        )
        from mrdamper.rig.reference import CUSTOM_DAMPER, REFERENCE_KEY, reference_name

        meta[REFERENCE_KEY] = reference_name(self.model) or CUSTOM_DAMPER
        v_meas = _velocity(x_meas, fs, self.velocity_cutoff)
        note = (
            f"v = central difference of x after zero-phase Butterworth low-pass (order "
            f"{VELOCITY_FILTER_ORDER}, {self.velocity_cutoff:g} Hz)"
        )
        meta["processing"] = (*tuple(meta.get("processing", ())), note)
        meta["velocity_cutoff"] = self.velocity_cutoff
        measured: dict[str, Any] = {ch: e_meas}
        return Experiment(t=t, x=x_meas, v=v_meas, F=F_meas, name=name, metadata=meta, **measured)
