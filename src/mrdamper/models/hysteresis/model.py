"""Fitted-model and estimator base of the one-state hysteresis families (private).

``tanh``, ``boucwen``, ``dahl`` and ``lugre`` are each a small module declaring its parameters
(the fields of a :class:`HysteresisModel` subclass) and its identification spec
(:class:`~.fit.FitSpec`); everything else is here, written once: parameter checks, the free
run, the per-sample step, the estimator settings, the output-error fit and its step-halving
check.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource, require_experiment
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models import _output_error as oe
from mrdamper.models.base import (
    STEP_VMAX,
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_number,
)
from mrdamper.models.hysteresis import kernels as _k
from mrdamper.models.hysteresis.fit import FitSettings, FitSpec, check_mappings, identify
from mrdamper.models.lag import check_lag, resolved
from mrdamper.models.step import Step

__all__ = ["STEP_VMAX", "HysteresisEstimator", "HysteresisModel"]


@dataclass(frozen=True, kw_only=True)
class HysteresisModel(FittedModel):
    """Base of the four families' fitted models (see the family modules).

    Attributes
    ----------
    eta : float
        Rate of the first-order drive lag from the electrical input to ``u`` [1/s]; 0: no lag.
    f0 : float
        Force offset [N].
    substeps : int
        RK4 sub-steps per sampling interval; 0 chooses them from the parameters and the record.
    """

    family: ClassVar[str] = "abstract"

    eta: float = 0.0
    f0: float = 0.0
    substeps: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        oe.check_real_fields(self, _k.PARAM_NAMES[self.family])
        if self.eta < 0.0:
            raise DataValidationError(
                "eta", f"expected a drive-lag rate >= 0 [1/s] (0: no lag), got {self.eta!r}"
            )
        self._check()

    def _check(self) -> None:
        """Family-specific parameter checks (one-line errors naming the field)."""

    def parameter_vector(self) -> np.ndarray:
        """Parameters as a float64 array in the kernel order (SI)."""
        return np.array([getattr(self, n) for n in _k.PARAM_NAMES[self.family]], dtype=np.float64)

    def substeps_for(self, experiment: Experiment) -> int:
        """RK4 sub-steps per sampling interval used for ``experiment`` (``substeps``, or the
        automatic choice of :func:`~.kernels.auto_substeps` for its interval and the
        velocity bound :meth:`~mrdamper.models.base.FittedModel.step_vmax`): those of the step
        built for its interval, one rule for both."""
        return self._substeps(experiment.dt, self.step_vmax(experiment.v))

    def _substeps(self, dt: float, vmax: float) -> int:
        """``substeps``, or the automatic count for an interval of ``dt`` [s] and velocities up
        to ``vmax`` [m/s]."""
        if self.substeps > 0:
            return self.substeps
        return _k.auto_substeps(self.family, self.parameter_vector(), dt, vmax)

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] of one record from its x, v and electrical input, from rest.

        Raises
        ------
        DataValidationError
            If the record lacks the model's electrical input channel.
        OutOfRangeError
            If the electrical input leaves ``input_range`` and ``range_policy == "error"``.
        SimulationDivergedError
            If the state becomes non-finite or leaves its bound (names the first failing sample).
        """
        require_experiment(experiment)
        e = np.ascontiguousarray(self.electrical_input(experiment), dtype=np.float64)
        nsub = self.substeps_for(experiment)
        F, status, sample = _k.simulate(
            _k.FAMILIES[self.family],
            np.ascontiguousarray(experiment.x, dtype=np.float64),
            np.ascontiguousarray(experiment.v, dtype=np.float64),
            e,
            experiment.dt,
            self.parameter_vector(),
            nsub,
        )
        if status != _k.STATUS_OK:
            raise SimulationDivergedError(
                self.kind,
                sample,
                f"record {experiment.name!r}: state became non-finite or unbounded with {nsub} "
                "RK4 sub-steps per sample (set 'substeps' higher, or check the parameters)",
            )
        return np.asarray(F)

    def step(self, *, dt: float = 1e-3, vmax: float | None = None) -> Step:
        """The model as a per-sample step (:mod:`mrdamper.models.step`).

        The state is ``(z, u)``, at rest ``(0, e[0])``. Without a drive lag the force reads the
        present input (``feedthrough``); with one it reads the lagged input ``u``, a state.
        ``advance`` integrates an interval with the RK4 sub-steps of :meth:`predict` (the same
        compiled interval), no longer than ``max_h``: the automatic choice for an interval of
        ``dt`` [s] and velocities up to ``vmax`` [m/s] (or ``dt / substeps`` when ``substeps`` is
        set); with the default ``vmax`` and the record's interval, the sub-steps of
        :meth:`predict` on every record within that velocity.

        Parameters
        ----------
        dt : float
            Reference interval [s] for the sub-step choice (default 1 ms).
        vmax : float, optional
            Largest damper velocity [m/s] the step must resolve (default
            :meth:`~mrdamper.models.base.FittedModel.step_vmax`: 1.5 m/s or the training peak
            velocity when larger).
        """
        p = np.ascontiguousarray(self.parameter_vector())
        vmax = self.step_vmax() if vmax is None else vmax
        nsub = self._substeps(dt, vmax)
        form = _k.HysteresisForm(_k.FAMILIES[self.family], p, dt / nsub)

        def initial_state(x0: float, v0: float, e0: float) -> np.ndarray:
            return np.array([0.0, e0])

        return Step(
            self.kind,
            form,
            _k.step_force,
            _k.step_advance,
            initial_state,
            feedthrough=self.eta == 0.0,
        )

    def invert_record(
        self,
        x: np.ndarray,
        v: np.ndarray,
        F_desired: np.ndarray,
        dt: float,
        lo: float,
        hi: float,
        *,
        reg: float = 0.0,
        max_change: float = math.inf,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Causal per-sample inverse along a record, through the model's step.

        At every sample the input ``u`` the laws read, in its admissible interval (within
        ``max_change`` of the previous one), minimising
        ``(F(u) - F_desired)^2 + reg^2 (u - u_prev)^2`` is taken in closed form
        (:func:`~.kernels.inverse_step`: the force is affine in ``u`` at the present
        state), then the state is advanced with the motion. Without a drive lag ``u`` is the input
        itself, in ``[lo, hi]``. With one it is the lagged input, confined to what a command in
        ``[lo, hi]`` held over the interval reaches (:func:`~.kernels.inverse_run`);
        the command is then :func:`mrdamper.control.inverse.current.driver_command` of it, which
        :func:`mrdamper.control.inverse_current` applies. The step has the RK4 sub-steps
        :meth:`predict` takes on the record, so without a lag the model's free run with the
        inputs found gives ``F_desired`` wherever it is in reach (``reg = 0``); with a lag the
        free run reads the command linearly interpolated between samples, not held, so it
        differs from ``F_desired`` by that half-sample shift of the command.

        Parameters
        ----------
        x, v, F_desired : ndarray
            Displacement [m], velocity [m/s] and desired force [N], one value a sample.
        dt : float
            Sampling interval [s].
        lo, hi : float
            Input limits [A] or [V].
        reg : float
            Regularisation weight [N per input unit]; 0: the exact solution per sample.
        max_change : float
            Largest change of ``u`` per sample [A] or [V].

        Returns
        -------
        u : ndarray
            Input the laws read [A] or [V] (with a drive lag: the lagged input).
        saturated : ndarray of bool
            Samples where no admissible input gives the desired force.

        Raises
        ------
        SimulationDivergedError
            If the state becomes non-finite or leaves its bound.
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise DataValidationError(
                "dt", f"expected a positive sampling interval [s], got {dt!r}"
            )
        x = np.ascontiguousarray(x, dtype=np.float64)
        v = np.ascontiguousarray(v, dtype=np.float64)
        form = self.step(dt=dt, vmax=self.step_vmax(v)).form
        e, sat, status, sample = _k.inverse_run(
            form,
            x,
            v,
            np.ascontiguousarray(F_desired, dtype=np.float64),
            float(dt),
            float(lo),
            float(hi),
            float(reg) ** 2,
            float(max_change),
        )
        if status != _k.STATUS_OK:
            raise SimulationDivergedError(
                self.kind, int(sample), "inverse: state became non-finite or unbounded"
            )
        return np.asarray(e), np.asarray(sat)

    def force_authority(self, v_ref: float) -> float:
        """Steady force range per input unit at the velocity ``v_ref`` [m/s] [N per input unit].

        The free run at the constant velocity ``v_ref`` with the input held at each end of
        ``input_range``, long enough for the state to settle (ten time constants of the fastest
        rate, at least 0.3 s, 3000 samples), compared at its last sample. It scales the default
        regularisation weight of the inverse (:func:`mrdamper.control.inverse.current.default_reg`).
        """
        lo, hi = (float(b) for b in self.input_range)
        if not hi > lo:
            raise DataValidationError("input_range", f"expected low < high, got {(lo, hi)}")
        p = self.parameter_vector()
        rate = _k.fastest_rate(self.family, p, abs(v_ref))
        T = min(max(0.3, 10.0 / rate), 30.0) if rate > 0.0 else 0.3
        n = 3001
        dt = T / (n - 1)
        v = np.full(n, float(v_ref))
        x = v * (np.arange(n) * dt) - 0.5 * v_ref * T  # centred stroke
        nsub = self.substeps or _k.auto_substeps(self.family, p, dt, abs(v_ref))
        ends = []
        for e in (lo, hi):
            F, status, _ = _k.simulate(_k.FAMILIES[self.family], x, v, np.full(n, e), dt, p, nsub)
            if status != _k.STATUS_OK:
                raise SimulationDivergedError(self.kind, n, f"steady run at {v_ref!r} m/s")
            ends.append(float(F[-1]))
        return abs(ends[1] - ends[0]) / (hi - lo)


@dataclass
class HysteresisEstimator(Estimator):
    """Output-error estimator of the four families (settings only; see :mod:`.fit`).

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel the model reads.
    start, fixed : mapping, optional
        Start values / fixed values of some identified parameters (names of the family's
        ``IDENTIFIED`` tuple, SI). An explicit ``fixed`` replaces the family's default fixed set.
    bounds : mapping, optional
        ``name -> (low, high)`` overriding the family's default bounds.
    n_starts : int
        Starts: the data-driven guess plus ``n_starts - 1`` seeded variants; each runs
        ``screen_nfev`` evaluations and the best continues to convergence.
    seed : int
        Seed of the random starts.
    weighting : {"record", "none"}
        ``"record"``: every record counts as much (cost = half the mean per-record ESR).
    max_nfev, screen_nfev : int
        Evaluation limits of the final run and of each screening run.
    ftol, xtol, gtol : float
        Tolerances of :func:`scipy.optimize.least_squares`.
    substeps : int
        RK4 sub-steps per sample (0 = automatic); kept by the fitted model.
    eta : float, "auto", "identify" or None
        Rate [1/s] of the first-order drive lag from the electrical input to the laws.
        ``"auto"`` (default): identified on the training records when the input is a command
        voltage that varies within a record, none otherwise (:mod:`mrdamper.models.lag`);
        ``"identify"``: identified whenever the input switches within a record, a measured
        current included (the field's lag); a
        number: held at that rate; None: no lag.
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    step_tolerance : float
        Largest change of a training record's free run when the RK4 step is halved (ESR units)
        before the fit warns (``provenance["step_check"]``).
    """

    kind: ClassVar[str] = "abstract"
    spec: ClassVar[FitSpec]

    input: ElectricalSource = "i"
    start: Mapping[str, float] | None = None
    fixed: Mapping[str, float] | None = None
    bounds: Mapping[str, tuple[float, float]] | None = None
    n_starts: int = 3
    seed: int = 0
    weighting: Literal["record", "none"] = "record"
    max_nfev: int = 60
    screen_nfev: int = 8
    ftol: float = 1e-4
    xtol: float = 1e-8
    gtol: float = 1e-8
    substeps: int = 0
    eta: float | Literal["auto", "identify"] | None = "auto"
    range_policy: RangePolicy = "error"
    step_tolerance: float = 1e-4

    def _validate(self) -> None:
        super()._validate()
        oe.check_settings(self)
        for name in ("ftol", "xtol", "gtol"):
            check_number(name, getattr(self, name), what="a positive finite tolerance")
        check_lag(self.eta)
        check_mappings(self.spec, self._fit_settings())

    def lag_screening(self, neighbour: FittedModel) -> HysteresisEstimator:
        """The estimator of a drive-lag candidate fitted next to ``neighbour``, a candidate of
        the same search (:func:`mrdamper.models.lag.fit_with_lag`): one start, at the
        neighbour's identified parameters.

        A lag candidate differs from its neighbour (a factor 2 or sqrt(2) in the rate) by little
        more than the timing of the input, so the neighbour's optimum is a better start than the
        data-driven guesses, and the screening of ``n_starts`` starts is skipped. The search's
        candidates start this way (all fitted on the same inner split of the training records),
        and so does its final fit on the whole training records, from the chosen candidate.

        Parameters
        ----------
        neighbour : FittedModel
            A candidate fitted by this estimator with another lag.
        """
        identified = dict(neighbour.provenance).get("identified")
        if not identified:
            return self
        start = {nm: float(v) for nm, v in identified.items() if nm in self.spec.unknowns}
        return dataclasses.replace(self, start=start, n_starts=1)

    def _fit_settings(self) -> FitSettings:
        """The settings the fit reads (``eta`` as given: :meth:`_identify` resolves it)."""
        names = [f.name for f in dataclasses.fields(FitSettings)]
        return FitSettings(**{n: getattr(self, n) for n in names})

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Output-error fit (:func:`.fit.identify`), then the step-halving check.

        Raises
        ------
        IdentificationError
            Every start diverged, or the optimiser returned a non-finite result.
        """
        settings = dataclasses.replace(self._fit_settings(), eta=resolved(self.eta))

        def fit(exps: ExperimentSet) -> tuple[dict[str, Any], HysteresisModel, dict[str, Any]]:
            params, provenance = identify(
                self.spec, settings, exps, single=data.single, kind=self.kind
            )
            parameters: dict[str, Any] = {**params, "substeps": int(self.substeps)}
            model = self.model_class(**parameters, input=self.input, input_range=data.input_range)
            assert isinstance(model, HysteresisModel)
            return parameters, model, provenance

        return oe.fit_and_check(self.kind, data, fit, self.step_tolerance)
