"""P-15: Wang's phenomenological MR damper model with current-dependent coefficients.

The model (paper Section V table; READING-NOTES item 1) relates the force ``F`` [N] to the
velocity ``v`` [m/s] and the electrical input ``i`` ([A], or [V] with ``input="voltage"``)::

    F = f0 + w1(i) v + w2(i) dF/dt + w3(i) d2F/dt2 + w4(i) F^3 + w5(i) F^5
    w_j(i) = W[j-1, 0] + W[j-1, 1] i + W[j-1, 2] i^2          (5 x 3 = 15 coefficients)

``f0`` [N] is a constant force offset, identified when ``offset=True`` (default) and exactly 0
with ``offset=False`` (the paper's literal form). With ``m = -w3``, ``c = -w2``,
``a = -w4``, ``b = -w5`` it reads ``m F'' + c F' + g(F) = w1 v + f0``, ``g(F) = F + a F^3 + b F^5``:
a forced nonlinear oscillator for the force.

Stability by construction
-------------------------
The default identification (``method="output-error"``) writes each of ``w1, c, m, a, b`` in the
Bernstein basis of the identified input range with positive coefficients, so on the whole range
``m > 0``, ``c > 0``, ``a > 0``, ``b > 0`` and ``w1 > 0``; then ``g`` is odd and strictly
increasing (``g' >= 1``) and at every frozen input and velocity the ODE has exactly one
equilibrium, which is globally asymptotically stable (proof in ``docs/models.md``).
:meth:`P15Model.stability_certificate` checks these conditions on any coefficient set.

Simulation
----------
``(F, dF/dt)`` is integrated with the two-stage L-stable SDIRK2 scheme of
:mod:`mrdamper.models.p15.kernels`, ``ceil(dt / max_step)`` steps per sample, ``v`` and ``i``
linear between samples. L-stability keeps the stiff part of the force ODE (fast force relaxation
at large ``|F|``) stable at any step; the step is chosen for accuracy and checked by the
estimator: the free run of every training record is repeated with half the step and the change
(in ESR units) must stay below ``step_tolerance``, else a warning names the model and the
discrepancy (also in ``provenance["step_check"]``).

Free run starts from the model's rest state, like the other models' (LPV from zero initial
conditions, Spencer from its rest state): ``dF/dt = 0`` and ``F`` the equilibrium for the
record's first velocity and input (:func:`mrdamper.models.p15.fit.rest_state`). The measured
force is never used. A non-finite state, ``|F|`` above ``force_bound`` (10 x the training force
span), an implicit stage without a root, or ``w3(i)`` reaching zero along the record raises
:class:`~mrdamper.errors.SimulationDivergedError` with the first offending sample.

Identification
--------------
``method="output-error"`` (default): :mod:`mrdamper.models.p15.fit` (multiple shooting from the
measured state over short segments, then free-run least squares; forward sensitivities of the
compiled integrator), started from the ``form="monotone"`` equation-error fit.
``method="equation-error"``: the paper's reading, linear least squares of the relation on
filtered derivatives (:mod:`mrdamper.models.p15.fit`), ``form="free"`` (literal),
``"stable"`` or ``"monotone"`` (sign constraints on the Bernstein coefficients).

Examples
--------
>>> import numpy as np
>>> from mrdamper import Experiment
>>> W = np.array([[1500, 2000, 0], [-2e-3, -1e-3, 0], [-1e-6, 0, 0], [-2e-6, 0, 0], [-1e-12, 0, 0]])
>>> m = P15Model(W=tuple(W.ravel()), input_range=(0.0, 1.0), force_bound=1e5, max_step=1e-4)
>>> m.stability_certificate()["stable_by_construction"]
True
>>> t = np.arange(1000) / 1000.0
>>> v = 0.1 * np.sin(2 * np.pi * 2 * t)
>>> e = Experiment(t=t, x=0 * t, v=v, F=0 * t, i=0.5 + 0 * t)
>>> F = m.predict(e)
>>> bool(np.all(np.isfinite(F)))
True
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from mrdamper.analysis.laws import BLOCK
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _scale
from mrdamper.models._lag import first_order_lag
from mrdamper.models._step_check import step_halving_check
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
    check_number,
)
from mrdamper.models.lag import check_lag, resolved
from mrdamper.models.p15 import kernels as _k
from mrdamper.models.p15.fit import (
    BERNSTEIN_TO_POWER,
    bernstein_basis,
    check_levels,
    equation_error,
    filtered_state,
    identify_output_error,
    rest_state,
    to_monomial,
)
from mrdamper.models.p15.kernels import p15i_run
from mrdamper.models.step import Step
from mrdamper.progress import report

__all__ = ["P15Estimator", "P15Model"]


@dataclass(frozen=True)
class P15Model(FittedModel):
    """Identified P-15 model (see the module docstring for the equation).

    Attributes
    ----------
    W : tuple of 15 float
        Row-major 5 x 3 coefficients of ``w_1 .. w_5`` in the basis ``basis``. Units: w1 [N s/m],
        w2 [s], w3 [s^2], w4 [1/N^2], w5 [1/N^4] (in the power basis, each per input unit to the
        power of the term).
    f0 : float
        Force offset [N].
    force_bound : float
        Largest accepted ``|F|`` during simulation [N] (10 x the training force span).
    max_step : float
        Largest integration step [s] (``inf``: one step per sample).
    eta : float or None
        Rate [1/s] of an optional first-order drive lag ``d rho/dt = -eta (rho - input)`` (exact
        zero-order-hold discretisation, ``rho(t0) = input(t0)``); the coefficients are then
        quadratics in ``rho`` (for records whose electrical input is a command voltage, as in the
        LPV model). ``None``: the input itself.
    basis : {"power", "bernstein"}
        ``"power"``: ``w_j(i) = W[3(j-1)] + W[3(j-1)+1] i + W[3(j-1)+2] i^2``. ``"bernstein"``
        (what the estimator returns): ``W[3(j-1) + k]`` multiplies the Bernstein polynomial
        ``B_k(s)`` (``(1-s)^2, 2s(1-s), s^2``) of ``s = (i - lo) / (hi - lo)`` on ``input_range``,
        with ``s`` clipped to [0, 1]: the coefficients are held at their edge values outside the
        identified range (where a quadratic could otherwise lose its sign), and positivity is exact
        in floating point.
    """

    W: tuple[float, ...] = (0.0,) * 15
    f0: float = 0.0
    force_bound: float = 1e6
    max_step: float = math.inf
    eta: float | None = None
    basis: Literal["power", "bernstein"] = "power"

    kind: ClassVar[str] = "p15"

    def __post_init__(self) -> None:
        super().__post_init__()
        W = tuple(float(w) for w in np.asarray(self.W, dtype=float).ravel())
        if len(W) != 15:
            raise DataValidationError("W", f"p15 has 15 coefficients (5 x 3), got {len(W)}")
        if not all(math.isfinite(w) for w in W) or not math.isfinite(self.f0):
            raise DataValidationError(
                "W", f"p15 coefficients must be finite, got {W}, f0={self.f0}"
            )
        if not self.force_bound > 0:
            raise DataValidationError(
                "force_bound", f"expected a positive force [N], got {self.force_bound}"
            )
        if not self.max_step > 0:
            raise DataValidationError(
                "max_step", f"expected a positive step [s], got {self.max_step}"
            )
        if self.eta is not None and not (math.isfinite(self.eta) and self.eta > 0):
            raise DataValidationError(
                "eta", f"expected a positive drive-lag rate [1/s] or None, got {self.eta!r}"
            )
        if self.basis not in ("power", "bernstein"):
            raise DataValidationError(
                "basis", f"expected 'power' or 'bernstein', got {self.basis!r}"
            )
        if self.basis == "bernstein" and not self.input_range[1] > self.input_range[0]:
            raise DataValidationError(
                "input_range", f"the Bernstein basis needs lo < hi, got {self.input_range}"
            )
        object.__setattr__(self, "W", W)
        object.__setattr__(self, "f0", float(self.f0))
        object.__setattr__(self, "force_bound", float(self.force_bound))
        object.__setattr__(self, "max_step", float(self.max_step))

    @property
    def W_matrix(self) -> np.ndarray:
        """Stored coefficients as a (5, 3) array (row j-1: ``w_j`` in the model's ``basis``)."""
        return np.asarray(self.W, dtype=np.float64).reshape(5, 3)

    def coefficients(self, i: np.ndarray | float) -> np.ndarray:
        """``w_1 .. w_5`` at input ``i`` [A or V]; shape ``(5,) + shape(i)``."""
        ii = np.asarray(i, dtype=float)
        Wm = self.W_matrix
        if self.basis == "bernstein":
            phi = bernstein_basis(ii, *self.input_range)
            return np.stack(
                [Wm[j, 0] * phi[0] + Wm[j, 1] * phi[1] + Wm[j, 2] * phi[2] for j in range(5)]
            )
        return np.stack([Wm[j, 0] + Wm[j, 1] * ii + Wm[j, 2] * ii**2 for j in range(5)])

    def monomial(self) -> np.ndarray:
        """Power-basis coefficients (5 x 3, ``w_j = c0 + c1 i + c2 i^2``).

        Valid on ``input_range``.
        """
        if self.basis == "power":
            return self.W_matrix
        return to_monomial(self.W_matrix, *self.input_range)

    def bernstein(self) -> np.ndarray:
        """Bernstein coefficients (5 x 3) of ``w1, c = -w2, m = -w3, a = -w4, b = -w5`` on
        ``input_range``: a row of non-negative coefficients proves that quadratic non-negative on
        the whole range."""
        lo, hi = self.input_range
        if hi < lo:
            raise DataValidationError("input_range", f"expected lo <= hi, got {self.input_range}")
        if hi == lo:  # a one-point range: the Bernstein coefficients are the values there
            B = np.repeat(self.coefficients(lo)[:, None], 3, axis=1)
        elif self.basis == "bernstein":
            B = self.W_matrix
        else:
            R = hi - lo
            to_i = np.array(
                [
                    [1.0, -lo / R, lo**2 / R**2],
                    [0.0, 1.0 / R, -2 * lo / R**2],
                    [0.0, 0.0, 1.0 / R**2],
                ]
            )
            M = to_i @ BERNSTEIN_TO_POWER  # Bernstein -> monomial
            B = np.linalg.solve(M, self.W_matrix.T).T
        return np.asarray(B * np.array([1.0, -1.0, -1.0, -1.0, -1.0])[:, None])

    def stability_certificate(self) -> dict[str, Any]:
        """Check the sufficient conditions for stability on ``input_range`` (``docs/models.md``).

        Returns
        -------
        dict
            ``min_bernstein``: smallest Bernstein coefficient of each of ``w1, c, m, a, b``,
            relative to the largest magnitude of the same quadratic; ``stable_by_construction``:
            ``m, c`` positive and ``a, b`` non-negative on the range (``g`` strictly increasing;
            exact for ``basis="bernstein"``, up to ~1e-12 rounding of the power basis otherwise);
            ``passive``: also ``w1 > 0``; ``outside_range``: how the coefficients continue beyond
            the range (held at the edge values for the Bernstein basis, so the conditions hold for
            every input).
        """
        B = self.bernstein()
        rel = {}
        for name, row in zip(("w1", "c", "m", "a", "b"), B):
            top = float(np.max(np.abs(row))) or 1.0
            rel[name] = float(np.min(row) / top)
        tol = 0.0 if self.basis == "bernstein" else -1e-9
        stable = rel["m"] > 0 and rel["c"] > 0 and rel["a"] >= tol and rel["b"] >= tol
        return {
            "min_bernstein": rel,
            "stable_by_construction": bool(stable),
            "passive": bool(stable and rel["w1"] > 0),
            "outside_range": "held at edge values"
            if self.basis == "bernstein"
            else "quadratic extrapolation",
        }

    def substeps(self, dt: float) -> int:
        """Integration steps per sampling interval ``dt`` [s] (at most :data:`MAX_SUBSTEPS`)."""
        return int(_k.substeps(float(dt), self.max_step))

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N], from the model's rest state at the first sample.

        Raises
        ------
        SimulationDivergedError
            If ``w3(i)`` reaches zero or changes sign along the record, an implicit stage has no
            root, or the force becomes non-finite or exceeds ``force_bound``; the error names
            the first such sample.
        """
        return self.simulate_steps(experiment, self.substeps(experiment.dt))

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The model as a per-sample step (:mod:`mrdamper.models.step`).

        The state is ``(F, G, rho)``: force [N], its rate [N/s] and the model's input (through
        the drive lag with ``eta``), at rest ``(F_rest(e[0], v[0]), 0, e[0])``. ``advance``
        integrates an interval of ``dt`` with ``ceil(dt / max_step)`` steps of the L-stable
        scheme :meth:`predict` takes (the step the estimator checked by halving it), the inputs
        linear in between; it reports divergence like :meth:`predict` but does not check the
        sign of ``w3`` along the input, and applies no range policy. The force is a state: it
        does not depend on the present input (``feedthrough`` False).

        Parameters
        ----------
        dt, vmax : float
            Interval [s] and largest velocity [m/s] the step will see; unused by this family
            (the common signature of :meth:`~mrdamper.models.FittedModel.step`).
        """
        bern = self.basis == "bernstein"
        lo, hi = self.input_range if bern else (0.0, 1.0)
        form = _k.P15Form(
            np.ascontiguousarray(self.W_matrix),
            self.f0,
            int(bern),
            float(lo),
            float(hi),
            self.max_step,
            self.force_bound,
            -1.0 if self.eta is None else float(self.eta),
        )

        def initial_state(x0: float, v0: float, e0: float) -> np.ndarray:
            F0 = rest_state(self.coefficients(float(e0)), self.f0, float(v0))
            return np.array([F0, 0.0, e0])

        return Step(
            self.kind, form, _k.step_force, _k.step_advance, initial_state, feedthrough=False
        )

    def _check_w3(self, i: np.ndarray) -> None:
        """Raise if ``w3(i)`` vanishes or changes sign along ``i`` (block by block of
        :data:`~mrdamper.analysis.laws.BLOCK` samples: bounded temporaries on long records)."""
        w30 = float(self.coefficients(i[:1])[2][0])
        for a in range(0, i.size, BLOCK):
            w3 = self.coefficients(i[a : a + BLOCK])[2]
            bad = np.flatnonzero((w3 == 0) | (np.sign(w3) != np.sign(w30)))
            if bad.size:
                k = a + int(bad[0])
                raise SimulationDivergedError(
                    self.kind,
                    k,
                    f"w3({self.input}) changes sign or vanishes at {self.input}={i[k]:.6g} (w3 "
                    f"from {w30:.3g} at sample 0 to {w3[bad[0]]:.3g}); the force ODE is singular "
                    "there",
                )

    def simulate_steps(self, experiment: Experiment, n_sub: int) -> np.ndarray:
        """Free-run force [N] with ``n_sub`` integration steps per sample (see :meth:`predict`)."""
        i = _lagged(
            np.asarray(self.electrical_input(experiment), dtype=np.float64), experiment.dt, self.eta
        )
        self._check_w3(i)
        v = np.ascontiguousarray(experiment.v, dtype=np.float64)
        F0 = rest_state(self.coefficients(float(i[0])), self.f0, float(v[0]))
        one = np.zeros(1, dtype=np.int64)
        bern = self.basis == "bernstein"
        lo, hi = self.input_range if bern else (0.0, 1.0)
        F, _, bad = p15i_run(
            v,
            i,
            experiment.dt,
            self.W_matrix,
            self.f0,
            int(bern),
            lo,
            hi,
            int(n_sub),
            self.force_bound,
            one,
            np.array([experiment.n], dtype=np.int64),
            np.array([F0]),
            np.zeros(1),
            np.zeros((1, 16)),
            False,
            True,
        )
        if bad[0] >= 0:
            k = int(bad[0])
            raise SimulationDivergedError(
                self.kind,
                k,
                f"force left the bound |F| <= {self.force_bound:.4g} N, became non-finite or an "
                f"implicit stage had no root (t = {experiment.t[k]:.6g} s, {n_sub} steps per "
                "sample)",
            )
        return F


@dataclass
class P15Estimator(Estimator):
    """Identifies :class:`P15Model`.

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel.
    method : {"output-error", "equation-error"}
        ``"output-error"`` (default): least squares on the simulated force with the
        stable-by-construction parametrisation (multiple shooting, then free run).
        ``"equation-error"``: least squares of the relation on filtered derivatives, the paper's
        reading (with ``form="free"`` its literal form).
    form : {"free", "stable", "monotone"}
        Sign constraints of the equation-error fit (``method="equation-error"`` only; the
        output-error fit starts from the ``"monotone"`` equation-error fit).
    cutoff : float, "auto" or None
        Low-pass cut-off [Hz] of the zero-phase derivative filter (``"auto"``: ``min(fs / 10,
        100)`` per record; ``None``: no filter). Also filters the measured state from which the
        shooting segments start.
    filter_order : int
        Butterworth order (run forward and backward).
    offset : bool
        Identify the force offset ``f0`` [N] (default) or fix it to 0.
    stable_only : bool
        Raise :class:`IdentificationError` if a training record's free run diverges.
    max_step : float
        Largest integration step [s] used by the fit and given to the model (default 2.5 ms: two
        steps per sample at 200 Hz, one at 1 kHz and above), refined after the fit if the step
        check asks for it (``step_tolerance``).
    segment : float
        Duration [s] of the multiple-shooting segments.
    segment_stride : int
        Use every ``segment_stride``-th segment in the shooting stage (1: all).
    shoot_nfev, max_nfev : int
        Evaluation budgets of the shooting stage and of the free-run stage (0 skips a stage).
    shoot_nfev_max : int, optional
        Largest number of shooting evaluations in all: a shooting stage stopped by its budget
        ``shoot_nfev`` while the budget still cut the cost by more than 1 % continues with
        another budget, up to this number (default None: 4 x ``shoot_nfev``, 120 with the
        defaults; ``shoot_nfev`` turns the continuation off). A stage that converges within its
        first budget is not affected.
    max_samples : int
        Largest number of residual samples per evaluation (every k-th sample).
    jacobian : {"sensitivity", "2-point", "3-point"}
        Forward sensitivities (default) or SciPy finite differences (for comparison only).
    step_tolerance : float
        Largest accepted change of a training record's free run when the integration step is
        halved, in ESR units (mean squared change over the variance of the measured force).
        Above it the fit halves the model's step (at most ``step_refinements`` times) and checks
        again; a warning names the model and the discrepancy if it still fails.
    step_refinements : int
        How many times the fit may halve the model's step to meet ``step_tolerance``.
    eta : float, "auto", "identify" or None
        Drive-lag rate [1/s] of a first-order lag ``d rho/dt = -eta (rho - input)`` on the
        electrical input. ``"auto"`` (default): identified on the training records when the
        input is a varying command voltage, none otherwise (:mod:`mrdamper.models.lag`);
        ``"identify"``: identified whenever the input switches within a record, a measured
        current included (the field's lag); None: no
        lag.
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    """

    input: ElectricalSource = "i"
    method: Literal["output-error", "equation-error"] = "output-error"
    form: Literal["free", "stable", "monotone"] = "free"
    cutoff: float | Literal["auto"] | None = "auto"
    filter_order: int = 4
    offset: bool = True
    stable_only: bool = False
    max_step: float = 2.5e-3
    segment: float = 0.2
    segment_stride: int = 1
    shoot_nfev: int = 30
    max_nfev: int = 20
    shoot_nfev_max: int | None = None
    max_samples: int = 20000
    jacobian: Literal["sensitivity", "2-point", "3-point"] = "sensitivity"
    step_tolerance: float = 1e-4
    step_refinements: int = 3
    eta: float | Literal["auto", "identify"] | None = "auto"
    range_policy: RangePolicy = "error"

    kind: ClassVar[str] = "p15"
    model_class: ClassVar[type[FittedModel]] = P15Model

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Equation-error start, then (by default) output-error fit; step check of the result.

        At a single input level the five coefficient quadratics are constants (one coefficient
        each; the model is stored in the power basis with its range that one level).

        Raises
        ------
        DataValidationError
            A cut-off at or above a record's Nyquist frequency.
        IdentificationError
            Too few samples, an input with fewer than three distinct levels (and more than one),
            an ill-conditioned regression, or (with ``stable_only``) a diverging training
            simulation.
        """
        raw_all = data.records
        raw, windows = _scale.window_set(raw_all, budget=_scale.WINDOW_BUDGET_P15)  # long campaigns
        # the range of the raw input also holds every lagged input (a convex combination of it)
        lo, hi = data.input_range
        eta = resolved(self.eta)
        exps = (
            raw
            if eta is None
            else ExperimentSet(
                [
                    e.replace(**{self.input: _lagged(e.electrical(self.input), e.dt, eta)})
                    for e in raw
                ]
            )
        )
        if not data.single:
            check_levels(
                np.concatenate([e.electrical(self.input) for e in exps]), lo, hi, self.input
            )
        form = self.form if self.method == "equation-error" else "monotone"
        report("equation-error start")
        B, f0, ee_info = equation_error(
            list(exps),
            self.input,
            lo,
            hi,
            form=form,
            offset=self.offset,
            cutoff=self.cutoff,
            order=self.filter_order,
            single=data.single,
        )
        span = float(max(np.ptp(e.F) for e in exps))
        bound = 10.0 * span
        oe_info: dict[str, Any] = {}
        if self.method == "output-error":
            states = [filtered_state(e, self.cutoff, self.filter_order) for e in exps]
            B, f0, oe_info = identify_output_error(
                list(exps),
                self.input,
                lo,
                hi,
                B,
                f0,
                Ff=[s[0] for s in states],
                Gf=[s[1] for s in states],
                offset=self.offset,
                max_step=self.max_step,
                segment=self.segment,
                segment_stride=self.segment_stride,
                shoot_nfev=self.shoot_nfev,
                max_nfev=self.max_nfev,
                shoot_nfev_max=(
                    4 * self.shoot_nfev if self.shoot_nfev_max is None else self.shoot_nfev_max
                ),
                max_samples=self.max_samples,
                jacobian=self.jacobian,
                bound=bound,
                single=data.single,
            )
        if data.single:  # constants: the power basis, W[:, 0] = w_j, higher powers exactly 0
            W = np.zeros((5, 3))
            W[:, 0] = B[:, 0]
            basis: Literal["power", "bernstein"] = "power"
        else:
            W, basis = B, "bernstein"
        model = P15Model(
            W=tuple(W.ravel()),
            f0=f0,
            input=self.input,
            input_range=(lo, hi),
            force_bound=bound,
            max_step=self.max_step,
            eta=eta,
            basis=basis,
        )
        report("free run of the training records")
        divergence, esr = _simulate_training(model, raw)
        report("step-size check")
        model, step = self._checked_step(model, [e for e in raw if e.name not in divergence])
        w3_grid = model.coefficients(np.linspace(lo, hi, 201))[2]
        provenance: dict[str, Any] = {
            "estimator": type(self).__name__,
            "settings": asdict(self),
            "training_records": list(raw.names),
            **ee_info,
            "output_error": oe_info,
            "stability": model.stability_certificate(),
            "w3_range": [float(w3_grid.min()), float(w3_grid.max())],
            "w3_crosses_zero": bool(w3_grid.min() <= 0 <= w3_grid.max()),
            "training_divergence": divergence,
            "training_esr": esr,
            "step_check": step,
        }
        if windows is not None:
            provenance["windows"] = windows
            report("full-data check")
            provenance["full_data_check"] = _scale.full_data_esr(model, raw_all)
        if self.stable_only and divergence:
            first = next(iter(divergence.items()))
            raise IdentificationError(
                f"p15: free-run simulation of {len(divergence)} training record(s) diverged "
                f"(first: {first[0]!r} at sample {first[1]['sample']}); stable_only=True. "
                f"Use method='output-error' (stable by construction)"
            )
        return Identified(parameters=model.parameters, provenance=provenance)

    def _checked_step(
        self, model: P15Model, records: list[Experiment]
    ) -> tuple[P15Model, dict[str, Any]]:
        """Halve the model's step until halving it again changes no training free run by more than
        ``step_tolerance`` (at most ``step_refinements`` times); warn if that is not reached."""
        history = []
        for k in range(self.step_refinements + 1):
            last = k == self.step_refinements
            with warnings.catch_warnings():
                if not last:
                    warnings.simplefilter("ignore", RuntimeWarning)
                check = step_halving_check(
                    "p15", records, functools.partial(_run_refined, model), self.step_tolerance
                )
            history.append(
                {"max_step": model.max_step, "max_discrepancy": check["max_discrepancy"]}
            )
            if check["passed"] or last:
                break
            model = dataclasses.replace(
                model, max_step=0.5 * min(model.max_step, min(e.dt for e in records))
            )
        return model, {**check, "history": history, "max_step": model.max_step}

    def _validate(self) -> None:
        super()._validate()
        check_lag(self.eta)
        check_int("step_refinements", self.step_refinements, 0, 10)
        if self.cutoff != "auto":
            check_number(
                "cutoff", self.cutoff, allow_none=True, what="'auto' or a positive frequency [Hz]"
            )
        check_int("filter_order", self.filter_order, 1, 8)
        for name, low in (
            ("shoot_nfev", 0),
            ("max_nfev", 0),
            ("max_samples", 100),
            ("segment_stride", 1),
        ):
            check_int(name, getattr(self, name), low)
        if self.shoot_nfev_max is not None:
            check_int("shoot_nfev_max", self.shoot_nfev_max, 0)
        for name in ("max_step", "segment", "step_tolerance"):
            check_number(name, getattr(self, name))


def _run_refined(model: P15Model, e: Experiment, k: int) -> np.ndarray:
    """Free run of ``e`` with ``k`` times the model's integration steps per sample."""
    return model.simulate_steps(e, k * model.substeps(e.dt))


def _lagged(e: np.ndarray, dt: float, eta: float | None) -> np.ndarray:
    """The input through the drive lag ``eta`` [1/s], contiguous float64.

    Unchanged for ``None``.
    """
    e = np.ascontiguousarray(e, dtype=np.float64)
    return e if eta is None else first_order_lag(e, dt, eta)


def _simulate_training(
    model: P15Model, exps: Iterable[Experiment]
) -> tuple[dict[str, Any], dict[str, float]]:
    divergence: dict[str, Any] = {}
    esr: dict[str, float] = {}
    for e in exps:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                esr[e.name] = float(model.score(e).esr)
        except SimulationDivergedError as exc:
            divergence[e.name] = {"sample": int(exc.sample), "message": str(exc)}
    return divergence, esr
