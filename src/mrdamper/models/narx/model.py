"""Polynomial NARX damper model: a black-box peer of the paper's models (kind ``"narx"``).

Model, at its own sampling rate ``fs`` and in scaled units (``f = F / F_s``, ``x / x_s``,
``v / v_s``, ``e / e_s`` with ``e`` the electrical input, plus ``w = tanh(v / v0)``)::

    f[k] = sum_t theta_t * phi_t[k]

where each regressor ``phi_t`` is a monomial of total degree <= ``degree`` (the constant
included) in the base variables ``f[k-1..k-n_a]`` and ``x, v, e, w`` at lags ``0..n_b``; at most
``output_degree`` of its factors are past forces (``1``: the force enters affinely, which keeps
the free run far better behaved than powers of the fed-back force).

Identification (:class:`NARXEstimator`):

1. Equation error, term selection: every candidate monomial is evaluated on the measured signals of
   each record (records stay separate; each record's squared errors are weighted by
   ``1 / (N var(F))`` so records count equally, as in the mean ESR). Forward orthogonal least
   squares with the error reduction ratio (OLS-ERR, Billings' forward regression) picks the terms
   one at a time, each time the candidate whose part orthogonal to the terms already chosen explains
   the most of the force, until ``n_terms`` terms or until the unexplained fraction falls below
   ``err_tol``. The selection runs on the column-normalised Gram matrix, so the candidate matrix is
   never held in memory; near-collinear candidates are skipped.
2. Equation error, coefficients: linear least squares on the chosen columns (SVD), with a
   condition-number check (:class:`~mrdamper.errors.IdentificationError` above ``cond_max``).
3. Optional output-error refinement (``refine=True``): the coefficients of the chosen terms are
   refined by minimising the weighted free-run (simulation) error of every training record with a
   trust-region least-squares solver and exact sensitivities from the kernel. The refined
   coefficients are kept only if they lower the free-run training cost.

Free run: the first ``p = max(n_a, n_b)`` samples of a record's force (at the model rate) are the
initial conditions; from sample ``p`` on the measured force is never used. A record at another
rate is resampled to ``fs`` on the way in and the prediction interpolated back.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from dataclasses import InitVar, dataclass
from typing import Any, ClassVar, Literal, cast

import numpy as np

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource, require_experiment
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _scale
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
    check_number,
)
from mrdamper.models.narx import kernels as K
from mrdamper.models.narx.fit import free_run_cost, least_squares_terms, refine, select_terms
from mrdamper.models.rates import (
    MODEL_FS_REASON,
    model_rate,
    rename_setting,
    to_model_rate,
    to_record_rate,
)
from mrdamper.models.step import Step
from mrdamper.progress import report

__all__ = ["NARXEstimator", "NARXModel", "candidate_structure"]

#: Signal rows of the kernels' ``S`` array (``e`` is the model's electrical input).
SIGNALS: tuple[str, ...] = ("F", "x", "v", "e", "tanh_v")
#: Default budget of the output-error refinement (residual evaluations).
_DEFAULT_MAX_NFEV = 40
_NFEV_REASON = "the same name as every other estimator's iteration budget"


# ----------------------------------------------------------------------------- structure
def _int_setting(name: str, value: Any, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise DataValidationError(name, f"expected an integer >= {lo}, got {value!r}")
    return int(value)


def candidate_structure(
    n_a: int, n_b: int, degree: int, output_degree: int = 1, use_tanh: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Base variables and every candidate monomial of a polynomial NARX model.

    Parameters
    ----------
    n_a : int
        Number of past forces ``F[k-1..k-n_a]`` (>= 1).
    n_b : int
        Largest input lag: x, v, e (and tanh(v / v0)) enter at lags ``0..n_b``.
    degree : int
        Largest total degree of a monomial (>= 1).
    output_degree : int
        Largest number of past-force factors in a monomial (>= 1).
    use_tanh : bool
        Include ``tanh(v / v0)`` at lags ``0..n_b`` among the base variables.

    Returns
    -------
    base : ndarray of int64, shape (n_base, 2)
        ``(signal row, lag)`` of every base variable (rows index :data:`SIGNALS`).
    slots : ndarray of int64, shape (n_candidates, degree)
        Base-variable indices of every monomial, ``-1`` for an empty slot; row 0 is the constant.
    """
    n_a = _int_setting("n_a", n_a, 1)
    n_b = _int_setting("n_b", n_b, 0)
    degree = _int_setting("degree", degree, 1)
    output_degree = _int_setting("output_degree", output_degree, 1)
    base = [(0, lag) for lag in range(1, n_a + 1)]
    for sig in (1, 2, 3, 4) if use_tanh else (1, 2, 3):
        base += [(sig, lag) for lag in range(n_b + 1)]
    slots = []
    for d in range(degree + 1):
        for combo in itertools.combinations_with_replacement(range(len(base)), d):
            if sum(1 for j in combo if base[j][0] == 0) <= output_degree:
                slots.append(list(combo) + [-1] * (degree - d))
    return np.array(base, dtype=np.int64), np.array(slots, dtype=np.int64).reshape(-1, degree)


# ----------------------------------------------------------------------------- fitted model
@dataclass(frozen=True, kw_only=True, eq=False)
class NARXModel(FittedModel):
    """Identified polynomial NARX damper model (immutable).

    Parameters
    ----------
    fs : float
        Sampling rate the discrete model runs at [Hz].
    base : ndarray of int, shape (n_base, 2)
        Base variables as ``(signal row, lag)``; signal rows index
        ``("F", "x", "v", "e", "tanh_v")``, lags in samples at ``fs``.
    terms : ndarray of int, shape (n_terms, degree)
        Base-variable indices of each selected monomial, ``-1`` for an empty slot.
    theta : ndarray of float, shape (n_terms,)
        Coefficients in scaled units (see :meth:`coefficients` for SI units).
    scales : ndarray of float, shape (5,)
        Scale of each signal row: F [N], x [m], v [m/s], e [A] or [V], tanh_v [-] (1).
    v0 : float
        Velocity of the ``tanh(v / v0)`` feature [m/s].
    force_bound : float
        Free-run force magnitude regarded as divergence [N].
    x_limits : (float, float)
        Displacement range [m] the ``x`` regressors are clipped to (``(-inf, inf)``: none).
    v_limit : float
        Velocity magnitude [m/s] the ``v`` and ``tanh(v / v0)`` regressors are clipped to
        (``inf``: none). The estimator sets both to the training envelope
        (``extrapolation="clip"``): a polynomial fed values it never saw can burst.

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.data import Experiment
    >>> t = np.arange(200) * 1e-3
    >>> v = 0.1 * np.sin(2 * np.pi * 5 * t)
    >>> e = Experiment(t=t, x=0 * t, v=v, F=0 * t, i=0 * t + 0.5, name="demo")
    >>> m = NARXModel(fs=1000.0, base=[[0, 1], [2, 0]], terms=[[0], [1]], theta=[0.5, 1.0],
    ...               scales=[1000.0, 1.0, 0.1, 1.0, 1.0], v0=0.01, input_range=(0, 1))
    >>> m.term_names
    ['F[k-1]', 'v[k]']
    >>> F = m.predict(e)  # F[k] = 0.5 F[k-1] + 1000 N / (0.1 m/s) * v[k]
    >>> bool(np.isclose(F[10], 0.5 * F[9] + 1e4 * v[10]))
    True
    """

    kind: ClassVar[str] = "narx"

    fs: float
    base: np.ndarray
    terms: np.ndarray
    theta: np.ndarray
    scales: np.ndarray
    v0: float = 1.0
    force_bound: float = 1e9
    x_limits: tuple[float, float] = (-math.inf, math.inf)
    v_limit: float = math.inf

    def __post_init__(self) -> None:
        super().__post_init__()
        set_ = object.__setattr__
        lim = tuple(float(b) for b in self.x_limits)
        if len(lim) != 2 or any(math.isnan(b) for b in lim) or not lim[0] <= lim[1]:
            raise DataValidationError(
                "x_limits", f"expected (low, high) with low <= high, got {self.x_limits!r}"
            )
        set_(self, "x_limits", lim)
        if isinstance(self.v_limit, bool) or not float(self.v_limit) > 0:
            raise DataValidationError(
                "v_limit", f"expected a positive velocity [m/s] or inf, got {self.v_limit!r}"
            )
        set_(self, "v_limit", float(self.v_limit))
        base = np.array(self.base, dtype=np.int64).reshape(-1, 2)
        terms = np.array(self.terms, dtype=np.int64)
        theta = np.array(self.theta, dtype=np.float64)
        scales = np.array(self.scales, dtype=np.float64)
        if terms.ndim != 2 or terms.shape[0] == 0:
            raise DataValidationError(
                "terms", f"expected a 2-D (n_terms, degree) array, got shape {terms.shape}"
            )
        if theta.shape != (terms.shape[0],):
            raise DataValidationError(
                "theta", f"expected shape ({terms.shape[0]},) to match terms, got {theta.shape}"
            )
        if (
            scales.shape != (len(SIGNALS),)
            or not np.all(np.isfinite(scales))
            or np.any(scales <= 0)
        ):
            raise DataValidationError(
                "scales", f"expected {len(SIGNALS)} positive finite scales, got {scales.tolist()}"
            )
        if not np.all(np.isfinite(theta)):
            raise DataValidationError("theta", "expected finite coefficients")
        if base.size and (
            np.any(base[:, 0] < 0) or np.any(base[:, 0] >= len(SIGNALS)) or np.any(base[:, 1] < 0)
        ):
            raise DataValidationError(
                "base",
                f"expected (signal 0..{len(SIGNALS) - 1}, lag >= 0) rows, got {base.tolist()}",
            )
        if base.size and np.any((base[:, 0] == 0) & (base[:, 1] < 1)):
            raise DataValidationError(
                "base", "past forces need a lag >= 1 (F[k] cannot explain itself)"
            )
        if np.any(terms < -1) or np.any(terms >= base.shape[0]):
            raise DataValidationError(
                "terms", f"expected indices -1..{base.shape[0] - 1}, got {terms.tolist()}"
            )
        for name in ("fs", "v0", "force_bound"):
            val = getattr(self, name)
            if (
                isinstance(val, bool)
                or not isinstance(val, (int, float, np.integer, np.floating))
                or not float(val) > 0
                or not math.isfinite(float(val))
            ):
                raise DataValidationError(name, f"expected a positive finite number, got {val!r}")
            set_(self, name, float(val))
        if self.input not in ("i", "voltage"):
            raise DataValidationError("input", f"expected 'i' or 'voltage', got {self.input!r}")
        for name, arr in (("base", base), ("terms", terms), ("theta", theta), ("scales", scales)):
            arr.setflags(write=False)
            set_(self, name, arr)

    def __eq__(self, other: object) -> bool:
        """Equal when every field except provenance is equal (arrays compared element-wise)."""
        if type(other) is not type(self):
            return NotImplemented
        for f in dataclasses.fields(self):
            if f.name == "provenance":
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray):
                if a.dtype != b.dtype or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    # --- structure -----------------------------------------------------------------------
    @property
    def max_lag(self) -> int:
        """Number of initial samples ``p`` (largest lag, at least 1) at the model rate."""
        return max(1, int(self.base[:, 1].max()) if self.base.size else 1)

    def _base_name(self, j: int) -> str:
        sig, lag = int(self.base[j, 0]), int(self.base[j, 1])
        name = self.input if sig == 3 else SIGNALS[sig]
        return f"{name}[k-{lag}]" if lag else f"{name}[k]"

    @property
    def term_names(self) -> list[str]:
        """Readable names of the selected monomials (``"1"`` for the constant)."""
        return [
            "*".join(self._base_name(int(j)) for j in row if j >= 0) or "1" for row in self.terms
        ]

    def coefficients(self) -> dict[str, float]:
        """Coefficient of each monomial in SI units (force [N] from unscaled signals)."""
        out = {}
        for name, row, th in zip(self.term_names, self.terms, self.theta, strict=True):
            denom = 1.0
            for j in row:
                if j >= 0:
                    denom *= self.scales[self.base[j, 0]]
            out[name] = float(th * self.scales[0] / denom)
        return out

    # --- signals -------------------------------------------------------------------------
    def scaled_signals(self, experiment: Experiment) -> np.ndarray:
        """Scaled signal rows ``(F, x, v, e, tanh_v)`` at the model rate, shape (5, N)."""
        require_experiment(experiment)
        e = self.electrical_input(experiment)
        rows = [
            to_model_rate(np.asarray(a, dtype=np.float64), experiment.fs, self.fs)
            for a in (experiment.F, experiment.x, experiment.v, e)
        ]
        rows[1] = np.clip(rows[1], *self.x_limits)
        rows[2] = np.clip(rows[2], -self.v_limit, self.v_limit)
        rows.append(np.tanh(rows[2] / self.v0))
        S = np.vstack(rows)
        S /= self.scales[:, None]
        if S.shape[1] <= self.max_lag:
            raise DataValidationError(
                "F",
                f"record {experiment.name!r} has {S.shape[1]} samples at {self.fs:g} Hz; "
                f"expected more than the {self.max_lag} initial-condition samples",
            )
        return np.ascontiguousarray(S)

    def _back(self, f: np.ndarray, experiment: Experiment) -> np.ndarray:
        return to_record_rate(f * self.scales[0], self.fs, experiment)

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] from rest: the first ``max_lag`` forces are 0 N, as in the
        per-sample step (:meth:`step` with ``f_initial = 0``); the measured force is never read.

        Raises
        ------
        SimulationDivergedError
            If the force becomes non-finite or exceeds ``force_bound`` (sample at the model rate).
        DataValidationError
            If the record lacks the model's electrical input or is too short.
        """
        S = self.scaled_signals(experiment)
        S[0, : self.max_lag] = 0.0  # from rest, as the step
        bound = self.force_bound / self.scales[0]
        bad = K.free_run(S, self.base, self.terms, self.theta, self.max_lag, bound)
        if bad >= 0:
            raise SimulationDivergedError(
                self.kind,
                int(bad),
                f"|F| exceeded {self.force_bound:.3g} N or became non-finite in record "
                f"{experiment.name!r} (model rate {self.fs:g} Hz)",
            )
        return self._back(S[0], experiment)

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5, f_initial: float = 0.0) -> Step:
        """The model as a per-sample step at its own rate ``fs`` (:mod:`mrdamper.models.step`).

        The state holds the last :attr:`max_lag` scaled samples of every signal; the first
        ``max_lag`` forces are the initial conditions, ``f_initial`` [N] (0 N, from rest, is the
        free run of :meth:`predict`). The input is used as given (no range
        policy).

        Parameters
        ----------
        dt, vmax : float
            Interval [s] and largest velocity [m/s] the step will see; unused by this family
            (the common signature of :meth:`~mrdamper.models.FittedModel.step`).
        f_initial : float
            Force [N] of the first ``max_lag`` samples (default 0: from rest).
        """
        check_number("f_initial", f_initial, low=-math.inf, what="a finite force [N]")
        p = self.max_lag
        form = K.NARXForm(
            np.ascontiguousarray(self.base),
            np.ascontiguousarray(self.terms),
            np.ascontiguousarray(self.theta),
            np.ascontiguousarray(self.scales),
            self.v0,
            self.force_bound / float(self.scales[0]),
            p,
            float(f_initial),
            self.x_limits[0],
            self.x_limits[1],
            self.v_limit,
        )
        size = 1 + len(SIGNALS) * p

        def initial_state(x0: float, v0: float, e0: float) -> np.ndarray:
            return np.zeros(size)

        feed = bool(np.any((self.base[:, 0] == 3) & (self.base[:, 1] == 0)))
        return Step(
            self.kind,
            form,
            K.step_force,
            K.step_advance,
            initial_state,
            dt=1.0 / self.fs,
            feedthrough=feed,
        )

    def one_step_predict(self, experiment: Experiment) -> np.ndarray:
        """One-step-ahead force [N]: past forces are the measured ones (equation error view)."""
        S = self.scaled_signals(experiment)
        p = self.max_lag
        Phi = np.empty((S.shape[1] - p, self.terms.shape[0]))
        K.fill_candidates(S, self.base, self.terms, p, S.shape[1], Phi)
        f = S[0].copy()
        f[p:] = Phi @ self.theta
        return self._back(f, experiment)


# ----------------------------------------------------------------------------- estimator
@dataclass
class NARXEstimator(Estimator):
    """Identify a :class:`NARXModel` (settings only; see the module docstring for the method).

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel.
    n_a : int
        Number of past forces.
    n_b : int
        Largest lag of x, v, e and tanh(v / v0) (present value included).
    degree : int
        Largest total degree of a monomial.
    output_degree : int
        Largest number of past-force factors in a monomial.
    use_tanh : bool
        Add ``tanh(v / v0)`` features.
    v0 : float or None
        Velocity of the tanh feature [m/s]; None: 5 % of the largest training |v|.
    n_terms : int
        Largest number of selected terms.
    err_tol : float
        Stop selecting when the unexplained (one-step) fraction of the force falls below it [-].
    colin_tol : float
        Candidates whose part orthogonal to the chosen terms keeps less than this fraction of
        their squared norm are skipped [-].
    refine : bool
        Refine the coefficients on the free-run (output) error of the training records.
    max_nfev : int
        Budget of residual evaluations of the refinement (``refine_max_nfev`` is its old name,
        still accepted with a note).
    model_fs : float or None
        Model rate [Hz]; None: the lowest training record rate (with a note when the records'
        rates differ). ``fs`` is its old name, still accepted.
    cond_max : float
        Largest accepted condition number of the chosen (normalised) regression matrix [-].
    bound_factor : float
        Free-run divergence bound as a multiple of the largest training |F| [-].
    extrapolation : {"clip", "free"}
        ``"clip"`` (default): the fitted model clips its displacement and velocity regressors to
        the training range (``x_limits``, ``v_limit``), so a motion beyond the training envelope
        meets the polynomial only where it was identified (the force stays bounded; beyond the
        envelope it follows the edge of the training data). ``"free"``: no clipping (the
        polynomial extrapolates and can burst).
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    """

    kind: ClassVar[str] = "narx"
    model_class: ClassVar[type[FittedModel]] = NARXModel

    input: ElectricalSource = "i"
    n_a: int = 2
    n_b: int = 1
    degree: int = 3
    output_degree: int = 1
    use_tanh: bool = True
    v0: float | None = None
    n_terms: int = 12
    err_tol: float = 1e-10
    colin_tol: float = 1e-8
    refine: bool = True
    max_nfev: int = _DEFAULT_MAX_NFEV
    model_fs: float | None = None
    cond_max: float = 1e8
    bound_factor: float = 10.0
    extrapolation: Literal["clip", "free"] = "clip"
    range_policy: RangePolicy = "error"
    fs: InitVar[float | None] = None
    refine_max_nfev: InitVar[int | None] = None

    renamed_settings: ClassVar[Mapping[str, str]] = {
        "fs": "model_fs",
        "refine_max_nfev": "max_nfev",
    }

    def __post_init__(self, fs: float | None, refine_max_nfev: int | None) -> None:
        self.model_fs = cast(
            "float | None",
            rename_setting(self.kind, "fs", "model_fs", fs, self.model_fs, MODEL_FS_REASON),
        )
        given = None if self.max_nfev == _DEFAULT_MAX_NFEV else self.max_nfev
        renamed = rename_setting(
            self.kind, "refine_max_nfev", "max_nfev", refine_max_nfev, given, _NFEV_REASON
        )
        if renamed is not None:
            self.max_nfev = cast(int, renamed)

    def _validate(self) -> None:
        super()._validate()
        check_int("n_terms", self.n_terms, 1)
        check_int("max_nfev", self.max_nfev, 1)
        for name in ("err_tol", "colin_tol"):
            check_number(
                name, getattr(self, name), strict=False, high=1.0, what="a number in [0, 1)"
            )
        for name in ("v0", "model_fs"):
            check_number(name, getattr(self, name), allow_none=True)
        check_number("cond_max", self.cond_max)
        check_number("bound_factor", self.bound_factor, low=1.0, what="a finite number > 1")

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Term selection, least squares and optional output-error refinement (module docstring).

        Raises
        ------
        DataValidationError
            A constant-force or too-short record.
        IdentificationError
            Fewer equations than candidates, nothing selectable, or ill-conditioned regression.
        """
        exps = data.records
        base, cand = candidate_structure(
            self.n_a, self.n_b, self.degree, self.output_degree, self.use_tanh
        )
        fs = model_rate([e.fs for e in exps], self.model_fs, self.kind, self.min_model_fs)
        v_max = max(float(np.max(np.abs(e.v))) for e in exps)
        v0 = float(self.v0) if self.v0 is not None else 0.05 * v_max
        F_max = max(float(np.max(np.abs(e.F))) for e in exps)
        raw = (
            [F_max]
            + [
                max(
                    float(np.max(np.abs(getattr(e, c) if c != "e" else el)))
                    for e, el in zip(exps, data.electrical)
                )
                for c in ("x", "v", "e")
            ]
            + [1.0]
        )
        scales = np.array([s if s > 0 else 1.0 for s in raw])
        probe = NARXModel(
            fs=fs,
            base=base,
            terms=cand[:1],
            theta=np.zeros(1),
            scales=scales,
            v0=v0,
            force_bound=self.bound_factor * max(F_max, 1e-300),
            input=self.input,
            input_range=data.input_range,
            range_policy="ignore",
        )
        p = probe.max_lag
        records, weights = [], []
        lazy = (
            sum(e.n for e in exps) > _scale.WINDOW_THRESHOLD
        )  # long campaigns: one record at a time
        n_eq = 0
        for e in exps:
            S = probe.scaled_signals(e)
            sd = float(np.std(S[0, p:]))
            if sd == 0.0:
                raise DataValidationError(
                    "F", f"record {e.name!r} has constant force; expected a moving damper"
                )
            records.append(S)
            weights.append(1.0 / (sd * sd * (S.shape[1] - p)))
            n_eq += S.shape[1] - p
            if lazy:
                records[-1] = np.empty((0, 0))
        if lazy:
            records = _scale.LazyRecords(probe.scaled_signals, exps)  # type: ignore[assignment]
        if n_eq <= cand.shape[0]:
            raise IdentificationError(
                f"narx: {n_eq} equations for {cand.shape[0]} candidate terms; expected more "
                "samples (longer records) or a smaller structure (n_a, n_b, degree)"
            )
        # long campaigns: the output-error refinement runs on evenly spread windows (term selection
        # on windows was tried: its least-squares model diverged in free run on a 1 h record)
        fit_recs, fit_w, windows = _scale.narx_windows(records, weights, fs, p)
        order, err = select_terms(
            records, weights, base, cand, p, self.n_terms, self.err_tol, self.colin_tol
        )
        terms = cand[order]
        report("least squares of the selected terms")
        theta, cond = least_squares_terms(records, weights, base, terms, p, self.cond_max)
        model = dataclasses.replace(probe, terms=terms, theta=theta)
        if self.extrapolation == "clip":
            x_lo = min(float(np.min(e.x)) for e in exps)
            x_hi = max(float(np.max(e.x)) for e in exps)
            model = dataclasses.replace(model, x_limits=(x_lo, x_hi), v_limit=v_max)
        bound = model.force_bound / model.scales[0]
        report("free run of the least-squares model")
        cost_ls = free_run_cost(base, terms, theta, bound, records, weights, p)
        cost, nfev, refined = cost_ls, 0, False
        if self.refine:
            theta_r, cost_r, nfev = refine(
                base, terms, theta, bound, list(fit_recs), fit_w, p, self.max_nfev
            )
            if windows is not None:  # full-data check of the refined coefficients
                report("full-data check")
                cost_r = free_run_cost(base, terms, theta_r, bound, records, weights, p)
            if cost_r < cost_ls:
                model = dataclasses.replace(model, theta=theta_r)
                cost, refined = cost_r, True
        prov: dict[str, Any] = {
            "method": "OLS-ERR forward selection + least squares"
            + (" + output-error refinement" if refined else ""),
            "records": [e.name for e in exps],
            "n_equations": int(n_eq),
            "n_candidates": int(cand.shape[0]),
            "settings": {
                "n_a": self.n_a,
                "n_b": self.n_b,
                "degree": self.degree,
                "output_degree": self.output_degree,
                "use_tanh": self.use_tanh,
                "n_terms": self.n_terms,
                "refine": self.refine,
                "extrapolation": self.extrapolation,
            },
            "err": [float(x) for x in err],
            "err_total": float(np.sum(err)),
            "cond": float(cond),
            "free_run_cost_ls": float(cost_ls),
            "free_run_cost": float(cost),
            "refined": refined,
            "refine_nfev": int(nfev),
        }
        if windows is not None:
            prov["refine_windows"] = windows
            prov["full_data_check"] = {
                "free_run_cost_ls": float(cost_ls),
                "free_run_cost": float(cost),
            }
        return Identified(parameters=model.parameters, provenance=prov)
