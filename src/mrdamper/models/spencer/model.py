"""Spencer et al. (1997) modified Bouc-Wen model of an MR damper, current dependent.

Equations (Spencer, Dyke, Sain & Carlson, "Phenomenological model of a magnetorheological
damper", J. Eng. Mech. 123(3):230-238, 1997), with a force offset ``f0`` added::

    F  = c1(u) * dy/dt + k1 * (x - x0) + f0
    dy/dt = [alpha(u) * z + c0(u) * dx/dt + k0 * (x - y)] / (c0(u) + c1(u))
    dz/dt = -gamma * |dx/dt - dy/dt| * z * |z|**(n-1) - beta * (dx/dt - dy/dt) * |z|**n
            + A * (dx/dt - dy/dt)
    du/dt = -eta * (u - e)
    alpha(u) = alpha_a + alpha_b u,  c0(u) = c0a + c0b u,  c1(u) = c1a + c1b u

x [m] is the damper displacement, dx/dt the record's velocity v [m/s] (not a derivative of x),
e the electrical input of the record (coil current ``i`` [A] or command ``voltage`` [V], chosen by
``input``) and u its first-order filtered version (drive and fluid lag). The initial state is the
rest state: y = x(0), z = 0, u = e(0).

The model is integrated by a compiled fixed-step RK4 kernel (:mod:`.kernels`); the number
of sub-steps per sampling interval is chosen from the parameters and the record so that the step
resolves the stiffest time constant (see :meth:`SpencerModel.substeps_for`).

Identification (:class:`SpencerEstimator`) minimises the free-run simulation error of every
record (each simulated separately from its own rest state) by bounded nonlinear least squares,
with parameter scaling, seeded multi-start and a Jacobian from forward sensitivities.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource, require_experiment
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models import _output_error as oe
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
)
from mrdamper.models.spencer import kernels as _k
from mrdamper.models.spencer.fit import DEFAULT_BOUNDS, FitSettings, check_settings, identify
from mrdamper.models.spencer.kernels import (
    MAX_AUTO_SUBSTEPS,
    SUBSTEP_RATE_PRODUCT,
    auto_substeps,
)
from mrdamper.models.step import Step

__all__ = [
    "DEFAULT_BOUNDS",
    "MAX_AUTO_SUBSTEPS",
    "PARAMETER_NAMES",
    "PARAMETER_UNITS",
    "SUBSTEP_RATE_PRODUCT",
    "SpencerEstimator",
    "SpencerModel",
    "auto_substeps",
    "spencer1997",
]

#: Parameter names in kernel order.
PARAMETER_NAMES: tuple[str, ...] = _k.PARAM_NAMES

#: SI units of every parameter ("U" is the unit of the electrical input: A or V; z is in the
#: units of x times A, i.e. metres when A is dimensionless).
PARAMETER_UNITS: dict[str, str] = {
    "c0a": "N s/m",
    "c0b": "N s/(m U)",
    "k0": "N/m",
    "c1a": "N s/m",
    "c1b": "N s/(m U)",
    "k1": "N/m",
    "x0": "m",
    "alpha_a": "N/m",
    "alpha_b": "N/(m U)",
    "gamma": "m^-n",
    "beta": "m^-n",
    "A": "-",
    "n": "-",
    "eta": "1/s",
    "f0": "N",
}


@dataclass(frozen=True, kw_only=True)
class SpencerModel(FittedModel):
    """Identified (or published) Spencer modified Bouc-Wen model; an immutable value.

    Parameters
    ----------
    c0a, c0b : float
        Post-yield viscous damping ``c0 = c0a + c0b u`` [N s/m], [N s/(m U)].
    k0 : float
        Stiffness at large velocities [N/m].
    c1a, c1b : float
        Dashpot producing the roll-off at low velocities ``c1 = c1a + c1b u`` [N s/m], [N s/(m U)].
    k1 : float
        Accumulator stiffness [N/m].
    x0 : float
        Initial displacement of the accumulator spring [m].
    alpha_a, alpha_b : float
        Evolutionary coefficient ``alpha = alpha_a + alpha_b u`` [N/m], [N/(m U)].
    gamma, beta : float
        Hysteresis shape parameters [m^-n] (z in metres when ``A`` is dimensionless).
    A : float
        Bouc-Wen scale of the evolutionary variable [-].
    n : float
        Bouc-Wen exponent [-], at least 1.
    eta : float
        Rate of the first-order filter from the electrical input to u [1/s].
    f0 : float
        Force offset [N] (load-cell zero, accumulator preload).
    substeps : int
        RK4 sub-steps per sampling interval; 0 chooses them automatically per record.

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.data import Experiment
    >>> m = spencer1997()
    >>> t = np.arange(3000) / 3000.0
    >>> x = 0.005 * np.sin(2 * np.pi * 2 * t)
    >>> v = 0.005 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t)
    >>> e = Experiment(t=t, x=x, v=v, F=0 * t, voltage=0 * t + 1.0, name="demo")
    >>> F = m.predict(e)
    >>> bool(np.all(np.isfinite(F)))
    True
    """

    kind: ClassVar[str] = "spencer"

    c0a: float
    c0b: float
    k0: float
    c1a: float
    c1b: float
    k1: float
    x0: float
    alpha_a: float
    alpha_b: float
    gamma: float
    beta: float
    A: float
    n: float
    eta: float
    f0: float = 0.0
    substeps: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        oe.check_real_fields(self, PARAMETER_NAMES)
        if self.n < 1.0:
            raise DataValidationError("n", f"expected a Bouc-Wen exponent >= 1, got {self.n!r}")
        if self.eta < 0.0:
            raise DataValidationError(
                "eta", f"expected a non-negative filter rate [1/s], got {self.eta!r}"
            )

    # ------------------------------------------------------------------ parameter vector
    def parameter_vector(self) -> np.ndarray:
        """Parameters as a float64 array in :data:`PARAMETER_NAMES` order (SI)."""
        return np.array([getattr(self, n) for n in PARAMETER_NAMES], dtype=np.float64)

    @classmethod
    def from_vector(cls, p: np.ndarray, **common: Any) -> SpencerModel:
        """Build a model from a vector in :data:`PARAMETER_NAMES` order plus common fields."""
        values: dict[str, Any] = {
            n: float(v) for n, v in zip(PARAMETER_NAMES, np.asarray(p, dtype=float))
        }
        return cls(**values, **common)

    # ------------------------------------------------------------------ simulation
    def substeps_for(self, experiment: Experiment, electrical: np.ndarray | None = None) -> int:
        """RK4 sub-steps per sampling interval used for ``experiment``: those of the step built
        for its interval (:meth:`step`), one rule for both.

        With ``substeps == 0`` the count follows from an upper estimate of the fastest rate of
        the linearised model (filter rate, stiffness over damping, Bouc-Wen rate
        ``n (|beta| + |gamma|) |z|**(n-1) |v|`` at the saturated ``z``) at the velocity bound
        :meth:`~mrdamper.models.base.FittedModel.step_vmax` and over the identified input range
        (widened to the record's input when it leaves it; a model without a training envelope
        takes the record's input range), so that the product of the sub-step and that rate stays
        below :data:`SUBSTEP_RATE_PRODUCT`.
        """
        e = experiment.electrical(self.input) if electrical is None else electrical
        emin, emax = float(np.min(e)), float(np.max(e))
        if self.envelope is not None:
            emin = min(emin, self.input_range[0])
            emax = max(emax, self.input_range[1])
        return self._substeps(experiment.dt, self.step_vmax(experiment.v), emin, emax)

    def _substeps(self, dt: float, vmax: float, emin: float, emax: float) -> int:
        """``substeps``, or the automatic count for an interval of ``dt`` [s], velocities up to
        ``vmax`` [m/s] and the input in ``[emin, emax]``."""
        if self.substeps > 0:
            return self.substeps
        return auto_substeps(self.parameter_vector(), dt, vmax, emin, emax)

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] of one record from its x, v and electrical input.

        Raises
        ------
        DataValidationError
            If the record lacks the model's electrical input channel.
        OutOfRangeError
            If the electrical input leaves ``input_range`` and ``range_policy == "error"``.
        SimulationDivergedError
            If the state becomes non-finite, leaves its bound or the damping ``c0 + c1`` becomes
            non-positive; the error names the first failing sample.
        """
        require_experiment(experiment)
        e = np.ascontiguousarray(self.electrical_input(experiment), dtype=np.float64)
        nsub = self.substeps_for(experiment, e)
        F, status, sample = _k.simulate(
            experiment.x,
            experiment.v,
            e,
            experiment.dt,
            self.parameter_vector(),
            nsub,
            float(experiment.x[0]),
            0.0,
            float(e[0]),
        )
        _raise_on_status(status, sample, nsub, experiment.name)
        return np.asarray(F)

    def step(self, *, dt: float = 1e-3, vmax: float | None = None) -> Step:
        """The model as a per-sample step (:mod:`mrdamper.models.step`).

        The state is ``(y, z, u)``, at rest ``(x[0], 0, e[0])``; ``advance`` integrates an
        interval with classical RK4 sub-steps no longer than ``max_h``, chosen by the rule of
        :meth:`substeps_for` for an interval of ``dt`` [s] and velocities up to ``vmax`` [m/s]
        over the identified input range (or ``dt / substeps`` when ``substeps`` is set): with
        the default ``vmax`` and the record's interval it takes the sub-steps of :meth:`predict`
        on every record within that velocity. The force reads the
        filtered input ``u``, a state: ``feedthrough`` is False.

        Parameters
        ----------
        dt : float
            Reference interval [s] for the sub-step choice (default 1 ms).
        vmax : float, optional
            Largest damper velocity [m/s] the step must resolve (default
            :meth:`~mrdamper.models.base.FittedModel.step_vmax`: 1.5 m/s, beyond the velocities
            of a car suspension, or the training peak velocity when larger).
        """
        vmax = self.step_vmax() if vmax is None else vmax
        nsub = self._substeps(dt, vmax, self.input_range[0], self.input_range[1])
        form = _k.SpencerForm(np.ascontiguousarray(self.parameter_vector()), dt / nsub)

        def initial_state(x0: float, v0: float, e0: float) -> np.ndarray:
            return np.array([x0, 0.0, e0])

        return Step(
            self.kind, form, _k.step_force, _k.step_advance, initial_state, feedthrough=False
        )


def _raise_on_status(status: int, sample: int, nsub: int, name: str) -> None:
    if status == _k.STATUS_OK:
        return
    if status == _k.STATUS_BAD_DAMPING:
        raise SimulationDivergedError(
            "spencer",
            sample,
            f"record {name!r}: damping c0(u) + c1(u) is not positive; the parameters are invalid "
            "for this electrical input",
        )
    raise SimulationDivergedError(
        "spencer",
        sample,
        f"record {name!r}: state became non-finite or unbounded with {nsub} RK4 sub-steps per "
        "sample (set 'substeps' higher, or check the parameters)",
    )


def spencer1997(**common: Any) -> SpencerModel:
    """The prototype damper of Spencer et al. (1997), Table 1 values converted to SI.

    Published values (paper units): c0a 21.0 N s/cm, c0b 3.50 N s/(cm V), k0 46.9 N/cm,
    c1a 283 N s/cm, c1b 2.95 N s/(cm V), k1 5.00 N/cm, x0 14.3 cm, alpha_a 140 N/cm,
    alpha_b 695 N/(cm V), gamma = beta = 363 cm^-2, A 301, n 2, eta 190 1/s. The electrical input
    is the command voltage [V] (0 to 2.25 V in the paper's tests). No force offset (f0 = 0).

    Parameters
    ----------
    **common
        Overrides of the common fields (``range_policy``, ``provenance``, ...).
    """
    values: dict[str, Any] = {
        "c0a": 21.0e2,
        "c0b": 3.50e2,
        "k0": 46.9e2,
        "c1a": 283.0e2,
        "c1b": 2.95e2,
        "k1": 5.00e2,
        "x0": 14.3e-2,
        "alpha_a": 140.0e2,
        "alpha_b": 695.0e2,
        "gamma": 363.0e4,
        "beta": 363.0e4,
        "A": 301.0,
        "n": 2.0,
        "eta": 190.0,
        "f0": 0.0,
    }
    settings: dict[str, Any] = {
        "input": "voltage",
        "input_range": (0.0, 2.25),
        "range_policy": "error",
        "provenance": {
            "source": "Spencer, Dyke, Sain & Carlson (1997), Phenomenological model of a "
            "magnetorheological damper, J. Eng. Mech. 123(3):230-238, Table 1 (generalized model)",
            "units": "converted from N, cm, s, V to SI",
            "identified": False,
        },
    }
    settings.update(common)
    return SpencerModel(**values, **settings)


# ----------------------------------------------------------------------------- estimator
@dataclass
class SpencerEstimator(Estimator):
    """Identify a :class:`SpencerModel` from any set of records (settings only).

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel the model reads.
    start : mapping, optional
        Initial values of some parameters (SI); the others come from a data-driven guess (a
        Bingham regression mapped onto the model, see ``docs/calibration.md``).
    fixed : mapping, optional
        Parameters held at a value. Default ``{"x0": 0.0, "A": 1.0}``: ``k1 x0`` duplicates
        ``f0``, and ``A`` is redundant with the scale of z (alpha, beta, gamma absorb it). When
        the electrical input does not switch within any record (each record's input spans at
        most 5 % of the training input range, so noise on a held current does not count),
        ``eta`` cannot be identified and is also fixed (at ``start["eta"]`` or 100 1/s) unless
        ``fix_eta="never"``.
    bounds : mapping, optional
        ``name -> (low, high)`` overriding the default bounds (see :data:`DEFAULT_BOUNDS`).
    n_starts : int
        Number of starts: the data-driven guess plus ``n_starts - 1`` seeded random variants.
        Every start runs ``screen_nfev`` evaluations; the best then continues to convergence.
    seed : int
        Seed of the random starts (``numpy.random.default_rng``).
    weighting : {"record", "none"}
        ``"record"`` weights each record by ``1 / (std(F) sqrt(N_record * n_records))`` so the
        cost is half the mean per-record ESR; ``"none"`` weights every sample equally.
    jacobian : {"sensitivity", "2-point", "3-point"}
        Forward sensitivities integrated with the state (default) or SciPy finite differences
        (for comparison only).
    max_nfev, screen_nfev : int
        Function-evaluation limits of the final run and of each screening run.
    ftol, xtol, gtol : float
        Tolerances of :func:`scipy.optimize.least_squares`. ``ftol = 1e-4`` stops when the cost
        (half the mean ESR) changes by less than 0.01 % in a step: far below any difference
        that matters when comparing models.
    substeps : int
        RK4 sub-steps per sample during identification (0 = automatic per record and parameter
        set). The fitted model keeps ``substeps=0`` (automatic) unless this is positive.
    fix_eta : {"auto", "never", "always"}
        When to fix ``eta`` (see ``fixed``).
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    step_tolerance : float
        After the fit every training record is simulated again with half the RK4 step; a change
        of the free run above this value (ESR units: mean squared change over the variance of
        the measured force) gives a warning naming the discrepancy (``provenance["step_check"]``).
    """

    kind: ClassVar[str] = "spencer"
    model_class: ClassVar[type[FittedModel]] = SpencerModel

    input: ElectricalSource = "i"
    start: Mapping[str, float] | None = None
    fixed: Mapping[str, float] | None = None
    bounds: Mapping[str, tuple[float, float]] | None = None
    n_starts: int = 3
    seed: int = 0
    weighting: Literal["record", "none"] = "record"
    jacobian: Literal["sensitivity", "2-point", "3-point"] = "sensitivity"
    max_nfev: int = 100
    screen_nfev: int = 5
    ftol: float = 1e-4
    xtol: float = 1e-8
    gtol: float = 1e-8
    substeps: int = 0
    fix_eta: Literal["auto", "never", "always"] = "auto"
    range_policy: RangePolicy = "error"
    step_tolerance: float = 1e-4

    def _validate(self) -> None:
        super()._validate()
        oe.check_settings(self)
        check_settings(self._fit_settings())

    def _fit_settings(self) -> FitSettings:
        names = [f.name for f in dataclasses.fields(FitSettings)]
        return FitSettings(**{n: getattr(self, n) for n in names})

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Bounded nonlinear least squares on the free-run error (:mod:`.fit`), then the
        step-halving check of the result.

        Raises
        ------
        IdentificationError
            Every start diverged, or the optimiser returned a non-finite result.
        """

        def fit(exps: ExperimentSet) -> tuple[dict[str, Any], SpencerModel, dict[str, Any]]:
            p, provenance = identify(self._fit_settings(), exps, single=data.single)
            params: dict[str, Any] = {n: float(v) for n, v in zip(PARAMETER_NAMES, p)}
            params["substeps"] = max(0, int(self.substeps))
            model = SpencerModel(**params, input=self.input, input_range=data.input_range)
            return params, model, provenance

        # stiff model: halving the RK4 step must not change the free run (else warn, see provenance)
        return oe.fit_and_check("spencer", data, fit, self.step_tolerance)
