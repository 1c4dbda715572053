"""Semi-phenomenological MR damper models SP-1 ... SP-4 (Guo et al. variants, paper Section V).

Each variant is a static force map of displacement ``x`` [m], velocity ``v`` [m/s] and the
electrical input ``i`` ([A], or [V] with ``input="voltage"``)::

    SP-1: F = S1(i) tanh(S2(i) v + S3(i) x) + S4(i) v + S5(i) x + f0
    SP-2: F = S1 i tanh(S2 v + S3 x) + S4 v + S5 x + f0
    SP-3: F = (S1 i + S2) tanh(S3 v + S4 x) + S5 v + S6 x + f0
    SP-4: F = (S1 i^2 + S2 i + S3) tanh(S4 v + S5 x) + S6 v + S7 x + f0

SP-2 ... SP-4 are exactly the paper's table. For SP-1 the paper says "each S a function of i";
following READING-NOTES item 2 each ``S_j(i) = S_j0 + S_j1 i + S_j2 i^2`` (15 coefficients, the
same treatment as P-15). ``f0`` [N] is a constant force offset (accumulator preload, load-cell
zero); it is identified when the estimator's ``offset=True`` (default) and is exactly 0 with
``offset=False``, which is the paper's literal form.

Because the maps are static, a free-run prediction is a direct evaluation on the record's x, v
and electrical input: the measured force is never used. Optionally (``eta``, as for the LPV and
P-15 models) the map is evaluated at the electrical input passed through a first-order drive lag
``d rho/dt = -eta (rho - input)`` (zero-order-hold discretisation, ``rho[0] = input[0]``): the
map itself stays static, ``rho`` replaces ``i`` in it. Use it when the recorded input is a command
that reaches the fluid through a driver and coil with a lag (the Dyke voltage record).

Identification
--------------
Nonlinear least squares (:func:`scipy.optimize.least_squares`, trust-region reflective) on the
force error, with the analytic Jacobian of :mod:`mrdamper.models.sp.kernels`:

1. Scaling: x, v, i and F are divided by their training RMS (x, v), largest magnitude (i) and
   standard deviation (F); the fit runs on these dimensionless coefficients (all of order one)
   and they are converted back exactly to SI coefficients.
2. Linear start: for fixed tanh-argument coefficients the map is linear in everything else, so
   seeded random draws of the (normalised) tanh slope and displacement weight are each completed
   by linear least squares and ranked by their cost.
3. Multi-start: the ``n_starts`` best draws are refined by the nonlinear solver on an evenly
   spaced subset of at most ``screen_samples`` samples; the best result is polished on an evenly
   spaced subset of at most ``fit_samples`` samples (``None``: every sample). Subsetting a
   static map's samples changes no model term; it only bounds the solver's cost (a dense SVD of
   the Jacobian per iteration). With the defaults a 1 kHz training set of 100 000 samples is
   polished on every 5th sample; the number used is stored in ``provenance["n_fit_samples"]``.
4. Bounds: the constant term of the tanh velocity coefficient lies in ``[0, 1000]`` (normalised;
   this removes the sign symmetry ``(A, a, b) -> (-A, -a, -b)`` and keeps the solver away from a
   sign function whose Jacobian vanishes). Everything else is free in the free fit.
5. Monotone in velocity (``monotone``): ``dF/dv = A a sech^2(a v + b x) + c`` takes every value
   between ``c`` and ``A a + c``. After the free fit its floor over the input range is
   evaluated (:func:`~mrdamper.models.sp.fit.velocity_slope_floor`); when it is negative (and
   by default only then) the fit is repeated with ``A``, ``a`` and ``c`` written in the
   Bernstein basis of the input range with non-negative coefficients, which keeps each of them,
   and so ``dF/dv``, non-negative at every input of the range. A free fit can fall with
   velocity past its records (a large tanh amplitude and a negative viscous slope fit slow
   records as well), and a quarter car with such a damper diverges.

Identifiability is checked before fitting: each component polynomial needs as many distinct
input levels as it has coefficients (SP-1 and SP-4 need three, SP-3 two, SP-2 a non-zero input);
otherwise :class:`~mrdamper.errors.IdentificationError` names the rank found. The exception is
data at a single, constant input level: each component then keeps only its lowest-power term
(its law in the input is a constant, the higher coefficients are exactly 0), the identified
range is that level, and a one-line note says so (``provenance["note"]`` and a ``UserWarning``).

Examples
--------
>>> import numpy as np
>>> from mrdamper import Experiment
>>> t = np.arange(2000) / 1000.0
>>> x = 0.01 * np.sin(2 * np.pi * 2 * t); v = 0.01 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t)
>>> i = 0.5 + 0.5 * np.sin(2 * np.pi * 0.5 * t)
>>> true = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), input_range=(0.0, 1.0))
>>> e = Experiment(t=t, x=x, v=v, i=i, F=np.zeros_like(t))
>>> e = e.replace(F=true.predict(e))
>>> fitted = SP3Estimator(seed=0).fit(e)
>>> bool(np.allclose(fitted.S, true.S, rtol=1e-6))
True
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, ClassVar, Literal, cast

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError
from mrdamper.models import _scale
from mrdamper.models._lag import first_order_lag
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
)
from mrdamper.models.lag import check_lag, resolved
from mrdamper.models.protocols import StaticMapForm
from mrdamper.models.sp.fit import (
    component_values,
    identify,
    single_level_terms,
    stack,
    velocity_slope_floor,
)
from mrdamper.models.sp.kernels import COMPONENTS, make_static_step, sp_force
from mrdamper.models.step import Step
from mrdamper.progress import report

__all__ = [
    "SP1Estimator",
    "SP1Model",
    "SP2Estimator",
    "SP2Model",
    "SP3Estimator",
    "SP3Model",
    "SP4Estimator",
    "SP4Model",
    "SPModel",
]


# ============================================================================ fitted models
@dataclass(frozen=True)
class SPModel(FittedModel):
    """Common behaviour of the SP-k fitted models (use SP1Model ... SP4Model).

    Attributes
    ----------
    S : tuple of float
        Coefficients in the paper's order (see the subclass for units and layout).
    f0 : float
        Force offset [N] (0 when identified with ``offset=False``).
    eta : float or None
        Rate [1/s] of an optional first-order drive lag of the electrical input (see the module
        docstring); ``None``: the map sees the input itself.
    rho_range : (float, float) or None
        With ``eta``: range of the lagged input the map was identified on [A] or [V] (the
        ``input_range`` is that of the recorded command); ``None`` without a lag.
    """

    S: tuple[float, ...] = ()
    f0: float = 0.0
    eta: float | None = None
    rho_range: tuple[float, float] | None = None

    #: (component, power of i) of each coefficient, in the paper's order.
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        S = tuple(float(s) for s in self.S)
        if len(S) != len(self.LAYOUT):
            raise DataValidationError(
                "S", f"{self.kind} has {len(self.LAYOUT)} coefficients, got {len(S)}"
            )
        if not all(np.isfinite(S)) or not np.isfinite(self.f0):
            raise DataValidationError(
                "S", f"{self.kind} coefficients must be finite, got {S}, f0={self.f0}"
            )
        object.__setattr__(self, "S", S)
        object.__setattr__(self, "f0", float(self.f0))
        if self.eta is not None:
            if (
                isinstance(self.eta, bool)
                or not isinstance(self.eta, (int, float))
                or not (np.isfinite(self.eta) and self.eta > 0)
            ):
                raise DataValidationError(
                    "eta", f"expected a positive drive-lag rate [1/s] or None, got {self.eta!r}"
                )
            object.__setattr__(self, "eta", float(self.eta))
        if self.rho_range is not None:
            rr = tuple(float(b) for b in self.rho_range)
            if len(rr) != 2 or not (np.isfinite(rr[0]) and np.isfinite(rr[1]) and rr[0] <= rr[1]):
                raise DataValidationError(
                    "rho_range",
                    f"expected finite (low, high) with low <= high, got {self.rho_range!r}",
                )
            object.__setattr__(self, "rho_range", rr)

    @classmethod
    def layout_arrays(cls) -> tuple[np.ndarray, np.ndarray]:
        """Component index (0..4 for A, a, b, c, d) and input exponent of each coefficient."""
        lay = np.asarray(cls.LAYOUT, dtype=np.int64).reshape(-1, 2)
        return np.ascontiguousarray(lay[:, 0]), np.ascontiguousarray(lay[:, 1])

    def components(self, i: np.ndarray | float) -> dict[str, np.ndarray]:
        """Values of the five components at input ``i`` [A or V].

        Returns
        -------
        dict
            ``A`` [N], ``a`` [s/m], ``b`` [1/m], ``c`` [N s/m], ``d`` [N/m] as arrays shaped like
            ``i``.
        """
        comp, power = self.layout_arrays()
        values = component_values(self.S, comp, power, i)
        return {name: values[m] for m, name in enumerate(COMPONENTS)}

    def velocity_slope_floor(self) -> tuple[float, float]:
        """Smallest ``dF/dv`` [N s/m] of the map over its identified input range (the lagged
        input's with ``eta``) and the input [A or V] where it is reached; negative: the force
        falls with velocity there (see the estimator's ``monotone``)."""
        comp, power = self.layout_arrays()
        lo, hi = self.rho_range if self.rho_range is not None else self.input_range
        return velocity_slope_floor(np.asarray(self.S, dtype=np.float64), comp, power, lo, hi)

    def force(self, x: np.ndarray, v: np.ndarray, i: np.ndarray) -> np.ndarray:
        """Evaluate the map on plain arrays (no range policy) [N].

        Parameters
        ----------
        x, v, i : ndarray
            Displacement [m], velocity [m/s], electrical input [A or V].
        """
        comp, power = self.layout_arrays()
        xa, va, ia = (np.ascontiguousarray(a, dtype=np.float64) for a in (x, v, i))
        return sp_force(xa, va, ia, comp, power, np.asarray(self.S, dtype=np.float64), self.f0)

    def inverse_form(self) -> StaticMapForm:
        """The map as the plain arrays of the control kernels (invertible, see
        :class:`~mrdamper.models.protocols.InvertibleModel`)."""
        comp, power = self.layout_arrays()
        return StaticMapForm(comp, power, np.asarray(self.S, dtype=np.float64), self.f0, self.eta)

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The map as a per-sample step (:mod:`mrdamper.models.step`): the state is the drive
        lag's output (with ``eta``) or the input itself; the input is used as given (no range
        policy).

        Parameters
        ----------
        dt, vmax : float
            Interval [s] and largest velocity [m/s] the step will see; unused by this family
            (the common signature of :meth:`~mrdamper.models.FittedModel.step`).
        """
        return make_static_step(self.kind, self.inverse_form())

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N]: direct evaluation on the record's x, v and electrical input
        (through the drive lag when ``eta`` is set; the range policy applies to the input)."""
        i = self.electrical_input(experiment)
        if self.eta is not None:
            i = first_order_lag(np.ascontiguousarray(i, dtype=np.float64), experiment.dt, self.eta)
        return self.force(experiment.x, experiment.v, i)


@dataclass(frozen=True)
class SP1Model(SPModel):
    """SP-1: ``F = S1(i) tanh(S2(i) v + S3(i) x) + S4(i) v + S5(i) x + f0``.

    ``S`` holds 15 coefficients: ``S_j(i) = S[3(j-1)] + S[3(j-1)+1] i + S[3(j-1)+2] i^2`` for
    j = 1..5. Units: S1 [N], S2 [s/m], S3 [1/m], S4 [N s/m], S5 [N/m], each divided by the
    input unit to the power of the term.
    """

    kind: ClassVar[str] = "sp1"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = tuple(
        (m, p) for m in range(5) for p in (0, 1, 2)
    )


@dataclass(frozen=True)
class SP2Model(SPModel):
    """SP-2: ``F = S1 i tanh(S2 v + S3 x) + S4 v + S5 x + f0``.

    ``S = (S1 [N/A], S2 [s/m], S3 [1/m], S4 [N s/m], S5 [N/m])`` (per V with ``input="voltage"``).
    """

    kind: ClassVar[str] = "sp2"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = ((0, 1), (1, 0), (2, 0), (3, 0), (4, 0))


@dataclass(frozen=True)
class SP3Model(SPModel):
    """SP-3: ``F = (S1 i + S2) tanh(S3 v + S4 x) + S5 v + S6 x + f0``.

    ``S = (S1 [N/A], S2 [N], S3 [s/m], S4 [1/m], S5 [N s/m], S6 [N/m])``.
    """

    kind: ClassVar[str] = "sp3"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = ((0, 1), (0, 0), (1, 0), (2, 0), (3, 0), (4, 0))


@dataclass(frozen=True)
class SP4Model(SPModel):
    """SP-4: ``F = (S1 i^2 + S2 i + S3) tanh(S4 v + S5 x) + S6 v + S7 x + f0``.

    ``S = (S1 [N/A^2], S2 [N/A], S3 [N], S4 [s/m], S5 [1/m], S6 [N s/m], S7 [N/m])``.
    """

    kind: ClassVar[str] = "sp4"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = (
        (0, 2),
        (0, 1),
        (0, 0),
        (1, 0),
        (2, 0),
        (3, 0),
        (4, 0),
    )


# ============================================================================ estimators
@dataclass
class _SPEstimator(Estimator):
    """Identifies an SP-k model by multi-start nonlinear least squares (settings only).

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel of the records.
    seed : int
        Seed of the random start draws (``numpy.random.default_rng``); same seed, same model.
    n_starts : int
        Number of starts refined by the nonlinear solver.
    n_candidates : int
        Number of random tanh-argument draws screened by linear least squares.
    offset : bool
        Identify a constant force offset ``f0`` [N] (default). ``False`` fixes ``f0 = 0``,
        the paper's literal form.
    max_nfev : int
        Function-evaluation budget of each nonlinear refinement.
    screen_samples : int
        Samples (evenly spaced over the training data) used for screening and multi-start.
    fit_samples : int or None
        Samples (evenly spaced) used by the final polish; ``None`` uses every sample.
    eta : float, "auto", "identify" or None
        Drive-lag rate [1/s]: the map is fitted to the electrical input passed through the lag
        (per record, see the module docstring). ``"auto"`` (default): identified on the training
        records when the input is a varying command voltage, none otherwise
        (:mod:`mrdamper.models.lag`);
        ``"identify"``: identified whenever the input switches within a record, a measured
        current included (the field's lag); None: no lag.
    monotone : bool or "auto"
        Keep the force from falling with velocity: the tanh amplitude, the tanh velocity
        coefficient and the viscous slope are kept non-negative over the identified input range
        (Bernstein coefficients, module docstring), so ``dF/dv >= 0`` for every motion. A map
        whose force falls with velocity pushes a quarter car at speeds beyond its training data
        and the loop can diverge. ``"auto"`` (default): the free fit, and when its slope
        ``dF/dv`` is negative anywhere on the input range (at any velocity) the constrained fit
        replaces it, with a warning that gives both training errors; ``True``: always
        constrained; ``False``: the free fit (the paper's).
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    """

    input: ElectricalSource = "i"
    seed: int = 0
    n_starts: int = 4
    n_candidates: int = 64
    offset: bool = True
    max_nfev: int = 200
    screen_samples: int = 4000
    fit_samples: int | None = 20000
    eta: float | Literal["auto", "identify"] | None = "auto"
    monotone: bool | Literal["auto"] = "auto"

    range_policy: RangePolicy = "error"

    model_class: ClassVar[type[FittedModel]] = SPModel

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Multi-start nonlinear least squares of the map (see the module docstring).

        Raises
        ------
        IdentificationError
            Too few samples, an input that does not vary enough to identify the current
            dependence, a force without variance, or no start converged to a finite cost.
        """
        cls = cast(type[SPModel], self.model_class)
        comp_all, power_all = cls.layout_arrays()
        report("stacking the samples")
        eta = resolved(self.eta)
        x, v, i, F = stack(
            data.records, self.input, eta, _scale.WINDOW_THRESHOLD
        )  # long campaigns: an even subset
        # one level: every component's polynomial in the input reduces to its constant term
        keep = (
            single_level_terms(comp_all, power_all) if data.single else np.ones(comp_all.size, bool)
        )
        comp, power = comp_all[keep], power_all[keep]
        # the inputs the map sees: the lagged ones (its rho_range) or the records' own range
        span = (float(np.min(i)), float(np.max(i))) if eta is not None else data.input_range

        def fit(monotone: bool) -> tuple[np.ndarray, float, dict[str, Any]]:
            return identify(
                cls.kind,
                self.input,
                comp,
                power,
                x,
                v,
                i,
                F,
                offset=self.offset,
                seed=self.seed,
                n_starts=self.n_starts,
                n_candidates=self.n_candidates,
                max_nfev=self.max_nfev,
                screen_samples=self.screen_samples,
                fit_samples=self.fit_samples,
                monotone=span if monotone else None,
            )

        S_kept, f0, provenance = fit(self.monotone is True)
        slope, at = velocity_slope_floor(S_kept, comp, power, *span)
        check: dict[str, Any] = {
            "setting": self.monotone,
            "constrained": self.monotone is True,
            "slope_floor": slope,
            "slope_floor_at": at,
        }
        if self.monotone == "auto" and slope < 0:
            free_esr = provenance["training_esr"]
            S_kept, f0, provenance = fit(True)
            unit = "A" if self.input == "i" else "V"
            check.update(constrained=True, free_training_esr=free_esr)
            check["note"] = (
                f"{cls.kind}: the free fit's force falls with velocity (dF/dv down to "
                f"{slope:.4g} N s/m at {at:.4g} {unit}), so a loop faster than the training "
                f"motions could diverge; fitted again with dF/dv >= 0 over {span[0]:.4g}-"
                f"{span[1]:.4g} {unit}: training ESR {provenance['training_esr']:.4g} against "
                f"{free_esr:.4g} free (setting monotone)"
            )
            warn_user(check["note"], UserWarning)
        S = np.zeros(comp_all.size)
        S[keep] = S_kept
        provenance = {
            "estimator": type(self).__name__,
            "settings": asdict(self),
            "training_records": list(data.records.names),
            "n_samples": int(sum(e.n for e in data.records)),
            **provenance,
            "monotone": check,
        }
        return Identified(
            parameters={
                "S": tuple(S),
                "f0": f0,
                "eta": eta,
                "rho_range": None if eta is None else (float(np.min(i)), float(np.max(i))),
            },
            provenance=provenance,
        )

    def _validate(self) -> None:
        super()._validate()
        for name, low in (
            ("n_starts", 1),
            ("n_candidates", 1),
            ("max_nfev", 1),
            ("screen_samples", 100),
        ):
            check_int(name, getattr(self, name), low)
        check_int("fit_samples", self.fit_samples, 100, allow_none=True)
        check_int("seed", self.seed, None)
        check_lag(self.eta)
        if not (isinstance(self.monotone, bool) or self.monotone == "auto"):
            raise DataValidationError(
                "monotone", f"expected true, false or 'auto', got {self.monotone!r}"
            )


@dataclass
class SP1Estimator(_SPEstimator):
    """Identifies :class:`SP1Model` (see :class:`_SPEstimator` for the settings)."""

    kind: ClassVar[str] = "sp1"
    model_class: ClassVar[type[FittedModel]] = SP1Model


@dataclass
class SP2Estimator(_SPEstimator):
    """Identifies :class:`SP2Model` (see :class:`_SPEstimator` for the settings)."""

    kind: ClassVar[str] = "sp2"
    model_class: ClassVar[type[FittedModel]] = SP2Model


@dataclass
class SP3Estimator(_SPEstimator):
    """Identifies :class:`SP3Model` (see :class:`_SPEstimator` for the settings)."""

    kind: ClassVar[str] = "sp3"
    model_class: ClassVar[type[FittedModel]] = SP3Model


@dataclass
class SP4Estimator(_SPEstimator):
    """Identifies :class:`SP4Model` (see :class:`_SPEstimator` for the settings)."""

    kind: ClassVar[str] = "sp4"
    model_class: ClassVar[type[FittedModel]] = SP4Model
