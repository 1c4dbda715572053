"""Output-error identification of the one-state hysteresis families (private).

Shared by ``tanh``, ``boucwen``, ``dahl`` and ``lugre`` (:mod:`mrdamper.models.hysteresis.kernels`):

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

from mrdamper.data import ExperimentSet
from mrdamper.errors import DataValidationError
from mrdamper.models import _output_error as oe
from mrdamper.models._output_error import Record
from mrdamper.models.hysteresis import kernels as _k

__all__ = ["FitSettings", "FitSpec", "Scales", "check_mappings", "identify", "unit_floors"]

#: First-start yield displacement as a fraction of the median record amplitude [-].
YIELD_FRACTION = 0.05


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
        Family name (a key of :data:`~mrdamper.models.hysteresis.kernels.PARAM_NAMES`).
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
class FitSettings(oe.OutputErrorSettings):
    """The estimator settings the identification uses."""

    eta: float | None


def check_mappings(spec: FitSpec, est: FitSettings) -> None:
    """Check ``start``, ``fixed`` and ``bounds`` name unknowns of the family with finite numbers
    and ``low < high``."""
    oe.check_mappings(spec.unknowns, est.start, est.fixed, est.bounds)


class _Objective(oe.FreeRunObjective):
    """Weighted free-run residuals of the scaled free unknowns."""

    def __init__(
        self,
        spec: FitSpec,
        recs: list[Record],
        theta: dict[str, float],
        free: list[str],
        scale: np.ndarray,
        eta: float,
        substeps: int,
    ) -> None:
        super().__init__(recs, self.vector, self.run)
        self.spec = spec
        self.names = _k.PARAM_NAMES[spec.family]
        self.code = _k.FAMILIES[spec.family]
        self.theta = theta
        self.free = free
        self.scale = scale
        self.eta = eta
        self.substeps = substeps

    def unknowns(self, q: np.ndarray) -> dict[str, float]:
        th = dict(self.theta)
        th.update({nm: float(val) for nm, val in zip(self.free, q * self.scale)})
        return th

    def vector(self, q: np.ndarray) -> np.ndarray:
        pub = self.spec.to_params(self.unknowns(q))
        pub["eta"] = self.eta
        return np.array([pub[nm] for nm in self.names], dtype=np.float64)

    def run(self, r: Record, p: np.ndarray) -> tuple[np.ndarray, int, int]:
        nsub = self.substeps or _k.auto_substeps(self.spec.family, p, r.dt, r.vmax)
        F, status, sample = _k.simulate(self.code, r.x, r.v, r.e, r.dt, p, nsub)
        return F, int(status), int(sample)


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
    recs = oe.records(exps, est.input, est.weighting, f"{kind} identification")
    eta = 0.0 if est.eta is None else float(est.eta)
    scales = Scales(
        force=float(np.mean([np.std(r.F) for r in recs])),
        v=max(max(r.vmax for r in recs), 1e-9),
        x=max(max(float(np.max(np.abs(r.x))) for r in recs), 1e-9),
        e=max([1.0] + [float(np.max(np.abs(r.e))) for r in recs]),
        amplitude=max(float(np.median([np.max(np.abs(r.x - np.mean(r.x))) for r in recs])), 1e-6),
    )
    reg = oe.regression(recs)
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

    options = {"ftol": est.ftol, "xtol": est.xtol, "gtol": est.gtol}
    q_starts = [np.array([d[nm] for nm in free]) / scale for d in starts]
    fit = oe.multistart(
        obj, q_starts, lo, hi, free, kind=kind, settings=est, jac="2-point", options=options
    )
    theta = obj.unknowns(fit.final.x)
    params = spec.to_params(theta)
    params["eta"] = eta
    provenance: dict[str, Any] = {
        "method": "bounded nonlinear least squares on the free-run simulation error "
        "(scipy.optimize.least_squares, trf, finite-difference Jacobian); records simulated "
        "separately from rest",
        "weighting": est.weighting,
        "input": est.input,
        "identified": theta,
        "fixed": fixed,
        "free": free,
        "bounds": {nm: list(bounds[nm]) for nm in free},
        "seed": int(est.seed),
        **fit.provenance,
        "substeps": int(est.substeps) if est.substeps > 0 else "automatic",
        "notes": notes,
    }
    return params, provenance
