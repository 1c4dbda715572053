"""Identification machinery of the Spencer model (private; used by ``FitSettings.fit``).

* Records are simulated separately from their own rest state; residuals are stacked.
* Unknowns are scaled (``p = scale * q``) so the optimiser works on numbers of order one.
* The Jacobian comes from forward sensitivities integrated with the state by the RK4 kernel.
* The first start is a data-driven guess: a weighted linear regression
  ``F ~ (fa + fb e) tanh(v / v_eps) + (ca + cb e) v + k x + f0`` mapped onto the model at an
  assumed yield displacement and damper ratio ``c1 / c0``; further starts vary those two
  assumptions and jitter the result with a seeded generator.
* Each start runs a short screening fit; the best continues to convergence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mrdamper.data import ExperimentSet
from mrdamper.errors import DataValidationError
from mrdamper.models import _output_error as oe
from mrdamper.models._output_error import COND_WARNING, Record
from mrdamper.models.envelope import SWITCH_FRACTION
from mrdamper.models.levels import held_within_records
from mrdamper.models.spencer import kernels as _k
from mrdamper.models.spencer.kernels import PARAM_NAMES as PARAMETER_NAMES
from mrdamper.models.spencer.kernels import auto_substeps

__all__ = ["COND_WARNING", "DEFAULT_BOUNDS", "FitSettings", "check_settings", "identify"]

_INF = math.inf
#: Default identification bounds (SI). Current-dependence coefficients are non-negative (the
#: MR effect grows with the field); gamma may take either sign; n stays in [1, 4].
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "c0a": (0.0, _INF),
    "c0b": (0.0, _INF),
    "k0": (0.0, _INF),
    "c1a": (0.0, _INF),
    "c1b": (0.0, _INF),
    "k1": (-_INF, _INF),
    "x0": (-_INF, _INF),
    "alpha_a": (0.0, _INF),
    "alpha_b": (0.0, _INF),
    "gamma": (-_INF, _INF),
    "beta": (0.0, _INF),
    "A": (0.0, _INF),
    "n": (1.0, 4.0),
    "eta": (1e-2, 1e5),
    "f0": (-_INF, _INF),
}


@dataclass(frozen=True)
class FitSettings(oe.OutputErrorSettings):
    """The estimator settings the identification uses (see ``SpencerEstimator``)."""

    jacobian: str
    fix_eta: str


#: First-start assumptions: yield displacement as a fraction of the median record amplitude,
#: ratio c1 / c0 and Bouc-Wen exponent (n = 1 is the smooth, mildly stiff end of the range).
YIELD_FRACTION = 0.02
RATIO_START = 20.0
N_START = 1.0
#: Parameters fixed when the estimator's ``fixed`` is None: k1 x0 duplicates f0, and A is
#: redundant with the scale of z.
DEFAULT_FIXED = {"x0": 0.0, "A": 1.0}
#: Scaling of the unknowns inside least_squares (they are already scaled by their start values).
X_SCALE: Any = 1.0
#: Input-dependent terms fixed at 0 when the training input takes a single level.
SINGLE_LEVEL_FIXED = ("c0b", "c1b", "alpha_b")
_IDX = {n: k for k, n in enumerate(PARAMETER_NAMES)}


def check_settings(est: FitSettings) -> None:
    """Check the parameter mappings ``start``, ``fixed`` and ``bounds`` (the other settings are
    checked by the estimator)."""
    oe.check_mappings(PARAMETER_NAMES, est.start, est.fixed, est.bounds)


def _map_start(
    reg: np.ndarray, yield_disp: float, ratio: float, A: float, n: float, force_scale: float
) -> dict[str, float]:
    """Map Bingham-like regression coefficients onto Spencer parameters."""
    fa, fb, ca, cb, k, f0 = (float(c) for c in reg)
    zss = max(abs(A), 1e-12) * yield_disp
    factor = (1.0 + ratio) / ratio
    small_f = 1e-3 * force_scale
    alpha_a = max(fa, small_f) * factor / zss
    return {
        "alpha_a": alpha_a,
        "alpha_b": max(fb, 0.0) * factor / zss,
        "c0a": max(ca, 1e-3 * force_scale) * factor,
        "c0b": max(cb, 0.0) * factor,
        "c1a": ratio * max(ca, 1e-3 * force_scale) * factor,
        "c1b": ratio * max(cb, 0.0) * factor,
        "k0": 0.02 * alpha_a,
        "k1": k,
        "x0": 0.0,
        "beta": abs(A) / (2.0 * zss**n),
        "gamma": abs(A) / (2.0 * zss**n),
        "A": A,
        "n": n,
        "eta": 100.0,
        "f0": f0,
    }


class _Objective(oe.FreeRunObjective):
    """Weighted free-run residuals and their sensitivity Jacobian in scaled unknowns."""

    def __init__(
        self,
        recs: list[Record],
        p_fixed: np.ndarray,
        free: np.ndarray,
        scale: np.ndarray,
        substeps: int,
    ) -> None:
        super().__init__(recs, self.vector, self.run)
        self.p_fixed = p_fixed
        self.free = free
        self.scale = scale
        self.substeps = substeps
        self.njev = 0

    def vector(self, q: np.ndarray) -> np.ndarray:
        p = self.p_fixed.copy()
        p[self.free] = q * self.scale
        return p

    def nsub(self, p: np.ndarray, r: Record) -> int:
        if self.substeps > 0:
            return self.substeps
        return auto_substeps(p, r.dt, r.vmax, r.emin, r.emax)

    def run(self, r: Record, p: np.ndarray) -> tuple[np.ndarray, int, int]:
        F, status, sample = _k.simulate(
            r.x, r.v, r.e, r.dt, p, self.nsub(p, r), r.x[0], 0.0, r.e[0]
        )
        return F, int(status), int(sample)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        self.njev += 1
        p = self.params(q)
        J = np.empty((self.n, self.free.size))
        for r in self.recs:
            _, G, status, _ = _k.simulate_sens(
                r.x, r.v, r.e, r.dt, p, self.nsub(p, r), r.x[0], 0.0, r.e[0], self.free
            )
            if status != _k.STATUS_OK:
                J[r.sl] = 0.0
                continue
            J[r.sl] = G * (r.weight * self.scale)
        return J


def _constant_input(recs: list[Record]) -> bool:
    """The electrical input never switches within a record (spans of at most
    :data:`~mrdamper.models.envelope.SWITCH_FRACTION` of the training range; noise on a held
    current does not count)."""
    return held_within_records([(r.emin, r.emax) for r in recs], SWITCH_FRACTION)


def identify(
    est: FitSettings, exps: ExperimentSet, *, single: bool = False
) -> tuple[np.ndarray, dict[str, Any]]:
    """Run the identification; return the parameter vector (:data:`PARAMETER_NAMES` order) and
    the provenance.

    With ``single`` (the electrical input takes one level in all the records) the laws in the
    input are constants: ``c0b``, ``c1b`` and ``alpha_b`` are fixed at 0 unless given in
    ``fixed``.
    """
    recs = oe.records(exps, est.input, est.weighting, "Spencer identification")
    notes: list[str] = []
    if est.fixed is None:
        fixed: dict[str, float] = dict(DEFAULT_FIXED)
    else:  # an explicit mapping replaces the defaults
        fixed = {k: float(v) for k, v in est.fixed.items()}
    if single:
        for name in SINGLE_LEVEL_FIXED:
            fixed.setdefault(name, 0.0)
    start_user = {k: float(v) for k, v in (est.start or {}).items()}
    constant = _constant_input(recs)
    if "eta" not in fixed and (est.fix_eta == "always" or (est.fix_eta == "auto" and constant)):
        fixed["eta"] = start_user.get("eta", 100.0)
        if constant:
            notes.append(
                f"eta fixed at {fixed['eta']:g} 1/s: the electrical input does not switch within "
                "any record, so the filter rate cannot be identified"
            )
    bounds = dict(DEFAULT_BOUNDS)
    bounds.update({k: (float(b[0]), float(b[1])) for k, b in (est.bounds or {}).items()})

    force_scale = float(np.mean([np.std(r.F) for r in recs]))
    reg = oe.regression(recs)
    A = fixed.get("A", start_user.get("A", 1.0))
    n0 = fixed.get("n", start_user.get("n", N_START))
    amp = float(np.median([np.max(np.abs(r.x - np.mean(r.x))) for r in recs]))
    yield0 = max(YIELD_FRACTION * amp, 1e-6)
    ratio0 = RATIO_START

    def build(yield_disp: float, ratio: float) -> np.ndarray:
        d = _map_start(reg, yield_disp, ratio, A, n0, force_scale)
        d.update(start_user)
        d.update(fixed)
        return np.array([d[nm] for nm in PARAMETER_NAMES], dtype=float)

    free_names = [nm for nm in PARAMETER_NAMES if nm not in fixed]
    if not free_names:
        raise DataValidationError("fixed", "every parameter is fixed; nothing to identify")
    free = np.array([_IDX[nm] for nm in free_names], dtype=np.int64)
    lo = np.array([bounds[nm][0] for nm in free_names])
    hi = np.array([bounds[nm][1] for nm in free_names])
    base = build(yield0, ratio0)
    for nm, value in fixed.items():
        b = bounds[nm]
        if not b[0] <= value <= b[1]:
            notes.append(f"fixed {nm}={value:g} lies outside its default bounds {b}")

    floors = _scale_floors(recs, force_scale)
    scale = np.maximum(np.abs(base[free]), np.array([floors[nm] for nm in free_names]))
    obj = _Objective(recs, base.copy(), free, scale, int(est.substeps))
    q_lo, q_hi = lo / scale, hi / scale

    rng = np.random.default_rng(est.seed)
    starts = [base]
    for _ in range(est.n_starts - 1):
        yd = yield0 * math.exp(rng.uniform(-1.5, 1.5))
        ra = ratio0 * math.exp(rng.uniform(-1.2, 1.2))
        p = build(yd, ra)
        jitter = np.exp(0.15 * rng.standard_normal(p.size))
        for j, nm in enumerate(PARAMETER_NAMES):
            if nm not in fixed and nm not in start_user and nm not in ("n", "k1", "f0", "x0"):
                p[j] *= jitter[j]
        starts.append(p)

    method = est.jacobian
    jac = obj.jacobian if method == "sensitivity" else method
    options = {"x_scale": X_SCALE, "ftol": est.ftol, "xtol": est.xtol, "gtol": est.gtol}
    q_starts = [p0[free] / scale for p0 in starts]
    fit = oe.multistart(
        obj,
        q_starts,
        q_lo,
        q_hi,
        free_names,
        kind="spencer",
        settings=est,
        jac=jac,
        options=options,
    )
    p_hat = obj.params(fit.final.x)
    provenance: dict[str, Any] = {
        "method": "bounded nonlinear least squares on the free-run simulation error "
        "(scipy.optimize.least_squares, trf); records simulated separately from rest",
        "jacobian": "forward sensitivities (RK4)"
        if method == "sensitivity"
        else f"finite differences ({method})",
        "weighting": est.weighting,
        "input": est.input,
        "fixed": fixed,
        "free": free_names,
        "bounds": {nm: list(bounds[nm]) for nm in free_names},
        "seed": int(est.seed),
        **fit.provenance,
        "njev_total": int(obj.njev),
        "substeps": int(est.substeps) if est.substeps > 0 else "automatic",
        "notes": notes,
    }
    return p_hat, provenance


def _scale_floors(recs: list[Record], force_scale: float) -> dict[str, float]:
    vs = max(max(r.vmax for r in recs), 1e-9)
    xs = max(max(float(np.max(np.abs(r.x))) for r in recs), 1e-9)
    es = max(max(abs(r.emin), abs(r.emax)) for r in recs) or 1.0
    damp = 1e-2 * force_scale / vs
    stiff = 1e-2 * force_scale / xs
    return {
        "c0a": damp,
        "c0b": damp / es,
        "c1a": damp,
        "c1b": damp / es,
        "k0": stiff,
        "k1": stiff,
        "x0": xs,
        "alpha_a": stiff,
        "alpha_b": stiff / es,
        "gamma": 1.0,
        "beta": 1.0,
        "A": 1.0,
        "n": 1.0,
        "eta": 10.0,
        "f0": 1e-2 * force_scale,
    }
