"""The output-error fit shared by Spencer and the one-state hysteresis families (private).

Both identify a continuous-time model by bounded nonlinear least squares on its free-run error;
what differs is the parameter vector, the simulation, the first start and (for Spencer) the
sensitivity Jacobian. Everything else is here, written once:

* :func:`records`: each record's arrays and weight (``"record"`` weighting: each record by
  ``1 / (std(F) sqrt(N_record n_records))``, so the cost is half the mean per-record ESR;
  ``"none"``: every sample by ``1 / (std(F) sqrt(N))``);
* :func:`check_mappings`: the ``start`` / ``fixed`` / ``bounds`` settings name known parameters
  with finite numbers and ``low < high``;
* :func:`regression`: the weighted regression
  ``F ~ (fa + fb e) tanh(v / v_eps) + (ca + cb e) v + k x + f0`` that every first start maps onto
  its family;
* :class:`FreeRunObjective`: the weighted free-run residuals (a failed simulation gives a
  penalty and is counted);
* :func:`multistart`: every start screened with ``screen_nfev`` evaluations, the best continued
  to convergence (:func:`scipy.optimize.least_squares`, ``trf``), the conditioning and
  convergence warnings and the per-record ESR of the result;
* :func:`fit_and_check`: the fit on evenly spread windows of long campaigns, then the
  step-halving check of the fitted model and the full-data check.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

from mrdamper._warn import warn_user
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError
from mrdamper.models import _scale
from mrdamper.models._step_check import step_halving_check
from mrdamper.models._values import Identified, TrainingData
from mrdamper.models.settings import check_int, check_number
from mrdamper.progress import counted, report

__all__ = [
    "COND_WARNING",
    "PENALTY",
    "FitOutcome",
    "FreeRunObjective",
    "OutputErrorSettings",
    "Record",
    "check_mappings",
    "check_real_fields",
    "check_settings",
    "fit_and_check",
    "multistart",
    "records",
    "regression",
    "strictly_inside",
]

#: Residual value per sample returned for parameter sets whose simulation fails.
PENALTY = 1e3
#: Condition number of J^T J (scaled unknowns) above which the fit is reported ill-conditioned.
COND_WARNING = 1e10


@dataclass(frozen=True)
class OutputErrorSettings:
    """The estimator settings every output-error fit reads (a family adds its own)."""

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


@dataclass(frozen=True)
class Record:
    """One training record as the fit reads it.

    Attributes
    ----------
    name : str
        Record name.
    x, v, e, F : ndarray
        Displacement [m], velocity [m/s], electrical input [A or V] and force [N].
    dt : float
        Sampling interval [s].
    weight : float
        Residual weight [1/N].
    vmax, emin, emax : float
        Largest |velocity| [m/s]; smallest and largest electrical input.
    sl : slice
        The record's rows in the stacked residual vector.
    """

    name: str
    x: np.ndarray
    v: np.ndarray
    e: np.ndarray
    F: np.ndarray
    dt: float
    weight: float
    vmax: float
    emin: float
    emax: float
    sl: slice


def records(
    exps: ExperimentSet, source: ElectricalSource, weighting: str, what: str
) -> list[Record]:
    """The records of ``exps`` with their weights (see the module docstring).

    Raises
    ------
    DataValidationError
        A record has fewer than 10 samples (``what`` names the fit), or the force whose standard
        deviation the weight divides by is constant.
    """
    recs = []
    offset = 0
    n_rec = len(exps)
    total = sum(e.n for e in exps)
    f_std = float(np.std(np.concatenate([e.F for e in exps])))
    for exp in exps:
        exp.require_samples(10, what)
        e = np.ascontiguousarray(exp.electrical(source), dtype=np.float64)
        if weighting == "record":
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
            Record(
                exp.name,
                np.ascontiguousarray(exp.x),
                np.ascontiguousarray(exp.v),
                e,
                np.ascontiguousarray(exp.F),
                exp.dt,
                w,
                float(np.max(np.abs(exp.v))),
                float(np.min(e)),
                float(np.max(e)),
                slice(offset, offset + exp.n),
            )
        )
        offset += exp.n
    return recs


def check_mappings(
    names: Sequence[str],
    start: Mapping[str, float] | None,
    fixed: Mapping[str, float] | None,
    bounds: Mapping[str, tuple[float, float]] | None,
) -> None:
    """Check that ``start``, ``fixed`` and ``bounds`` name parameters of ``names`` with finite
    numbers and ``low < high`` (one-line errors naming the setting)."""
    for name, mapping in (("start", start), ("fixed", fixed), ("bounds", bounds)):
        if mapping is None:
            continue
        if not isinstance(mapping, Mapping):
            raise DataValidationError(
                name, f"expected a mapping of parameter names, got {type(mapping).__name__}"
            )
        unknown = sorted(set(mapping) - set(names))
        if unknown:
            raise DataValidationError(
                name, f"unknown parameter(s) {unknown}; expected names from {list(names)}"
            )
    for name, value in {**(start or {}), **(fixed or {})}.items():
        if not _is_real(value) or not math.isfinite(float(value)):
            raise DataValidationError(
                name, f"start/fixed value must be a finite number, got {value!r}"
            )
    for name, b in (bounds or {}).items():
        try:
            lo, hi = float(b[0]), float(b[1])
        except (TypeError, ValueError, IndexError):
            raise DataValidationError(
                f"bounds[{name!r}]", f"expected (low, high), got {b!r}"
            ) from None
        if not lo < hi:
            raise DataValidationError(f"bounds[{name!r}]", f"expected low < high, got ({lo}, {hi})")


def _is_real(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))


def check_real_fields(model: Any, names: Sequence[str]) -> None:
    """Check that the fields ``names`` of a frozen fitted model are finite real numbers, store
    them as floats, and check ``substeps`` (a non-negative integer) and ``input``."""
    for name in names:
        value = getattr(model, name)
        if not _is_real(value):
            raise DataValidationError(name, f"expected a real number, got {value!r}")
        if not math.isfinite(float(value)):
            raise DataValidationError(name, f"expected a finite number, got {value!r}")
        object.__setattr__(model, name, float(value))
    substeps = model.substeps
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 0:
        raise DataValidationError(
            "substeps", f"expected a non-negative integer (0 = automatic), got {substeps!r}"
        )
    object.__setattr__(model, "substeps", int(substeps))
    source = model.input
    if source not in ("i", "voltage"):
        raise DataValidationError("input", f"expected 'i' or 'voltage', got {source!r}")


def check_settings(est: Any) -> None:
    """The number checks of the settings every output-error estimator has."""
    for name in ("n_starts", "max_nfev", "screen_nfev"):
        check_int(name, getattr(est, name), 1)
    check_int("substeps", est.substeps, 0)
    check_number("step_tolerance", est.step_tolerance, what="a positive finite number (ESR units)")


def regression(recs: Sequence[Record]) -> np.ndarray:
    """Weighted least squares of F on [tanh(v/v_eps), e tanh, v, e v, x, 1]."""
    rows, rhs = [], []
    for r in recs:
        veps = 0.05 * max(r.vmax, 1e-9)
        s = np.tanh(r.v / veps)
        X = np.column_stack([s, r.e * s, r.v, r.e * r.v, r.x, np.ones_like(r.x)])
        rows.append(X * r.weight)
        rhs.append(r.F * r.weight)
    X = np.vstack(rows)
    y = np.concatenate(rhs)
    # the electrical columns are exactly collinear with the others when e is one constant value
    coef, *_ = np.linalg.lstsq(X, y, rcond=1e-10)
    return np.asarray(coef)


def strictly_inside(q: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``q`` moved strictly inside ``[lo, hi]`` (the optimiser starts from an interior point)."""
    q = q.copy()
    width = np.where(np.isfinite(hi - lo), hi - lo, np.inf)
    pad = np.minimum(1e-6 * np.maximum(np.abs(q), 1.0), 0.01 * width)
    q = np.maximum(q, lo + pad)
    inside: np.ndarray = np.minimum(q, hi - pad)  # annotated: numpy's stubs return Any here
    return inside


#: ``simulate(record, p) -> (F, status, sample)``: a record's free run (status 0: ok).
Simulate = Callable[[Record, np.ndarray], tuple[np.ndarray, int, int]]


class FreeRunObjective:
    """Weighted free-run residuals of the scaled free unknowns ``q``.

    Parameters
    ----------
    recs : list of Record
        The training records.
    params : callable
        ``params(q) -> p``: the parameter vector the simulation reads.
    simulate : callable
        ``simulate(record, p) -> (F, status, sample)``.
    """

    def __init__(
        self,
        recs: list[Record],
        params: Callable[[np.ndarray], np.ndarray],
        simulate: Simulate,
    ) -> None:
        self.recs = recs
        self.params = params
        self.simulate = simulate
        self.n = recs[-1].sl.stop
        self.nfev = 0
        self.failures = 0
        self.last_failure = ""

    def residuals(self, q: np.ndarray) -> np.ndarray:
        """Stacked weighted residuals; :data:`PENALTY` everywhere when a simulation fails."""
        self.nfev += 1
        p = self.params(q)
        out = np.empty(self.n)
        for r in self.recs:
            F, status, sample = self.simulate(r, p)
            if status != 0:
                self.failures += 1
                self.last_failure = f"record {r.name!r}: status {status} at sample {sample}"
                return np.full(self.n, PENALTY)
            out[r.sl] = r.weight * (F - r.F)
        return out


@dataclass(frozen=True)
class FitOutcome:
    """What :func:`multistart` found.

    Attributes
    ----------
    final : scipy.optimize.OptimizeResult
        The result of the best start after its final run.
    provenance : dict
        The fit's record: starts, cost, per-record ESR, evaluations, status, conditioning,
        parameters at their bounds (by name), simulation failures.
    """

    final: OptimizeResult
    provenance: dict[str, Any]


def multistart(
    obj: FreeRunObjective,
    starts: Sequence[np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    free: Sequence[str],
    *,
    kind: str,
    settings: OutputErrorSettings,
    jac: Any,
    options: Mapping[str, Any],
) -> FitOutcome:
    """Screen every start, continue the best to convergence and check the result.

    Parameters
    ----------
    obj : FreeRunObjective
        The residuals.
    starts : sequence of ndarray
        Start points in scaled unknowns (moved strictly inside the bounds here).
    lo, hi : ndarray
        Bounds of the scaled unknowns.
    free : sequence of str
        Names of the unknowns (for ``at_bounds``).
    kind : str
        Kind named in errors and warnings.
    settings
        ``n_starts``, ``screen_nfev`` and ``max_nfev``.
    jac : callable or str
        Jacobian of the residuals, or the finite-difference scheme of ``least_squares``.
    options : mapping
        Further ``least_squares`` options (tolerances, ``x_scale``).

    Raises
    ------
    IdentificationError
        Every start diverged, or the optimiser returned a non-finite result.
    """
    kw: dict[str, Any] = {"bounds": (lo, hi), "method": "trf", **options}
    runs: list[dict[str, Any]] = []
    results = []
    for k, q in enumerate(starts):
        q0 = strictly_inside(q, lo, hi)
        r0 = obj.residuals(q0)
        if obj.last_failure and np.all(r0 == PENALTY):
            runs.append(
                {
                    "start": k,
                    "cost": math.inf,
                    "status": "start diverged",
                    "detail": obj.last_failure,
                }
            )
            obj.last_failure = ""
            continue
        nfev = settings.screen_nfev if settings.n_starts > 1 else settings.max_nfev
        stage = f"start {k + 1} of {len(starts)}: " if len(starts) > 1 else ""
        # the evaluation budget counts the calls of the residuals when the Jacobian is analytic
        residuals = counted(
            obj.residuals, stage + "least squares: evaluation", nfev if callable(jac) else None
        )
        res = least_squares(residuals, q0, jac=jac, max_nfev=nfev, **kw)
        runs.append(
            {"start": k, "cost": float(res.cost), "nfev": int(res.nfev), "status": int(res.status)}
        )
        results.append(res)
    finite = [r for r in results if np.isfinite(r.cost) and r.cost < 0.25 * PENALTY**2 * obj.n]
    if not finite:
        raise IdentificationError(
            f"{kind}: every one of {len(starts)} start(s) diverged or failed "
            f"(last failure: {obj.last_failure or 'n/a'}); give 'start' values or wider 'bounds'"
        )
    best = min(finite, key=lambda r: r.cost)
    final = best
    if settings.n_starts > 1:
        residuals = counted(
            obj.residuals,
            "best start: least squares: evaluation",
            settings.max_nfev if callable(jac) else None,
        )
        final = least_squares(residuals, best.x, jac=jac, max_nfev=settings.max_nfev, **kw)
        if not final.cost <= best.cost:
            final = best
    if not np.all(np.isfinite(final.x)) or not math.isfinite(final.cost):
        raise IdentificationError(
            f"{kind}: optimiser returned a non-finite result ({final.message})"
        )
    sv = np.linalg.svd(final.jac, compute_uv=False)
    cond = float((sv[0] / sv[-1]) ** 2) if sv[-1] > 0 else math.inf
    ill = not cond < COND_WARNING
    converged = bool(final.status > 0)
    if ill:
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
    rec_esr = {
        r.name: float(np.mean((resid[r.sl] / r.weight) ** 2) / np.var(r.F)) for r in obj.recs
    }
    provenance: dict[str, Any] = {
        "records": [r.name for r in obj.recs],
        "n_samples": int(obj.n),
        "starts": runs,
        "cost": float(final.cost),
        "mean_record_esr": float(np.mean(list(rec_esr.values()))),
        "record_esr": rec_esr,
        "nfev_total": int(obj.nfev),
        "status": int(final.status),
        "message": str(final.message),
        "converged": converged,
        "optimality": float(final.optimality),
        "cond_JTJ": cond,
        "ill_conditioned": ill,
        "at_bounds": [free[int(j)] for j in np.flatnonzero(final.active_mask)],
        "simulation_failures": int(obj.failures),
    }
    return FitOutcome(final, provenance)


class _CheckedModel(Protocol):
    """A fitted model whose RK4 sub-steps can be set (a frozen dataclass)."""

    __dataclass_fields__: ClassVar[dict[str, Any]]

    @property
    def substeps(self) -> int: ...

    def substeps_for(self, experiment: Experiment) -> int: ...

    def predict(self, experiment: Experiment) -> np.ndarray: ...


def fit_and_check(
    kind: str,
    data: TrainingData,
    fit: Callable[[ExperimentSet], tuple[dict[str, Any], _CheckedModel, dict[str, Any]]],
    step_tolerance: float,
) -> Identified:
    """Fit on the training records (evenly spread windows of a long campaign), then check the
    fitted model: its free run must not change when the RK4 step is halved
    (``provenance["step_check"]``), and a windowed fit is scored on all the data
    (``provenance["full_data_check"]``).

    Parameters
    ----------
    kind : str
        Kind named in the step check's warning.
    data : TrainingData
        The training records.
    fit : callable
        ``fit(records) -> (parameters, model, provenance)``.
    step_tolerance : float
        Largest change of a free run when the step is halved (ESR units).
    """
    exps, windows = _scale.window_set(data.records, budget=_scale.WINDOW_BUDGET_SPENCER)
    parameters, model, provenance = fit(exps)
    report("step-size check")
    provenance["step_check"] = step_halving_check(
        kind,
        exps,
        lambda e, k: dataclasses.replace(model, substeps=k * model.substeps_for(e)).predict(e),
        step_tolerance,
    )
    if windows is not None:
        provenance["windows"] = windows
        report("full-data check")
        provenance["full_data_check"] = _scale.full_data_esr(model, data.records)
    return Identified(parameters=parameters, provenance=provenance)
