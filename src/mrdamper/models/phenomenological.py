"""P-15: Wang's phenomenological MR damper model with current-dependent coefficients.

The model (paper Section V table; READING-NOTES item 1) relates the force ``F`` [N] to the
velocity ``v`` [m/s] and the electrical input ``i`` ([A], or [V] with ``input="voltage"``)::

    F = f0 + w1(i) v + w2(i) dF/dt + w3(i) d2F/dt2 + w4(i) F^3 + w5(i) F^5
    w_j(i) = W[j-1, 0] + W[j-1, 1] i + W[j-1, 2] i^2          (5 x 3 = 15 coefficients)

``f0`` [N] is a constant force offset (accumulator preload, load-cell zero), identified when
``offset=True`` (default) and exactly 0 with ``offset=False`` (the paper's literal form).

The relation is implicit in ``F``: the force is the solution of a second-order ODE. Simulation
solves it for the highest derivative,

    d2F/dt2 = (F - f0 - w1 v - w2 dF/dt - w4 F^3 - w5 F^5) / w3,

and integrates ``(F, dF/dt)`` with compiled fixed-step RK4 (:mod:`mrdamper.models._p15_kernels`).
Writing ``m = -w3`` and ``c = -w2`` gives ``m F'' + c F' + g(F) = w1 v`` with
``g(F) = F - w4 F^3 - w5 F^5 - f0``: a forced nonlinear oscillator whose S-shaped ``g`` produces
the hysteresis. It is well posed only for ``w3 != 0`` and is dissipative and bounded for
``w3 < 0``, ``w2 < 0``, ``w5 < 0`` (``form="stable"`` imposes these signs; see below).

Identification
--------------
Equation-error linear least squares on filtered derivatives, per record (records are never
joined: filtering and differentiation stop at record edges):

1. ``F`` and ``v`` pass a zero-phase Butterworth low-pass (``filter_order``, default 4, run
   forward and backward, so no phase lag between F, its derivatives and v) with cut-off
   ``cutoff`` [Hz]. Default ``"auto"``: a tenth of each record's sampling rate, capped at
   100 Hz (1 kHz records: 100 Hz; 200 Hz records: 20 Hz; 3 kHz records: 100 Hz). The measured
   force of an MR damper holds sharp reversals, so the cut-off must stay well above the
   excitation frequency; the second derivative amplifies noise with the cut-off squared, so it
   must stay well below Nyquist. ``docs/models.md`` reports how the real-data results move with
   the cut-off.
2. ``dF/dt`` and ``d2F/dt2`` are second-order central differences of the filtered force
   (:func:`numpy.gradient`); ``3 fs / cutoff`` samples are trimmed at both record edges.
3. The quadratics ``w_j(i)`` are expanded in the Bernstein basis of ``s = (i - lo) / (hi - lo)``
   over the training input range (well conditioned on [0, 1]); columns are scaled to unit norm;
   the condition number of the scaled regression is checked (``IdentificationError`` above
   ``1e10``, a warning above ``1e6``) and stored in provenance. The coefficients are converted
   exactly to the monomial ``W`` above.
4. ``form="free"`` (default, the paper's plain least squares) or ``form="stable"``: bounded least
   squares (:func:`scipy.optimize.lsq_linear`) with every Bernstein coefficient of ``w3`` and
   ``w2`` below zero and of ``w5`` at most zero, which is sufficient for ``w3 < 0``, ``w2 < 0``,
   ``w5 <= 0`` on the whole training input range; ``form="monotone"`` adds ``w4 <= 0`` so that
   ``g`` is increasing (no bistable branch, a saturating static force-velocity curve).

After the fit every training record is simulated. A divergence is recorded in
``provenance["training_divergence"]`` (record name -> sample), and with ``stable_only=True`` it
raises :class:`~mrdamper.errors.IdentificationError` instead. An unstable least-squares fit is a
legitimate result of the method: it is reported, never hidden.

Simulation details
------------------
* Initial conditions: ``F(t0)`` and ``dF/dt(t0)`` are the value and slope at ``t0`` of a straight
  line fitted to the measured force over the record's first 5 ms (at least 3 samples). This is
  the only use of the measured force; the rest of the free run sees x, v and the input only.
* Sub-steps: ``n_sub = ceil(dt / max_step)`` RK4 steps per sample, where ``max_step`` [s] is
  stored in the model: half the inverse of the largest eigenvalue modulus of the linearised ODE
  over the training input range and force span (so ``h |lambda| <= 0.5``), and at most 2000.
* Divergence: a non-finite state or ``|F|`` above ``force_bound`` (10 x the training force span)
  raises :class:`~mrdamper.errors.SimulationDivergedError` with the first offending sample, as
  does ``w3(i)`` reaching zero or changing sign along the record's input.

Examples
--------
>>> import numpy as np
>>> from mrdamper import Experiment
>>> W = np.array([[1500, 2000, 0], [-2e-3, -1e-3, 0], [-1e-6, 0, 0], [2e-6, 0, 0], [-1e-12, 0, 0]])
>>> m = P15Model(W=tuple(W.ravel()), input_range=(0.0, 1.0), force_bound=1e5, max_step=1e-4)
>>> t = np.arange(1000) / 1000.0
>>> v = 0.1 * np.sin(2 * np.pi * 2 * t)
>>> e = Experiment(t=t, x=0 * t, v=v, F=0 * t, i=0.5 + 0 * t)
>>> F = m.predict(e)
>>> bool(np.all(np.isfinite(F)))
True
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from typing import Any, ClassVar, Literal

import numpy as np
from scipy.optimize import least_squares, lsq_linear
from scipy.signal import butter, sosfiltfilt

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models._p15_kernels import p15_sensitivities, p15_simulate
from mrdamper.models.base import Estimator, FittedModel
from mrdamper.models.registry import register

__all__ = ["P15Estimator", "P15Model"]

#: Upper limit of RK4 sub-steps per sampling interval.
MAX_SUBSTEPS = 2000
#: Condition number of the scaled regression above which identification fails / warns.
_COND_FAIL, _COND_WARN = 1e10, 1e6
#: Samples required per coefficient.
_SAMPLES_PER_PARAMETER = 10
#: Length of the initial-condition window [s].
_IC_WINDOW = 5e-3


@dataclass(frozen=True)
class P15Model(FittedModel):
    """Identified P-15 model (see the module docstring for the equation).

    Attributes
    ----------
    W : tuple of 15 float
        Row-major 5 x 3 coefficients, ``w_j(i) = W[3(j-1)] + W[3(j-1)+1] i + W[3(j-1)+2] i^2``.
        Units: w1 [N s/m], w2 [s], w3 [s^2], w4 [1/N^2], w5 [1/N^4], each per input unit to the
        power of the term.
    f0 : float
        Force offset [N].
    force_bound : float
        Largest accepted ``|F|`` during simulation [N] (10 x the training force span).
    max_step : float
        Largest RK4 step [s].
    """

    W: tuple[float, ...] = (0.0,) * 15
    f0: float = 0.0
    force_bound: float = 1e6
    max_step: float = math.inf

    kind: ClassVar[str] = "p15"

    def __post_init__(self) -> None:
        super().__post_init__()
        W = tuple(float(w) for w in np.asarray(self.W, dtype=float).ravel())
        if len(W) != 15:
            raise DataValidationError("W", f"p15 has 15 coefficients (5 x 3), got {len(W)}")
        if not all(math.isfinite(w) for w in W) or not math.isfinite(self.f0):
            raise DataValidationError("W", f"p15 coefficients must be finite, got {W}, f0={self.f0}")
        if not self.force_bound > 0:
            raise DataValidationError("force_bound", f"expected a positive force [N], got {self.force_bound}")
        if not self.max_step > 0:
            raise DataValidationError("max_step", f"expected a positive step [s], got {self.max_step}")
        object.__setattr__(self, "W", W)
        object.__setattr__(self, "f0", float(self.f0))
        object.__setattr__(self, "force_bound", float(self.force_bound))
        object.__setattr__(self, "max_step", float(self.max_step))

    @property
    def W_matrix(self) -> np.ndarray:
        """Coefficients as a (5, 3) array: row j-1 holds ``w_j``'s constant, linear, quadratic term."""
        return np.asarray(self.W, dtype=np.float64).reshape(5, 3)

    def coefficients(self, i: np.ndarray | float) -> np.ndarray:
        """``w_1 .. w_5`` at input ``i`` [A or V]; shape ``(5,) + shape(i)``."""
        ii = np.asarray(i, dtype=float)
        Wm = self.W_matrix
        return np.stack([Wm[j, 0] + Wm[j, 1] * ii + Wm[j, 2] * ii**2 for j in range(5)])

    def substeps(self, dt: float) -> int:
        """RK4 sub-steps per sampling interval ``dt`` [s] (at most :data:`MAX_SUBSTEPS`)."""
        if not math.isfinite(self.max_step):
            return 1
        return int(min(MAX_SUBSTEPS, max(1, math.ceil(dt / self.max_step - 1e-12))))

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] (initial state from the first 5 ms of the measured force).

        Raises
        ------
        SimulationDivergedError
            If ``w3(i)`` reaches zero or changes sign along the record, or the force becomes
            non-finite or exceeds ``force_bound``; the error names the first such sample.
        """
        i = np.ascontiguousarray(self.electrical_input(experiment), dtype=np.float64)
        w3 = self.coefficients(i)[2]
        bad = np.flatnonzero((w3 == 0) | (np.sign(w3) != np.sign(w3[0])))
        if bad.size:
            k = int(bad[0])
            raise SimulationDivergedError(
                self.kind, k,
                f"w3({self.input}) changes sign or vanishes at {self.input}={i[k]:.6g} "
                f"(w3 from {w3[0]:.3g} at sample 0 to {w3[k]:.3g}); the force ODE is singular there",
            )
        dt = experiment.dt
        n_sub = self.substeps(dt)
        if n_sub == MAX_SUBSTEPS and dt / self.max_step > MAX_SUBSTEPS:
            warnings.warn(
                f"p15: the ODE needs {math.ceil(dt / self.max_step)} RK4 sub-steps per sample; "
                f"capped at {MAX_SUBSTEPS} (accuracy not guaranteed)",
                RuntimeWarning,
                stacklevel=2,
            )
        F0, G0 = initial_state(experiment)
        F, k = p15_simulate(
            np.ascontiguousarray(experiment.v), i, dt, self.W_matrix, self.f0, F0, G0, n_sub, self.force_bound
        )
        if k >= 0:
            raise SimulationDivergedError(
                self.kind, k,
                f"force left the bound |F| <= {self.force_bound:.4g} N or became non-finite "
                f"(t = {experiment.t[k]:.6g} s, {n_sub} RK4 sub-steps per sample)",
            )
        return F


def initial_state(experiment: Experiment) -> tuple[float, float]:
    """Force [N] and force rate [N/s] at ``t0`` from a line fitted to the first 5 ms of F."""
    m = int(min(experiment.n, max(3, round(_IC_WINDOW * experiment.fs))))
    tt = experiment.t[:m] - experiment.t[0]
    slope, intercept = np.polyfit(tt, experiment.F[:m], 1)
    return float(intercept), float(slope)


@dataclass
class P15Estimator(Estimator):
    """Identifies :class:`P15Model` by least squares on filtered force derivatives.

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel.
    cutoff : float, "auto" or None
        Low-pass cut-off [Hz] of the zero-phase derivative filter; ``"auto"``: ``min(fs / 10,
        100)`` per record; ``None``: no filter (noise-free synthetic data only).
    filter_order : int
        Butterworth order (the filter runs forward and backward: twice the order, zero phase).
    form : {"free", "stable", "monotone"}
        Plain least squares (the paper, default); ``"stable"``: sign-constrained least squares
        (``w3 < 0``, ``w2 < 0``, ``w5 <= 0`` over the training input range); ``"monotone"``:
        additionally ``w4 <= 0``, so ``g(F)`` is increasing and the model has no bistable branch.
    offset : bool
        Identify the force offset ``f0`` [N] (default) or fix it to 0.
    stable_only : bool
        Raise :class:`IdentificationError` if a free-run simulation of a training record
        diverges (default: record it in provenance and return the model).
    refine : bool
        After the equation-error fit, minimise the free-run (output) error by nonlinear least
        squares with forward-sensitivity Jacobians and the same sign bounds as ``form``.
    max_nfev : int
        Evaluation budget of the refinement.
    refine_samples : int
        Largest number of residual samples of the refinement (every k-th sample of each
        simulated record; the simulation itself always runs on every sample).
    """

    input: ElectricalSource = "i"
    cutoff: float | Literal["auto"] | None = "auto"
    filter_order: int = 4
    form: Literal["free", "stable", "monotone"] = "free"
    offset: bool = True
    stable_only: bool = False
    refine: bool = False
    max_nfev: int = 20
    refine_samples: int = 20000

    kind: ClassVar[str] = "p15"

    def fit(self, data: Experiment | Iterable[Experiment]) -> P15Model:
        """Identify P-15 from one record or a collection of records.

        Raises
        ------
        DataValidationError
            Invalid setting, a record without the ``input`` channel, or a cut-off at or above
            a record's Nyquist frequency.
        IdentificationError
            Too few samples, an input with fewer than three distinct levels, an ill-conditioned
            regression, or (with ``stable_only``) a diverging training simulation.
        """
        t_start = time.perf_counter()
        self._check_settings()
        exps = self._as_set(data)
        parts = [self._regressors(e) for e in exps]
        n_total = sum(p[0].size for p in parts)
        n_par = 15 + int(self.offset)
        if n_total < _SAMPLES_PER_PARAMETER * n_par:
            raise IdentificationError(
                f"data: p15 has {n_par} parameters and needs at least {_SAMPLES_PER_PARAMETER * n_par} "
                f"samples after trimming the filter edges, got {n_total}"
            )
        i_all = np.concatenate([e.electrical(self.input) for e in exps])
        lo, hi = float(np.min(i_all)), float(np.max(i_all))
        i_reg = np.concatenate([p[1] for p in parts])
        _check_levels(i_reg, lo, hi, self.input)

        y = np.concatenate([p[0] for p in parts])
        cols = np.concatenate([p[2] for p in parts], axis=0)  # (n, 5): v, dF, ddF, F^3, F^5
        s = (i_reg - lo) / (hi - lo)
        basis = np.stack([(1 - s) ** 2, 2 * s * (1 - s), s**2], axis=1)
        X = (cols[:, :, None] * basis[:, None, :]).reshape(y.size, 15)
        if self.offset:
            X = np.concatenate([X, np.ones((y.size, 1))], axis=1)
        norms = np.sqrt(np.einsum("ij,ij->j", X, X))
        if np.any(norms == 0):
            j = int(np.flatnonzero(norms == 0)[0])
            raise IdentificationError(f"data: regressor {j} of p15 is identically zero; nothing to identify")
        ynorm = float(np.linalg.norm(y)) or 1.0
        Xs, ys = X / norms, y / ynorm
        # einsum without BLAS: the same bytes whatever the BLAS thread count (a fitted P-15 can be
        # chaotic, so rounding differences would otherwise show in its free run)
        gram = np.einsum("ij,ik->jk", Xs, Xs)
        ev = np.linalg.eigvalsh(gram)
        cond = float(np.sqrt(ev[-1] / ev[0])) if ev[0] > 0 else math.inf
        if not cond < _COND_FAIL:
            raise IdentificationError(
                f"data: p15 regression is ill-conditioned (condition number {cond:.3g} > {_COND_FAIL:g}); "
                f"the records do not excite all 15 terms (vary velocity amplitude and {self.input})"
            )
        if cond > _COND_WARN:
            warnings.warn(f"p15: regression condition number {cond:.3g}", RuntimeWarning, stacklevel=2)
        lb, ub = _form_bounds(self.form, X.shape[1])
        if self.form == "free":
            theta = np.linalg.solve(gram, np.einsum("ij,i->j", Xs, ys))
        else:
            theta = lsq_linear(Xs, ys, bounds=(lb, ub), method="bvls").x
        scale = ynorm / norms
        M = _coef_map(lo, hi)
        W = np.einsum("jk,k->j", M, theta[:15] * scale[:15]).reshape(5, 3)
        f0 = float(theta[15] * scale[15]) if self.offset else 0.0
        resid = float(np.sqrt(np.mean((X @ (theta * scale) - y) ** 2)))
        span = float(max(np.ptp(e.F) for e in exps))
        refined: dict[str, Any] = {}
        if self.refine:
            theta, refined = _refine(theta, scale, M, (lb, ub), exps, self, 10.0 * span, lo, hi)
            W = np.einsum("jk,k->j", M, theta[:15] * scale[:15]).reshape(5, 3)
            f0 = float(theta[15] * scale[15]) if self.offset else 0.0
        model = P15Model(
            W=tuple(W.ravel()),
            f0=f0,
            input=self.input,
            input_range=(lo, hi),
            force_bound=10.0 * span,
            max_step=_max_step(W, lo, hi, exps),
        )
        divergence, esr = _simulate_training(model, exps)
        w3_grid = model.coefficients(np.linspace(lo, hi, 201))[2]
        provenance: dict[str, Any] = {
            "estimator": type(self).__name__,
            "settings": asdict(self),
            "training_records": list(exps.names),
            "n_samples": int(y.size),
            "cutoff_hz": {e.name: _cutoff(self.cutoff, e.fs) for e in exps},
            "condition_number": cond,
            "equation_error_rms": resid,
            "refinement": refined,
            "w3_range": [float(w3_grid.min()), float(w3_grid.max())],
            "w3_crosses_zero": bool(w3_grid.min() <= 0 <= w3_grid.max()),
            "training_divergence": divergence,
            "training_esr": esr,
            "elapsed_s": time.perf_counter() - t_start,
        }
        if self.stable_only and divergence:
            first = next(iter(divergence.items()))
            raise IdentificationError(
                f"p15: free-run simulation of {len(divergence)} training record(s) diverged "
                f"(first: {first[0]!r} at sample {first[1]['sample']}); stable_only=True. "
                f"Try form='stable' or another cutoff"
            )
        return P15Model(**{**model.parameters, "input": self.input, "input_range": (lo, hi)},
                        provenance=provenance)

    # ------------------------------------------------------------------ helpers
    def _check_settings(self) -> None:
        if self.input not in ("i", "voltage"):
            raise DataValidationError("input", f"expected 'i' or 'voltage', got {self.input!r}")
        if self.cutoff is not None and self.cutoff != "auto" and (
            isinstance(self.cutoff, bool) or not isinstance(self.cutoff, (int, float)) or not self.cutoff > 0
        ):
            raise DataValidationError("cutoff", f"expected 'auto' or a positive frequency [Hz], got {self.cutoff!r}")
        if isinstance(self.filter_order, bool) or not isinstance(self.filter_order, int) or not 1 <= self.filter_order <= 8:
            raise DataValidationError("filter_order", f"expected an integer in 1..8, got {self.filter_order!r}")
        if self.form not in ("free", "stable", "monotone"):
            raise DataValidationError("form", f"expected 'free', 'stable' or 'monotone', got {self.form!r}")
        for name in ("max_nfev", "refine_samples"):
            val = getattr(self, name)
            if isinstance(val, bool) or not isinstance(val, int) or val < 1:
                raise DataValidationError(name, f"expected a positive integer, got {val!r}")
        for name in ("offset", "stable_only", "refine"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise DataValidationError(name, f"expected True or False, got {getattr(self, name)!r}")

    def _regressors(self, e: Experiment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Filtered force (target), input and the five regressor signals of one record, trimmed."""
        i = e.electrical(self.input)
        if self.cutoff is None:
            dF = np.gradient(e.F, e.dt)
            ddF = np.gradient(dF, e.dt)
            sl = slice(2, e.n - 2)
            F = e.F[sl]
            cols = np.stack([e.v[sl], dF[sl], ddF[sl], F**3, F**5], axis=1)
            return F, np.asarray(i[sl]), cols
        fc = float(_cutoff(self.cutoff, e.fs) or 0.0)
        if not fc < 0.5 * e.fs:
            raise DataValidationError(
                "cutoff", f"{fc:g} Hz is not below the Nyquist frequency {0.5 * e.fs:g} Hz of record {e.name!r}"
            )
        trim = math.ceil(3.0 * e.fs / fc)
        if e.n <= 2 * trim + 3 * self.filter_order:
            return np.empty(0), np.empty(0), np.empty((0, 5))
        sos = butter(self.filter_order, fc, btype="low", fs=e.fs, output="sos")
        Ff = sosfiltfilt(sos, e.F)
        vf = sosfiltfilt(sos, e.v)
        dF = np.gradient(Ff, e.dt)
        ddF = np.gradient(dF, e.dt)
        sl = slice(trim, e.n - trim)
        F = Ff[sl]
        cols = np.stack([vf[sl], dF[sl], ddF[sl], F**3, F**5], axis=1)
        return F, np.asarray(i[sl]), cols


def _cutoff(setting: float | str | None, fs: float) -> float | None:
    if setting is None:
        return None
    return float(min(fs / 10.0, 100.0)) if setting == "auto" else float(setting)


def _check_levels(i: np.ndarray, lo: float, hi: float, source: str) -> None:
    """Quadratics in the input need at least three distinct input levels."""
    if hi - lo <= 1e-9 * max(1.0, abs(hi)):
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels, but the training input is constant ({lo:g}); rank 1 of 3"
        )
    s = (i - lo) / (hi - lo)
    V = np.stack([np.ones_like(s), s, s * s], axis=1)
    sv = np.linalg.svd(V / np.linalg.norm(V, axis=0), compute_uv=False)
    rank = int(np.sum(sv > sv[0] * 1e-6))
    if rank < 3:
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels; the training input has numerical rank {rank} of 3"
        )


def _coef_map(lo: float, hi: float) -> np.ndarray:
    """Linear map (15 x 15) from Bernstein coefficients on ``s = (i - lo) / (hi - lo)`` (row-major
    5 x 3) to the monomial coefficients ``W`` in ``i``."""
    R = hi - lo
    # Bernstein (b0, b1, b2) -> power basis in s (a0, a1, a2) -> power basis in i
    to_s = np.array([[1.0, 0.0, 0.0], [-2.0, 2.0, 0.0], [1.0, -2.0, 1.0]])
    to_i = np.array([[1.0, -lo / R, lo**2 / R**2], [0.0, 1.0 / R, -2 * lo / R**2], [0.0, 0.0, 1.0 / R**2]])
    return np.kron(np.eye(5), to_i @ to_s)


def _form_bounds(form: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the scaled Bernstein coefficients that impose the sign constraints of ``form``."""
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    if form != "free":
        ub[3:6] = -1e-9  # w2 Bernstein coefficients < 0
        ub[6:9] = -1e-9  # w3 < 0
        ub[12:15] = 0.0  # w5 <= 0
    if form == "monotone":
        ub[9:12] = 0.0  # w4 <= 0: g(F) increasing, no bistable branch
    return lb, ub


def _max_step(W: np.ndarray, lo: float, hi: float, exps: Iterable[Experiment]) -> float:
    """Step [s] keeping ``h |lambda| <= 0.5`` for the linearised ODE over input range and force span."""
    Fmin = min(float(np.min(e.F)) for e in exps)
    Fmax = max(float(np.max(e.F)) for e in exps)
    ii = np.linspace(lo, hi, 11)[:, None]
    FF = np.linspace(Fmin, Fmax, 41)[None, :]
    w = [W[j, 0] + W[j, 1] * ii + W[j, 2] * ii**2 for j in range(5)]
    with np.errstate(divide="ignore", invalid="ignore"):
        b = w[1] / w[2]  # lambda^2 + b lambda - gp / w3 = 0
        gp = 1.0 - 3.0 * w[3] * FF**2 - 5.0 * w[4] * FF**4
        c = -gp / w[2]
        disc = np.sqrt((b * b - 4 * c).astype(complex))
        lam = np.maximum(np.abs((-b + disc) / 2), np.abs((-b - disc) / 2))
    lmax = float(np.nanmax(lam)) if np.any(np.isfinite(lam)) else math.inf
    return 0.5 / lmax if lmax > 0 else math.inf


def _refine(
    theta0: np.ndarray, scale: np.ndarray, M: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
    exps: Iterable[Experiment], est: P15Estimator, bound: float, lo: float, hi: float,
) -> tuple[np.ndarray, dict[str, Any]]:
    """Output-error refinement: least squares on the free-run simulation error of every training
    record, Jacobian from forward sensitivities, same sign bounds as the equation-error fit."""
    recs = list(exps)
    n_total = sum(e.n for e in recs)
    stride = max(1, math.ceil(n_total / est.refine_samples))
    idx = [np.arange(0, e.n, stride) for e in recs]
    states = [initial_state(e) for e in recs]
    Fs = float(np.std(np.concatenate([e.F for e in recs]))) or 1.0
    n_par = theta0.size
    lb, ub = bounds
    x0 = np.clip(theta0, lb, ub)

    def substeps(theta: np.ndarray) -> list[int]:
        W = np.einsum("jk,k->j", M, theta[:15] * scale[:15]).reshape(5, 3)
        ms = _max_step(W, lo, hi, recs)
        return [int(min(MAX_SUBSTEPS, max(1, math.ceil(e.dt / ms)))) if math.isfinite(ms) else 1 for e in recs]

    # Sub-steps are fixed at max(8, twice the starting model's need): a step into a stiffer region
    # (h |lambda| > 0.5 at that step) counts as divergence, which bounds the cost of each
    # evaluation and keeps the integration accurate.
    budget = [min(MAX_SUBSTEPS, max(8, 2 * n)) for n in substeps(x0)]

    def run(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        W = np.einsum("jk,k->j", M, theta[:15] * scale[:15]).reshape(5, 3)
        f0 = float(theta[15] * scale[15]) if est.offset else 0.0
        need = substeps(theta)
        res, jac = [], []
        for e, k, (F0, G0), n_sub, nb in zip(recs, idx, states, need, budget):
            if n_sub > nb:
                res.append(np.full(k.size, bound / Fs))
                jac.append(np.zeros((k.size, n_par)))
                continue
            n_sub = nb
            i = np.ascontiguousarray(e.electrical(est.input))
            F, J, bad = p15_sensitivities(np.ascontiguousarray(e.v), i, e.dt, W, f0, F0, G0, n_sub, bound,
                                          bool(est.offset))
            if bad >= 0:  # diverged: a large, finite residual so the solver rejects the step
                F[bad:] = bound
                J[bad:] = 0.0
            res.append((F[k] - e.F[k]) / Fs)
            Jt = np.empty((k.size, n_par))
            Jt[:, :15] = (J[k, :15] @ M) * scale[:15]
            if est.offset:
                Jt[:, 15] = J[k, 15] * scale[15]
            jac.append(Jt / Fs)
        return np.concatenate(res), np.concatenate(jac)

    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def cached(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = theta.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = run(theta)
        return cache[key]

    r0 = cached(x0)[0]
    sol = least_squares(lambda th: cached(th)[0], x0, jac=lambda th: cached(th)[1], bounds=(lb, ub),
                        method="trf", x_scale="jac", max_nfev=est.max_nfev)
    info = {
        "rms_before": float(np.sqrt(np.mean(r0**2)) * Fs),
        "rms_after": float(np.sqrt(2 * sol.cost / sol.fun.size) * Fs),
        "nfev": int(sol.nfev),
        "status": int(sol.status),
        "sample_stride": int(stride),
    }
    if not info["rms_after"] <= info["rms_before"]:
        return x0, {**info, "kept": "equation-error fit"}
    return sol.x, info


def _simulate_training(model: P15Model, exps: Iterable[Experiment]) -> tuple[dict[str, Any], dict[str, float]]:
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


register(P15Estimator, P15Model)
