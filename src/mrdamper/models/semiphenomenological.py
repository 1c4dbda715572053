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
force error, with the analytic Jacobian of :mod:`mrdamper.models._sp_kernels`:

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
   sign function whose Jacobian vanishes). Everything else is free.

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

import warnings
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from typing import Any, ClassVar, cast

import numpy as np
from scipy.optimize import least_squares

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError
from mrdamper.models import _scale
from mrdamper.models._lpv_kernels import first_order_lag
from mrdamper.models._sp_kernels import N_COMPONENTS, sp_force, sp_force_jacobian
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
    check_number,
)
from mrdamper.models.registry import register

__all__ = [
    "SP1Estimator",
    "SP1Model",
    "SP2Estimator",
    "SP2Model",
    "SP3Estimator",
    "SP3Model",
    "SP4Estimator",
    "SP4Model",
]

#: Names of the five components of the SP map, in kernel order.
COMPONENTS = ("A", "a", "b", "c", "d")
#: Upper bound of the normalised tanh velocity coefficient (see module docstring).
_TANH_SLOPE_MAX = 1e3
#: Largest accepted condition number of an input-power matrix (identifiability check).
_MAX_INPUT_COND = 1e6
#: Samples required per coefficient.
_SAMPLES_PER_PARAMETER = 10


# ============================================================================ fitted models
@dataclass(frozen=True)
class _SPModel(FittedModel):
    """Common behaviour of the SP-k fitted models (abstract; use SP1Model ... SP4Model).

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
            ``A`` [N], ``a`` [s/m], ``b`` [1/m], ``c`` [N s/m], ``d`` [N/m] as arrays shaped like ``i``.
        """
        ii = np.asarray(i, dtype=float)
        out = {name: np.zeros_like(ii) for name in COMPONENTS}
        for s, (m, p) in zip(self.S, self.LAYOUT):
            out[COMPONENTS[m]] = out[COMPONENTS[m]] + s * ii**p
        return out

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

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N]: direct evaluation on the record's x, v and electrical input
        (through the drive lag when ``eta`` is set; the range policy applies to the input)."""
        i = self.electrical_input(experiment)
        if self.eta is not None:
            i = first_order_lag(np.ascontiguousarray(i, dtype=np.float64), experiment.dt, self.eta)
        return self.force(experiment.x, experiment.v, i)


@dataclass(frozen=True)
class SP1Model(_SPModel):
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
class SP2Model(_SPModel):
    """SP-2: ``F = S1 i tanh(S2 v + S3 x) + S4 v + S5 x + f0``.

    ``S = (S1 [N/A], S2 [s/m], S3 [1/m], S4 [N s/m], S5 [N/m])`` (per V with ``input="voltage"``).
    """

    kind: ClassVar[str] = "sp2"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = ((0, 1), (1, 0), (2, 0), (3, 0), (4, 0))


@dataclass(frozen=True)
class SP3Model(_SPModel):
    """SP-3: ``F = (S1 i + S2) tanh(S3 v + S4 x) + S5 v + S6 x + f0``.

    ``S = (S1 [N/A], S2 [N], S3 [s/m], S4 [1/m], S5 [N s/m], S6 [N/m])``.
    """

    kind: ClassVar[str] = "sp3"
    LAYOUT: ClassVar[tuple[tuple[int, int], ...]] = ((0, 1), (0, 0), (1, 0), (2, 0), (3, 0), (4, 0))


@dataclass(frozen=True)
class SP4Model(_SPModel):
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
    eta : float or None
        Drive-lag rate [1/s]: the map is fitted to the electrical input passed through the lag
        (per record, see the module docstring); ``None`` (default): no lag.
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
    eta: float | None = None

    range_policy: RangePolicy = "error"

    model_class: ClassVar[type[FittedModel]] = _SPModel

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Multi-start nonlinear least squares of the map (see the module docstring).

        Raises
        ------
        IdentificationError
            Too few samples, an input that does not vary enough to identify the current
            dependence, a force without variance, or no start converged to a finite cost.
        """
        exps = data.records
        cls = cast(type[_SPModel], self.model_class)
        comp_all, power_all = cls.layout_arrays()
        x, v, i, F = _stack(
            exps, self.input, self.eta, _scale.WINDOW_THRESHOLD
        )  # long campaigns: an even subset
        # one level: every component's polynomial in the input reduces to its constant term
        keep = (
            _single_level_terms(comp_all, power_all)
            if data.single
            else np.ones(comp_all.size, bool)
        )
        comp, power = comp_all[keep], power_all[keep]
        n_par = comp.size + int(self.offset)
        if F.size < _SAMPLES_PER_PARAMETER * n_par:
            raise IdentificationError(
                f"data: {cls.kind} has {n_par} parameters and needs at least "
                f"{_SAMPLES_PER_PARAMETER * n_par} samples, got {F.size}"
            )
        Fs = float(np.std(F))
        if not Fs > 0:
            raise IdentificationError("F: training force has zero variance; nothing to identify")
        xs, vs = _rms(x), _rms(v)
        i_s = float(np.max(np.abs(i))) or 1.0
        xn, vn, inn, Fn = x / xs, v / vs, i / i_s, F / Fs
        sub = _even_subset(F.size, self.screen_samples)
        _check_identifiable(cls, comp, power, inn[sub], self.input)

        lb, ub = _bounds(comp, power, self.offset)
        rng = np.random.default_rng(self.seed)
        starts = _linear_starts(comp, power, xn[sub], vn[sub], inn[sub], Fn[sub], self, rng)

        def solve(theta0: np.ndarray, idx: np.ndarray | slice, nfev: int) -> Any:
            xa, va, ia, Fa = (np.ascontiguousarray(a[idx]) for a in (xn, vn, inn, Fn))

            def fun(th: np.ndarray) -> np.ndarray:
                f0 = th[-1] if self.offset else 0.0
                return sp_force(xa, va, ia, comp, power, th[: comp.size], f0) - Fa

            def jac(th: np.ndarray) -> np.ndarray:
                f0 = th[-1] if self.offset else 0.0
                return sp_force_jacobian(xa, va, ia, comp, power, th[: comp.size], f0, self.offset)[
                    1
                ]

            return least_squares(
                fun, theta0, jac=jac, bounds=(lb, ub), method="trf", x_scale="jac", max_nfev=nfev
            )

        results = []
        for theta0 in starts:
            try:
                res = solve(np.clip(theta0, lb, ub), sub, self.max_nfev)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
            if np.isfinite(res.cost) and np.all(np.isfinite(res.x)):
                results.append(res)
        if not results:
            raise IdentificationError(f"{cls.kind}: no start converged to a finite cost")
        best = min(results, key=lambda r: r.cost)
        full = _even_subset(F.size, self.fit_samples)
        final = solve(best.x, full, self.max_nfev)
        if not (np.isfinite(final.cost) and np.all(np.isfinite(final.x))):
            final = best
        if final.status == 0:
            warnings.warn(
                f"{cls.kind}: least squares stopped at max_nfev={self.max_nfev} before converging",
                RuntimeWarning,
                stacklevel=3,
            )
        S_kept, f0 = _to_physical(final.x, comp, power, self.offset, xs=xs, vs=vs, i_s=i_s, Fs=Fs)
        S = np.zeros(comp_all.size)
        S[keep] = S_kept
        rms = float(np.sqrt(2.0 * final.cost / final.fun.size) * Fs)
        provenance = {
            "estimator": type(self).__name__,
            "settings": asdict(self),
            "training_records": list(exps.names),
            "n_samples": int(sum(e.n for e in exps)),
            "n_samples_stacked": int(F.size),
            "n_screen_samples": int(sub.size),
            "n_fit_samples": int(full.size),
            "scales": {"x": xs, "v": vs, "input": i_s, "F": Fs},
            "start_costs": sorted(float(r.cost) for r in results),
            "nfev": int(final.nfev),
            "status": int(final.status),
            "message": str(final.message),
            "training_rms_error": rms,
            "training_esr": float(rms**2 / Fs**2),
        }
        return Identified(
            parameters={
                "S": tuple(S),
                "f0": f0,
                "eta": self.eta,
                "rho_range": None if self.eta is None else (float(np.min(i)), float(np.max(i))),
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
        check_number(
            "eta",
            self.eta,
            allow_none=True,
            what="a positive drive-lag rate [1/s] or None",
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


# ============================================================================ helpers
def _stack(
    exps: Iterable[Experiment],
    source: ElectricalSource,
    eta: float | None = None,
    max_samples: int | None = None,
) -> tuple[np.ndarray, ...]:
    """Concatenate the samples of all records (valid for a static map: no state crosses records);
    with ``eta`` the electrical input of each record goes through the drive lag first.

    With more than ``max_samples`` samples in all, only an evenly spaced subset of that many is
    gathered (record by record: the whole concatenation is never built).
    """
    cols: dict[str, list[np.ndarray]] = {"x": [], "v": [], "i": [], "F": []}
    exps = list(exps)
    total = sum(e.n for e in exps)
    keep = (
        _even_subset(total, max_samples)
        if max_samples is not None and total > max_samples
        else None
    )
    offset = 0
    for e in exps:
        sel: slice | np.ndarray = slice(None)
        if keep is not None:
            lo, hi = np.searchsorted(keep, [offset, offset + e.n])
            sel = keep[lo:hi] - offset
        offset += e.n
        el = np.ascontiguousarray(e.electrical(source), dtype=np.float64)
        cols["i"].append((el if eta is None else first_order_lag(el, e.dt, eta))[sel])
        cols["x"].append(e.x[sel])
        cols["v"].append(e.v[sel])
        cols["F"].append(e.F[sel])
    return tuple(np.ascontiguousarray(np.concatenate(cols[k])) for k in ("x", "v", "i", "F"))


def _even_subset(n: int, size: int | None) -> np.ndarray:
    """Indices of ``size`` samples evenly spaced over ``0 .. n-1`` (all samples if ``size`` is None)."""
    if size is None or size >= n:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, size).astype(np.int64))


def _rms(a: np.ndarray) -> float:
    r = float(np.sqrt(np.mean(a * a)))
    return r if r > 0 else 1.0


def _check_identifiable(
    cls: type[_SPModel], comp: np.ndarray, power: np.ndarray, inn: np.ndarray, source: str
) -> None:
    """Each component's input polynomial must have full column rank over the training input."""
    levels = np.unique(np.round(inn, 9))
    for m in range(N_COMPONENTS):
        pw = power[comp == m]
        if pw.size == 0:
            continue
        V = np.stack([inn**p for p in pw], axis=1)
        norms = np.linalg.norm(V, axis=0)
        if np.any(norms == 0):
            raise IdentificationError(
                f"{source}: {cls.kind} component {COMPONENTS[m]} has a term in {source}^{int(pw[norms == 0][0])} "
                f"but the training input is zero everywhere; records with a non-zero input are needed"
            )
        sv = np.linalg.svd(V / norms, compute_uv=False)
        if sv[-1] <= sv[0] / _MAX_INPUT_COND:
            rank = int(np.sum(sv > sv[0] / _MAX_INPUT_COND))
            raise IdentificationError(
                f"{source}: {cls.kind} component {COMPONENTS[m]} is a polynomial with {pw.size} "
                f"coefficients in {source} but the training input takes {min(levels.size, 99)} "
                f"distinct value(s) (numerical rank {rank} of {pw.size}); it is not identifiable: "
                f"train on records with at least {pw.size} distinct {source} levels"
            )


def _single_level_terms(comp: np.ndarray, power: np.ndarray) -> np.ndarray:
    """Mask keeping, per component, only its lowest power of the input (the constant law)."""
    keep = np.zeros(comp.size, bool)
    for m in np.unique(comp):
        idx = np.flatnonzero(comp == m)
        keep[idx[np.argmin(power[idx])]] = True
    return keep


def _bounds(comp: np.ndarray, power: np.ndarray, offset: bool) -> tuple[np.ndarray, np.ndarray]:
    n = comp.size + int(offset)
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    k = np.flatnonzero((comp == 1) & (power == 0))
    lb[k], ub[k] = 0.0, _TANH_SLOPE_MAX
    return lb, ub


def _linear_columns(
    comp: np.ndarray,
    power: np.ndarray,
    th: np.ndarray,
    xn: np.ndarray,
    vn: np.ndarray,
    inn: np.ndarray,
    offset: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Regressors of the coefficients that enter linearly (A, c, d, f0) for a fixed tanh term."""
    lin = np.flatnonzero(np.isin(comp, (0, 3, 4)))
    base = {0: th, 3: vn, 4: xn}
    cols = [base[int(comp[k])] * inn ** power[k] for k in lin]
    if offset:
        cols.append(np.ones_like(xn))
    return np.stack(cols, axis=1), lin


def _linear_starts(
    comp: np.ndarray,
    power: np.ndarray,
    xn: np.ndarray,
    vn: np.ndarray,
    inn: np.ndarray,
    Fn: np.ndarray,
    est: _SPEstimator,
    rng: np.random.Generator,
) -> list[np.ndarray]:
    """Rank seeded draws of the tanh argument by the cost of the linear least-squares completion."""
    ka = int(np.flatnonzero((comp == 1) & (power == 0))[0])
    kb = int(np.flatnonzero((comp == 2) & (power == 0))[0])
    n_par = comp.size + int(est.offset)
    slopes = 10.0 ** rng.uniform(-0.5, 2.0, est.n_candidates)
    ratios = rng.uniform(-1.0, 1.0, est.n_candidates)
    ratios[: max(1, est.n_candidates // 8)] = 0.0  # always try a tanh without displacement term
    scored = []
    for a, r in zip(slopes, ratios):
        z = a * vn + a * r * xn
        X, lin = _linear_columns(comp, power, np.tanh(z), xn, vn, inn, est.offset)
        coef = _normal_lstsq(X, Fn)
        cost = float(np.sum((X @ coef - Fn) ** 2))
        theta = np.zeros(n_par)
        theta[ka], theta[kb] = a, a * r
        theta[lin] = coef[: lin.size]
        if est.offset:
            theta[-1] = coef[-1]
        if np.isfinite(cost):
            scored.append((cost, theta))
    scored.sort(key=lambda ct: ct[0])
    return [th for _, th in scored[: est.n_starts]]


def _normal_lstsq(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares through column-equilibrated normal equations (small p, tall X).

    Used for the cheap screening of starts only; a (nearly) singular system returns a
    minimum-norm solution via ``lstsq`` on the small Gram matrix.
    """
    norms = np.sqrt(np.einsum("ij,ij->j", X, X))
    norms[norms == 0] = 1.0
    Xs = X / norms
    coef, *_ = np.linalg.lstsq(Xs.T @ Xs, Xs.T @ y, rcond=1e-12)
    return coef / norms


def _to_physical(
    theta: np.ndarray,
    comp: np.ndarray,
    power: np.ndarray,
    offset: bool,
    *,
    xs: float,
    vs: float,
    i_s: float,
    Fs: float,
) -> tuple[np.ndarray, float]:
    """Convert normalised coefficients back to SI: exact rescaling per component and power."""
    comp_scale = np.array([Fs, 1.0 / vs, 1.0 / xs, Fs / vs, Fs / xs])
    S = theta[: comp.size] * comp_scale[comp] / i_s ** power.astype(float)
    f0 = float(theta[-1] * Fs) if offset else 0.0
    return S, f0


for _est, _mod in (
    (SP1Estimator, SP1Model),
    (SP2Estimator, SP2Model),
    (SP3Estimator, SP3Model),
    (SP4Estimator, SP4Model),
):
    register(_est, _mod)
