"""Output-error identification of the one-state hysteresis families (private).

Shared by ``tanh``, ``boucwen``, ``dahl`` and ``lugre`` (:mod:`._hysteresis_kernels`):

* every record is simulated in free run from its own rest state; weighted residuals are stacked
  (``"record"`` weighting: each record by ``1 / (std(F) sqrt(N_record n_records))``, so the cost
  is half the mean per-record ESR);
* the unknowns are the family's *identified* parameters (:attr:`FitSpec.unknowns`, sometimes a
  reparametrisation of the published ones chosen so that a box keeps the model stable), scaled
  by their start values (``theta = scale * q``) so the optimiser works on numbers of order one;
* bounded nonlinear least squares (:func:`scipy.optimize.least_squares`, ``trf``, finite-difference
  Jacobian in the scaled unknowns);
* the first start maps the weighted regression
  ``F ~ (fa + fb e) tanh(v / v_eps) + (ca + cb e) v + k x + f0`` (shared with the Spencer fit) onto
  the family at an assumed yield displacement; further starts vary that displacement and jitter
  the result with a seeded generator; each start runs ``screen_nfev`` evaluations and the best
  continues to convergence.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from mrdamper._warn import warn_user
from mrdamper.data import ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError
from mrdamper.models.hysteresis import kernels as _k
from mrdamper.models.spencer.fit import _regression, _strictly_inside
from mrdamper.progress import counted, report

__all__ = ["FitSettings", "FitSpec", "Scales", "check_mappings", "identify", "unit_floors"]

#: Residual value per sample returned for parameter sets whose simulation fails.
_PENALTY = 1e3
#: First-start yield displacement as a fraction of the median record amplitude [-].
YIELD_FRACTION = 0.05
#: Condition number of J^T J (scaled unknowns) above which the fit is reported ill-conditioned.
COND_WARNING = 1e10


@dataclass(frozen=True)
class Scales:
    """Typical magnitudes of the training data (for scaling floors and starts).

    Attributes
    ----------
    force : float
        Mean per-record standard deviation of the force [N].
    v, x, e : float
        Largest |velocity| [m/s], |displacement| [m] and |electrical input| (at least 1).
    amplitude : float
        Median record amplitude of x about its mean [m].
    """

    force: float
    v: float
    x: float
    e: float
    amplitude: float


def unit_floors(units: Mapping[str, str]) -> Callable[[Scales], dict[str, float]]:
    """Scaling floors from the physical kind of every unknown.

    ``units`` maps an unknown to ``"damp"`` [N s/m], ``"stiff"`` [N/m], ``"force"`` [N],
    ``"1/v"`` [s/m], ``"1/x"`` [1/m], ``"x"`` [m] or ``"one"`` [-], with ``"/e"`` appended for
    a coefficient of the electrical input. The floor is 1 % of the typical force (over the
    typical velocity or displacement), the inverse typical velocity or displacement, 1 % of the
    typical displacement, or 1.
    """

    def floors(s: Scales) -> dict[str, float]:
        base = {
            "damp": 1e-2 * s.force / s.v,
            "stiff": 1e-2 * s.force / s.x,
            "force": 1e-2 * s.force,
            "1/v": 1.0 / s.v,
            "1/x": 1.0 / s.x,
            "x": 1e-2 * s.x,
            "one": 1.0,
        }
        out = {}
        for name, unit in units.items():
            kind = unit.removesuffix("/e")
            out[name] = base[kind] / (s.e if kind != unit else 1.0)
        return out

    return floors


@dataclass(frozen=True)
class FitSpec:
    """What the shared fit needs to know of a family.

    Attributes
    ----------
    family : str
        Family name (a key of :data:`~._hysteresis_kernels.PARAM_NAMES`).
    unknowns : tuple of str
        Names of the identified parameters (every parameter but ``eta``).
    bounds : mapping
        ``name -> (low, high)`` of every unknown.
    start : callable
        ``start(regression, yield_disp, scales) -> {unknown: value}``.
    floors : callable
        ``floors(scales) -> {unknown: smallest scale}``.
    to_params : callable
        ``to_params({unknown: value}) -> {published parameter: value}`` (``eta`` excluded).
    single_fixed : callable
        ``single_fixed(start) -> {unknown: value}``: what a single input level fixes.
    default_fixed : mapping
        Unknowns fixed unless the estimator's ``fixed`` says otherwise.
    jitter_skip : tuple of str
        Unknowns the random starts leave alone (signed offsets, exponents).
    """

    family: str
    unknowns: tuple[str, ...]
    bounds: Mapping[str, tuple[float, float]]
    start: Callable[[np.ndarray, float, Scales], dict[str, float]]
    floors: Callable[[Scales], dict[str, float]]
    to_params: Callable[[Mapping[str, float]], dict[str, float]]
    single_fixed: Callable[[Mapping[str, float]], dict[str, float]]
    default_fixed: Mapping[str, float] = field(default_factory=dict)
    jitter_skip: tuple[str, ...] = ("f0",)


@dataclass(frozen=True)
class FitSettings:
    """The estimator settings the identification uses."""

    input: ElectricalSource
    start: Mapping[str, float] | None
    fixed: Mapping[str, float] | None
    bounds: Mapping[str, tuple[float, float]] | None
    n_starts: int
    seed: int
    weighting: str
    max_nfev: int
    screen_nfev: int
    ftol: float
    xtol: float
    gtol: float
    substeps: int
    eta: float | None


@dataclass(frozen=True)
class _Record:
    name: str
    x: np.ndarray
    v: np.ndarray
    e: np.ndarray
    F: np.ndarray
    dt: float
    weight: float
    vmax: float
    sl: slice


def check_mappings(spec: FitSpec, est: FitSettings) -> None:
    """Check ``start``, ``fixed`` and ``bounds`` name unknowns of the family with finite numbers
    and ``low < high``."""
    for name in ("start", "fixed", "bounds"):
        mapping = getattr(est, name)
        if mapping is None:
            continue
        if not isinstance(mapping, Mapping):
            raise DataValidationError(
                name, f"expected a mapping of parameter names, got {type(mapping).__name__}"
            )
        unknown = sorted(set(mapping) - set(spec.unknowns))
        if unknown:
            raise DataValidationError(
                name, f"unknown parameter(s) {unknown}; expected names from {list(spec.unknowns)}"
            )
    for name, value in {**(est.start or {}), **(est.fixed or {})}.items():
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float, np.integer, np.floating))
            or not math.isfinite(float(value))
        ):
            raise DataValidationError(
                name, f"start/fixed value must be a finite number, got {value!r}"
            )
    for name, b in (est.bounds or {}).items():
        try:
            lo, hi = float(b[0]), float(b[1])
        except (TypeError, ValueError, IndexError):
            raise DataValidationError(
                f"bounds[{name!r}]", f"expected (low, high), got {b!r}"
            ) from None
        if not lo < hi:
            raise DataValidationError(f"bounds[{name!r}]", f"expected low < high, got ({lo}, {hi})")


def _records(est: FitSettings, exps: ExperimentSet, kind: str) -> list[_Record]:
    recs = []
    offset = 0
    n_rec = len(exps)
    total = sum(e.n for e in exps)
    f_std = float(np.std(np.concatenate([e.F for e in exps])))
    for exp in exps:
        exp.require_samples(10, f"{kind} identification")
        e = np.ascontiguousarray(exp.electrical(est.input), dtype=np.float64)
        if est.weighting == "record":
            sd = float(np.std(exp.F))
            if sd == 0.0:
                raise DataValidationError(
                    "F",
                    f"record {exp.name!r} has constant force; per-record weighting needs variance",
                )
            w = 1.0 / (sd * math.sqrt(exp.n * n_rec))
        else:
            if f_std == 0.0:
                raise DataValidationError("F", "the training force has zero variance")
            w = 1.0 / (f_std * math.sqrt(total))
        recs.append(
            _Record(
                exp.name,
                np.ascontiguousarray(exp.x),
                np.ascontiguousarray(exp.v),
                e,
                np.ascontiguousarray(exp.F),
                exp.dt,
                w,
                float(np.max(np.abs(exp.v))),
                slice(offset, offset + exp.n),
            )
        )
        offset += exp.n
    return recs


class _Objective:
    """Weighted free-run residuals of the scaled free unknowns."""

    def __init__(
        self,
        spec: FitSpec,
        recs: list[_Record],
        theta: dict[str, float],
        free: list[str],
        scale: np.ndarray,
        eta: float,
        substeps: int,
    ) -> None:
        self.spec = spec
        self.names = _k.PARAM_NAMES[spec.family]
        self.code = _k.FAMILIES[spec.family]
        self.recs = recs
        self.theta = theta
        self.free = free
        self.scale = scale
        self.eta = eta
        self.substeps = substeps
        self.n = recs[-1].sl.stop
        self.nfev = 0
        self.failures = 0
        self.last_failure = ""

    def unknowns(self, q: np.ndarray) -> dict[str, float]:
        th = dict(self.theta)
        th.update({nm: float(val) for nm, val in zip(self.free, q * self.scale)})
        return th

    def params(self, q: np.ndarray) -> np.ndarray:
        pub = self.spec.to_params(self.unknowns(q))
        pub["eta"] = self.eta
        return np.array([pub[nm] for nm in self.names], dtype=np.float64)

    def residuals(self, q: np.ndarray) -> np.ndarray:
        self.nfev += 1
        p = self.params(q)
        out = np.empty(self.n)
        for r in self.recs:
            nsub = self.substeps or _k.auto_substeps(self.spec.family, p, r.dt, r.vmax)
            F, status, sample = _k.simulate(self.code, r.x, r.v, r.e, r.dt, p, nsub)
            if status != _k.STATUS_OK:
                self.failures += 1
                self.last_failure = f"record {r.name!r}: status {status} at sample {sample}"
                return np.full(self.n, _PENALTY)
            out[r.sl] = r.weight * (F - r.F)
        return out


def identify(
    spec: FitSpec, est: FitSettings, exps: ExperimentSet, *, single: bool, kind: str
) -> tuple[dict[str, float], dict[str, Any]]:
    """Identify the family on ``exps``; return the published parameters (``eta`` included) and
    the provenance.

    With ``single`` (one input level over all records) the input-dependent terms are fixed as
    ``spec.single_fixed`` says, unless given in ``fixed``.

    Raises
    ------
    IdentificationError
        Every start diverged, or the optimiser returned a non-finite result.
    """
    recs = _records(est, exps, kind)
    eta = 0.0 if est.eta is None else float(est.eta)
    scales = Scales(
        force=float(np.mean([np.std(r.F) for r in recs])),
        v=max(max(r.vmax for r in recs), 1e-9),
        x=max(max(float(np.max(np.abs(r.x))) for r in recs), 1e-9),
        e=max([1.0] + [float(np.max(np.abs(r.e))) for r in recs]),
        amplitude=max(float(np.median([np.max(np.abs(r.x - np.mean(r.x))) for r in recs])), 1e-6),
    )
    reg = _regression(recs)  # type: ignore[arg-type]  # reads x, v, e, F, weight, vmax only
    start_user = {k: float(v) for k, v in (est.start or {}).items()}
    yield0 = YIELD_FRACTION * scales.amplitude

    def build(yield_disp: float) -> dict[str, float]:
        d = spec.start(reg, yield_disp, scales)
        d.update(start_user)
        return d

    base = build(yield0)
    fixed = dict(spec.default_fixed) if est.fixed is None else {}
    fixed.update({k: float(v) for k, v in (est.fixed or {}).items()})
    if single:
        for nm, val in spec.single_fixed(base).items():
            fixed.setdefault(nm, val)
    base.update(fixed)
    bounds = dict(spec.bounds)
    bounds.update({k: (float(b[0]), float(b[1])) for k, b in (est.bounds or {}).items()})
    free = [nm for nm in spec.unknowns if nm not in fixed]
    if not free:
        raise DataValidationError("fixed", "every parameter is fixed; nothing to identify")
    notes = [
        f"fixed {nm}={val:g} lies outside its bounds {bounds[nm]}"
        for nm, val in fixed.items()
        if not bounds[nm][0] <= val <= bounds[nm][1]
    ]
    floors = spec.floors(scales)
    scale = np.array([max(abs(base[nm]), floors[nm]) for nm in free])
    lo = np.array([bounds[nm][0] for nm in free]) / scale
    hi = np.array([bounds[nm][1] for nm in free]) / scale
    obj = _Objective(spec, recs, base, free, scale, eta, int(est.substeps))

    rng = np.random.default_rng(est.seed)
    starts = [base]
    for _ in range(est.n_starts - 1):
        d = build(yield0 * math.exp(rng.uniform(-1.5, 1.5)))
        for nm in free:
            if nm not in start_user and nm not in spec.jitter_skip:
                d[nm] *= math.exp(0.15 * rng.standard_normal())
        d.update(fixed)
        starts.append(d)

    kw: dict[str, Any] = {
        "bounds": (lo, hi),
        "method": "trf",
        "jac": "2-point",
        "ftol": est.ftol,
        "xtol": est.xtol,
        "gtol": est.gtol,
    }
    runs: list[dict[str, Any]] = []
    results = []
    for k, d in enumerate(starts):
        q0 = _strictly_inside(np.array([d[nm] for nm in free]) / scale, lo, hi)
        r0 = obj.residuals(q0)
        if obj.last_failure and np.all(r0 == _PENALTY):
            runs.append({"start": k, "cost": math.inf, "status": "start diverged"})
            obj.last_failure = ""
            continue
        nfev = est.screen_nfev if est.n_starts > 1 else est.max_nfev
        stage = f"start {k + 1} of {len(starts)}: " if len(starts) > 1 else ""
        res = least_squares(
            counted(obj.residuals, stage + "least squares: evaluation"), q0, max_nfev=nfev, **kw
        )
        runs.append(
            {"start": k, "cost": float(res.cost), "nfev": int(res.nfev), "status": int(res.status)}
        )
        results.append(res)
    finite = [r for r in results if np.isfinite(r.cost) and r.cost < 0.25 * _PENALTY**2 * obj.n]
    if not finite:
        raise IdentificationError(
            f"{kind}: every one of {len(starts)} start(s) diverged or failed "
            f"(last failure: {obj.last_failure or 'n/a'}); give 'start' values or wider 'bounds'"
        )
    best = min(finite, key=lambda r: r.cost)
    final = best
    if est.n_starts > 1:
        final = least_squares(
            counted(obj.residuals, "best start: least squares: evaluation"),
            best.x,
            max_nfev=est.max_nfev,
            **kw,
        )
        if not final.cost <= best.cost:
            final = best
    if not np.all(np.isfinite(final.x)) or not math.isfinite(final.cost):
        raise IdentificationError(
            f"{kind}: optimiser returned a non-finite result ({final.message})"
        )
    theta = obj.unknowns(final.x)
    sv = np.linalg.svd(final.jac, compute_uv=False)
    cond = float((sv[0] / sv[-1]) ** 2) if sv[-1] > 0 else math.inf
    converged = bool(final.status > 0)
    if not cond < COND_WARNING:
        warn_user(
            f"{kind}: identification is ill-conditioned (cond(J^T J) = {cond:.3g} in scaled "
            "unknowns); some parameters are not determined by these records",
            RuntimeWarning,
        )
    if not converged:
        warn_user(
            f"{kind}: optimiser stopped before convergence ({final.message}); raise max_nfev",
            RuntimeWarning,
        )
    report("residuals of the fit")
    resid = obj.residuals(final.x)
    rec_esr = {r.name: float(np.mean((resid[r.sl] / r.weight) ** 2) / np.var(r.F)) for r in recs}
    params = spec.to_params(theta)
    params["eta"] = eta
    provenance: dict[str, Any] = {
        "method": "bounded nonlinear least squares on the free-run simulation error "
        "(scipy.optimize.least_squares, trf, finite-difference Jacobian); records simulated "
        "separately from rest",
        "records": [r.name for r in recs],
        "n_samples": int(obj.n),
        "weighting": est.weighting,
        "input": est.input,
        "identified": theta,
        "fixed": fixed,
        "free": free,
        "bounds": {nm: list(bounds[nm]) for nm in free},
        "starts": runs,
        "seed": int(est.seed),
        "cost": float(final.cost),
        "mean_record_esr": float(np.mean(list(rec_esr.values()))),
        "record_esr": rec_esr,
        "nfev_total": int(obj.nfev),
        "status": int(final.status),
        "message": str(final.message),
        "converged": converged,
        "cond_JTJ": cond,
        "ill_conditioned": not cond < COND_WARNING,
        "at_bounds": [free[j] for j in np.flatnonzero(final.active_mask)],
        "simulation_failures": int(obj.failures),
        "substeps": int(est.substeps) if est.substeps > 0 else "automatic",
        "notes": notes,
    }
    return params, provenance
