"""LPV input-output damper model (paper eqs. 7-9, 16-22) and its LTI counterpart.

Discrete transfer function of order ``n_m`` whose coefficients are polynomials of degree ``n_rho``
in the scheduling variable ``rho`` (frozen-coefficient form, reading notes items 3-4)::

    F[k] = y[k] + F0
    y[k] = -sum_{j=1..n_m} a_j(rho[k]) y[k-j] + sum_{j=1..n_m} b_j(rho[k]) u[k-j]     (b0 = 0)
    a_j(rho) = sum_p alpha[j-1, p] rho^p,   b_j(rho) = sum_p beta[j-1, p] rho^p

``rho`` is the electrical input (``input="i"`` coil current [A], or ``"voltage"`` [V]), optionally
through a first-order drive lag ``d rho/dt = -eta (rho - input)``. ``u`` is the scheduling input of
:mod:`mrdamper.analysis` built from the model's :class:`~mrdamper.analysis.ZoneLaws`
(``input_signal="u"``), or the raw velocity (``input_signal="v"``, ablation). The model works at
its own sampling rate ``fs``; records at another rate are resampled on the way in and the force is
interpolated back. Free run starts from rest (zero initial conditions) in every record.

The LTI model (kind ``"lti"``) is the same structure with ``n_rho = 0`` (no scheduling of the
coefficients; paper Fig. 4).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import InitVar, dataclass, field
from typing import Any, ClassVar, Literal

import numpy as np
import pandas as pd

from mrdamper.analysis import ZoneLaws, fit_zone_laws, zone_fits_binned
from mrdamper.analysis.scheduling import Reading
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _lpv_fit, _lpv_inputs, _scale
from mrdamper.models import _lpv_kernels as K
from mrdamper.models._rates import model_rate, rename_setting, to_model_rate, to_record_rate
from mrdamper.models.base import Estimator, FittedModel, single_level, single_level_note
from mrdamper.models.registry import register

__all__ = ["LPVEstimator", "LPVModel", "LTIEstimator", "LTIModel", "select_order"]

InputSignal = Literal["u", "v", "hysteretic"]


# ----------------------------------------------------------------------------- signal helpers
def _distinct_levels(rho: np.ndarray, tol: float) -> int:
    r = np.sort(rho)
    return int(1 + np.count_nonzero(np.diff(r) > tol))


# ----------------------------------------------------------------------------- fitted models
@dataclass(frozen=True)
class LPVModel(FittedModel):
    """Identified LPV input-output damper model (immutable).

    Attributes
    ----------
    alpha, beta : ndarray, shape (n_m, n_rho + 1)
        Denominator / numerator polynomial coefficients (eq. 9): row ``j-1`` holds ``a_j`` /
        ``b_j``; column p multiplies ``rho**p``. ``beta`` maps ``u`` [m/s] to force [N].
    offset : float
        Output force offset ``F0`` [N].
    fs : float
        Sampling rate the discrete model runs at [Hz].
    input_signal : {"u", "v", "hysteretic"}
        LPV input: the scheduling input of the zone laws, the raw velocity, or the zone-law input
        with a hysteretic pre-yield state (:mod:`mrdamper.analysis.hysteretic`).
    stroke, blend : float or None
        Stroke scale [m] and pre-yield share [-] of the hysteretic input (None otherwise).
    reading : {"continuous", "literal"}
        Reading of eq. (22) used to build ``u``.
    zone_laws : ZoneLaws or None
        Laws used to build ``u`` (None when ``input_signal="v"``).
    eta : float or None
        Drive-lag rate of the scheduling filter [1/s]; None: ``rho`` is the electrical input.
    rho_range : (float, float)
        Range of ``rho`` seen in training.
    force_bound : float
        Free-run output magnitude regarded as divergence [N].
    """

    kind: ClassVar[str] = "lpv"

    alpha: np.ndarray = field(default_factory=lambda: np.zeros((1, 1)))
    beta: np.ndarray = field(default_factory=lambda: np.zeros((1, 1)))
    offset: float = 0.0
    fs: float = 1.0
    input_signal: InputSignal = "u"
    reading: Reading = "continuous"
    zone_laws: ZoneLaws | None = None
    eta: float | None = None
    rho_range: tuple[float, float] = (0.0, 0.0)
    force_bound: float = 1e9
    stroke: float | None = None
    blend: float | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        _lpv_inputs.check_model(self)  # hysteretic input: stroke and blend
        set_ = object.__setattr__
        for name in ("alpha", "beta"):
            arr = np.array(getattr(self, name), dtype=np.float64)
            if arr.ndim != 2:
                raise DataValidationError(
                    name, f"expected a 2-D (n_m, n_rho+1) array, got shape {arr.shape}"
                )
            arr.setflags(write=False)
            set_(self, name, arr)
        if self.alpha.shape != self.beta.shape:
            raise DataValidationError(
                "beta", f"shape {self.beta.shape} differs from alpha {self.alpha.shape}"
            )
        if isinstance(self.zone_laws, Mapping):
            set_(self, "zone_laws", ZoneLaws.from_dict(self.zone_laws))
        if self.input_signal not in ("u", "v", "hysteretic"):
            raise DataValidationError(
                "input_signal", f"expected 'u', 'v' or 'hysteretic', got {self.input_signal!r}"
            )
        if self.input_signal != "v" and self.zone_laws is None:
            raise DataValidationError(
                "zone_laws", f"input_signal={self.input_signal!r} needs zone laws to build u"
            )
        if not self.fs > 0:
            raise DataValidationError("fs", f"expected a positive rate [Hz], got {self.fs}")
        set_(self, "offset", float(self.offset))
        set_(self, "fs", float(self.fs))
        set_(self, "rho_range", tuple(float(b) for b in self.rho_range))
        if self.eta is not None:
            set_(self, "eta", float(self.eta))

    # --- structure -----------------------------------------------------------------------
    @property
    def n_m(self) -> int:
        """Model order (number of lags)."""
        return int(self.alpha.shape[0])

    @property
    def n_rho(self) -> int:
        """Polynomial degree of the coefficients in ``rho``."""
        return int(self.alpha.shape[1] - 1)

    @property
    def parameters(self) -> dict[str, Any]:
        """Model parameters, with the zone laws as a plain dict (JSON-safe)."""
        p = super().parameters
        p["zone_laws"] = None if self.zone_laws is None else self.zone_laws.to_dict()
        return p

    def a(self, rho: Any) -> np.ndarray:
        """Denominator coefficients ``a_1..a_n`` at ``rho``; shape ``rho.shape + (n_m,)``."""
        r = np.asarray(rho, dtype=float)
        return (r[..., None, None] ** np.arange(self.n_rho + 1) * self.alpha).sum(-1)

    def b(self, rho: Any) -> np.ndarray:
        """Numerator coefficients ``b_1..b_n`` at ``rho`` [N s/m]; shape ``rho.shape + (n_m,)``."""
        r = np.asarray(rho, dtype=float)
        return (r[..., None, None] ** np.arange(self.n_rho + 1) * self.beta).sum(-1)

    # --- signals -------------------------------------------------------------------------
    def scheduling_variable(self, experiment: Experiment) -> np.ndarray:
        """``rho`` at the record's own rate (range policy applied to the electrical input)."""
        e = self.electrical_input(experiment)
        if self.eta is not None:
            e = K.first_order_lag(
                np.ascontiguousarray(e, dtype=np.float64), experiment.dt, self.eta
            )
        return np.asarray(e, dtype=np.float64)

    def model_signals(self, experiment: Experiment) -> tuple[np.ndarray, np.ndarray]:
        """``(u, rho)`` at the model rate ``fs`` for one record."""
        rho = to_model_rate(self.scheduling_variable(experiment), experiment.fs, self.fs)
        v = to_model_rate(np.asarray(experiment.v), experiment.fs, self.fs)
        if self.input_signal == "v":
            u = v
        elif self.input_signal == "hysteretic":
            u = _lpv_inputs.model_input(self, v, rho)
        elif self.zone_laws is None:  # excluded by __post_init__; kept for type narrowing
            raise DataValidationError("zone_laws", "input_signal='u' needs zone laws to build u")
        else:
            u = self.zone_laws.scheduling_input(v, rho, reading=self.reading)
        return np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(
            rho, dtype=np.float64
        )

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force [N] from the record's velocity and electrical input.

        Raises
        ------
        SimulationDivergedError
            If the output becomes non-finite or exceeds ``force_bound``.
        """
        u, rho = self.model_signals(experiment)
        y, bad = K.simulate_record(u, rho, self.alpha, self.beta, self.force_bound)
        if bad >= 0:
            raise SimulationDivergedError(
                self.kind,
                int(bad),
                f"|y| exceeded {self.force_bound:.3g} N or became non-finite in record "
                f"{experiment.name!r} (model rate {self.fs:g} Hz); frozen poles: "
                f"max |z| = {self.max_pole_modulus():.4f} over rho in {self.rho_range}",
            )
        return to_record_rate(y + self.offset, self.fs, experiment)

    # --- stability -----------------------------------------------------------------------
    def frozen_poles(self, rho: Any = None, n_grid: int = 51) -> np.ndarray:
        """Poles of the frozen-``rho`` denominators; shape ``(len(rho), n_m)``.

        ``rho`` defaults to ``n_grid`` points over ``rho_range``.
        """
        grid = (
            np.linspace(*self.rho_range, n_grid)
            if rho is None
            else np.atleast_1d(np.asarray(rho, float))
        )
        return _lpv_fit.frozen_poles(self.alpha, grid)

    def max_pole_modulus(self, n_grid: int = 51) -> float:
        """Largest frozen-pole modulus over ``rho_range`` [-] (< 1: frozen-stable)."""
        p = self.frozen_poles(n_grid=n_grid)
        return float(np.max(np.abs(p))) if p.size else 0.0

    def is_frozen_stable(self, n_grid: int = 51) -> bool:
        """True when every frozen-``rho`` model on the grid has all poles inside the unit circle.

        Frozen stability is necessary, not sufficient, for stability under fast-varying ``rho``.
        """
        return self.max_pole_modulus(n_grid) < 1.0

    def coefficients_frame(self) -> pd.DataFrame:
        """Table of ``alpha`` and ``beta`` (rows ``a_j`` / ``b_j``, columns ``rho^p``)."""
        rows = [("a", j + 1, *self.alpha[j]) for j in range(self.n_m)]
        rows += [("b", j + 1, *self.beta[j]) for j in range(self.n_m)]
        return pd.DataFrame(
            rows, columns=["coef", "lag", *[f"rho^{p}" for p in range(self.n_rho + 1)]]
        )


@dataclass(frozen=True)
class LTIModel(LPVModel):
    """The LPV structure without scheduling of the coefficients (``n_rho = 0``)."""

    kind: ClassVar[str] = "lti"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.alpha.shape[1] != 1:
            raise DataValidationError(
                "alpha", f"an LTI model has n_rho = 0; got {self.alpha.shape[1] - 1}"
            )


# ----------------------------------------------------------------------------- estimators
@dataclass
class LPVEstimator(Estimator):
    """Identify an :class:`LPVModel` from training records (settings only).

    Parameters
    ----------
    n_m : int
        Model order.
    n_rho : int
        Polynomial degree of the coefficients in ``rho``.
    input : {"i", "voltage"}
        Electrical input used as scheduling variable.
    eta : float, optional
        Drive-lag rate [1/s] of a first-order filter on the electrical input (e.g. command
        voltage). None: ``rho`` is the electrical input itself.
    input_signal : {"hysteretic", "u", "v"}
        LPV input: the zone-law input with a hysteretic pre-yield state (default,
        :mod:`mrdamper.analysis.hysteretic`), the paper's static zone-law input ``u`` (needed by
        the inverse and the state-space / C exports), or the raw velocity (ablation).
    stroke, blend : float, optional
        Stroke scale [m] and pre-yield share [-] of the hysteretic input; when either is None
        it is chosen on the training records (lowest mean free-run training ESR over a grid).
    reading : {"continuous", "literal"}
        Reading of eq. (22).
    zone_laws : ZoneLaws, optional
        Laws to use; by default they are fitted on the training records.
    laws_by : {"auto", "current", "plateaus", "bins"}
        How the laws are fitted: records grouped by metadata ``current``, constant plateaus of
        the electrical input, or bins of ``rho``. ``"auto"``: ``"current"`` if every record has it,
        ``"bins"`` if none has it (noted in the provenance as ``laws_note``); a mix is refused
        (name the method).
    laws_degree : int
        Degree of the slope/intercept laws (2 in the paper).
    n_bins : int
        Number of ``rho`` bins for ``laws_by="bins"``.
    model_fs : float, optional
        Model rate [Hz]; default: the lowest sampling rate of the training records (records at
        other rates are resampled, with a note). ``fs`` is its old name, still accepted.
    offset : bool
        Estimate an output force offset ``F0``.
    weighting : {"esr", "sse"}
        ``"esr"`` weights each record by ``1 / (n var F)`` so all records count equally (as in
        the mean ESR); ``"sse"`` weights every sample equally.
    refine : bool
        Output-error refinement (free-run error) from the least-squares start.
    max_nfev : int
        Iteration budget of the refinement.
    oe_solver : {"gauss-newton", "least_squares"}
        Refinement solver: Levenberg-Marquardt on kernel-accumulated normal equations (fast), or
        ``scipy.optimize.least_squares`` with the stored analytic Jacobian (slower).
    range_policy : {"error", "warn", "clip", "ignore"}
        Stored in the fitted model.
    stability : {"enforce", "warn"}
        ``"enforce"`` (default): the output-error refinement is constrained to frozen stability
        over the identified ``rho`` range (every frozen pole of modulus below 0.999 on a
        101-point grid) and the fit refuses, naming the pole, when the returned model would not be
        frozen-stable. ``"warn"``: unconstrained refinement; an unstable result only warns.
    """

    kind: ClassVar[str] = "lpv"
    model_cls: ClassVar[type[LPVModel]] = LPVModel

    n_m: int = 3
    n_rho: int = 2
    input: Literal["i", "voltage"] = "i"
    eta: float | None = None
    input_signal: InputSignal = "hysteretic"
    reading: Reading = "continuous"
    zone_laws: ZoneLaws | None = None
    laws_by: Literal["auto", "current", "plateaus", "bins"] = "auto"
    laws_degree: int = 2
    n_bins: int = 5
    model_fs: float | None = None
    offset: bool = True
    weighting: Literal["esr", "sse"] = "esr"
    refine: bool = True
    max_nfev: int = 60
    oe_solver: Literal["gauss-newton", "least_squares"] = "gauss-newton"
    range_policy: Literal["error", "warn", "clip", "ignore"] = "error"
    stability: Literal["enforce", "warn"] = "enforce"
    stroke: float | None = None
    blend: float | None = None
    fs: InitVar[float | None] = None

    renamed_settings: ClassVar[Mapping[str, str]] = {"fs": "model_fs"}

    def __post_init__(self, fs: float | None) -> None:
        self.model_fs = rename_setting(self.kind, "fs", "model_fs", fs, self.model_fs)  # type: ignore[assignment]

    def _validate(self) -> None:
        for name in ("n_m", "n_rho", "laws_degree", "n_bins", "max_nfev"):
            val = getattr(self, name)
            if not isinstance(val, (int, np.integer)) or isinstance(val, bool) or val < 0:
                raise DataValidationError(name, f"expected a non-negative integer, got {val!r}")
        if self.n_m < 1:
            raise DataValidationError("n_m", f"expected an order of at least 1, got {self.n_m}")
        choices = {
            "input": ("i", "voltage"),
            "input_signal": ("u", "v", "hysteretic"),
            "reading": ("continuous", "literal"),
            "laws_by": ("auto", "current", "plateaus", "bins"),
            "weighting": ("esr", "sse"),
            "oe_solver": ("gauss-newton", "least_squares"),
            "range_policy": ("error", "warn", "clip", "ignore"),
            "stability": ("enforce", "warn"),
        }
        for name, ok in choices.items():
            if getattr(self, name) not in ok:
                raise DataValidationError(
                    name, f"expected one of {ok}, got {getattr(self, name)!r}"
                )
        if self.eta is not None and not (np.isfinite(self.eta) and self.eta > 0):
            raise DataValidationError(
                "eta", f"expected a positive drive-lag rate [1/s], got {self.eta!r}"
            )
        mfs = self.model_fs
        if mfs is not None and (
            isinstance(mfs, bool)
            or not isinstance(mfs, (int, float))
            or not (np.isfinite(mfs) and mfs > 0)
        ):
            raise DataValidationError(
                "model_fs", f"expected a positive model rate [Hz], got {mfs!r}"
            )

    def _laws(
        self,
        exps: Sequence[Experiment],
        rhos: list[np.ndarray],
        prov: dict[str, Any],
        single: bool = False,
    ) -> ZoneLaws | None:
        if self.input_signal == "v":
            return None
        if self.zone_laws is not None:
            return self.zone_laws
        by = self.laws_by
        if by == "auto":
            lacking = [e.name for e in exps if "current" not in e.metadata]
            if lacking and len(lacking) < len(exps):
                raise DataValidationError(
                    "laws_by",
                    f"'auto' needs metadata 'current' on every record or on none; {len(lacking)} of "
                    f"{len(exps)} records lack it (first: {lacking[0]!r}); set laws_by='bins' or "
                    f"'plateaus', or give the laws (zone_laws=)",
                )
            by = "bins" if lacking else "current"
            if lacking:
                prov["laws_note"] = (
                    "laws_by='auto': no record carries metadata 'current'; laws fitted on rho bins"
                )
        if by == "bins":
            v, F, r = _scale.strided(
                [[e.v for e in exps], [e.F for e in exps], rhos]
            )  # long campaigns
            fits = zone_fits_binned(v, F, r, n_bins=self.n_bins)
            return fit_zone_laws(fits, degree=min(self.laws_degree, max(len(fits) - 1, 0)))
        return fit_zone_laws(
            exps, degree=0 if single else self.laws_degree, by=by, source=self.input
        )

    def fit(
        self,
        data: Experiment | Iterable[Experiment],
        *,
        record_weights: Sequence[float] | None = None,
    ) -> LPVModel:
        """Identify the model from one record or a collection (records keep their own start).

        Parameters
        ----------
        data : Experiment or iterable of Experiment
            Training records.
        record_weights : sequence of float, optional
            One non-negative weight per record [-], multiplying that record's share of the
            least-squares and output-error costs (on top of ``weighting``); e.g. to mix measured
            records with synthetic ones without duplicating records. Default: all 1.

        Raises
        ------
        IdentificationError
            Rank-deficient regression, too few scheduling levels for ``n_rho``, or (with
            ``stability="enforce"``) no frozen-stable model; the message names the pole.
        """
        self._validate()
        exps = self._as_set(data)
        if _lpv_inputs.needs_choice(self):  # hysteretic input: stroke / blend on training data
            return _lpv_inputs.fit_choosing(self, exps, record_weights)
        user_w = _record_weights(record_weights, len(exps))
        fs = model_rate([e.fs for e in exps], self.model_fs, self.kind)
        raw = [np.asarray(e.electrical(self.input), dtype=np.float64) for e in exps]
        in_range = (min(float(r.min()) for r in raw), max(float(r.max()) for r in raw))
        rhos = [
            K.first_order_lag(r, e.dt, self.eta) if self.eta is not None else r
            for r, e in zip(raw, exps)
        ]
        prov: dict[str, Any] = {}
        level = single_level(np.array([_scale.extrema(r) for r in rhos]))  # no concatenated copy
        laws = self._laws(exps, rhos, prov, single=level is not None)
        proto = self.model_cls(
            alpha=np.zeros((self.n_m, self.n_rho + 1)),
            beta=np.zeros((self.n_m, self.n_rho + 1)),
            fs=fs,
            input_signal=self.input_signal,
            reading=self.reading,
            zone_laws=laws,
            eta=self.eta,
            input=self.input,
            input_range=in_range,
            range_policy="ignore",
            **_lpv_inputs.model_settings(self),
        )
        F, U, R, w = [], [], [], []
        for e in exps:
            u, rho = proto.model_signals(e)
            Fr = np.ascontiguousarray(to_model_rate(np.asarray(e.F), e.fs, fs), dtype=np.float64)
            e.require_samples(self.n_m + 2, "LPV identification")
            F.append(Fr)
            U.append(u)
            R.append(rho)
            var = float(np.var(Fr))
            w.append(1.0 / (Fr.size * var) if self.weighting == "esr" and var > 0 else 1.0)
        weights = np.asarray(w) * user_w
        weights = weights / weights.mean()
        rho_range = _scale.input_range_of(R)
        tol = 1e-9 * max(1.0, abs(rho_range[1]))
        long = sum(r.size for r in R) > _scale.WINDOW_THRESHOLD  # long campaigns: record by record
        n_lev = _scale.distinct_levels(R, tol) if long else _distinct_levels(np.concatenate(R), tol)
        n_p = self.n_rho + 1
        reduced_laws = self.input_signal != "v" and self.zone_laws is None and self.laws_degree > 0
        if level is not None and (n_p > 1 or reduced_laws):
            n_p = 1  # one level: coefficients and laws are constants (higher powers exactly 0)
            prov["note"] = single_level_note(self.kind, self.input, level)
            warnings.warn(prov["note"], UserWarning, stacklevel=2)
        elif n_lev < n_p:
            raise IdentificationError(
                f"{self.kind}: rho takes {n_lev} distinct value(s) in the training data; degree "
                f"n_rho={self.n_rho} needs at least {self.n_rho + 1} (use more current levels or lower n_rho)"
            )
        rec = _lpv_fit.Records(F=F, u=U, rho=R, weights=weights)
        ls = _lpv_fit.ls_identify(rec, self.n_m, n_p, self.offset)
        f_scale = max(max(float(np.max(np.abs(f))) for f in F), 1.0)
        bound = 1e3 * f_scale
        theta, F0 = ls.theta, ls.offset
        prov.update(
            {
                "training_records": list(exps.names),
                "n_samples": int(sum(a.size for a in F)),
                "settings": _settings_dict(self),
                "ls_solver": ls.solver,
                "ls_condition_number": ls.cond,
            }
        )
        if record_weights is not None:
            prov["record_weights"] = [float(x) for x in user_w]
        enforce = self.stability == "enforce"
        grid = np.linspace(*rho_range, _lpv_fit.STABILITY_GRID)
        ls_cost = _cost(rec, theta, F0, self.n_m, n_p, bound)
        prov["ls_free_run_cost"] = ls_cost
        if self.refine:
            theta0, shrink = _stable_start(theta, self.n_m, n_p, rho_range, rec, F0, bound)
            if shrink != 1.0:
                prov["oe_start_pole_scaling"] = shrink
            rec_oe, windows = _scale.window_records(
                rec, fs
            )  # long campaigns: evenly spread windows
            th_r, f0_r, sol = _lpv_fit.refine_output_error(
                rec_oe,
                theta0,
                F0,
                self.n_m,
                n_p,
                offset=self.offset,
                bound=bound,
                max_nfev=self.max_nfev,
                solver=self.oe_solver,
                rho_grid=grid if enforce else None,
            )
            oe_cost = _cost(rec, th_r, f0_r, self.n_m, n_p, bound)
            prov.update(oe_cost=oe_cost, oe_nfev=int(sol.nfev), oe_status=int(sol.status))
            if windows is not None:
                prov.update(
                    oe_windows=windows, full_data_check={"ls_cost": ls_cost, "oe_cost": oe_cost}
                )
            ls_ok = not enforce or _pole(theta, self.n_m, n_p, grid)[0] < 1.0
            if oe_cost < ls_cost or not ls_ok:
                theta, F0 = th_r, f0_r
                if oe_cost >= ls_cost:
                    prov["oe_note"] = (
                        "least-squares model has a lower free-run cost but is not frozen-stable; "
                        "refined (frozen-stable) model kept"
                    )
            else:
                prov["oe_note"] = (
                    "refinement did not lower the free-run cost; least-squares model kept"
                )
        pmax, rho_at, pole = _pole(theta, self.n_m, n_p, grid)
        if enforce and not pmax < 1.0:
            raise IdentificationError(
                f"{self.kind}: no frozen-stable model: frozen pole z = {pole.real:.4f}{pole.imag:+.4f}j "
                f"(|z| = {pmax:.4f}) at rho = {rho_at:.4g} of the identified range "
                f"[{rho_range[0]:.4g}, {rho_range[1]:.4g}]"
                + (
                    ""
                    if self.refine
                    else "; the least-squares estimate is unstable, set refine=True"
                )
                + " (stability='warn' returns it with a warning)"
            )
        alpha, beta = (
            np.pad(c, ((0, 0), (0, self.n_rho + 1 - n_p)))
            for c in _lpv_fit.split_theta(theta, self.n_m, n_p)
        )
        model = self.model_cls(
            alpha=alpha,
            beta=beta,
            offset=F0,
            fs=fs,
            input_signal=self.input_signal,
            reading=self.reading,
            zone_laws=laws,
            eta=self.eta,
            rho_range=rho_range,
            force_bound=bound,
            input=self.input,
            input_range=in_range,
            range_policy=self.range_policy,
            provenance=prov,
            **_lpv_inputs.model_settings(self),
        )
        prov.update(max_frozen_pole=pmax, frozen_stable=pmax < 1.0)
        if pmax >= 1.0:
            warnings.warn(
                f"{self.kind}: identified model is not frozen-stable over rho in "
                f"[{rho_range[0]:.4g}, {rho_range[1]:.4g}] "
                f"(max frozen pole modulus {pmax:.4f} at rho = {rho_at:.4g})",
                RuntimeWarning,
                stacklevel=2,
            )
        return model


def _pole(theta: np.ndarray, n_m: int, n_p: int, grid: np.ndarray) -> tuple[float, float, complex]:
    return _lpv_fit.largest_frozen_pole(_lpv_fit.split_theta(theta, n_m, n_p)[0], grid)


def _record_weights(weights: Sequence[float] | None, n: int) -> np.ndarray:
    """Validated per-record weights (all 1 when None)."""
    if weights is None:
        return np.ones(n)
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (n,):
        raise DataValidationError(
            "record_weights", f"expected {n} weights (one per record), got shape {w.shape}"
        )
    if not np.all(np.isfinite(w)) or np.any(w < 0) or not np.any(w > 0):
        raise DataValidationError(
            "record_weights", f"expected finite weights >= 0, not all zero, got {w.tolist()}"
        )
    return w


def _stable_start(
    theta: np.ndarray,
    n_m: int,
    n_p: int,
    rho_range: tuple[float, float],
    rec: _lpv_fit.Records,
    F0: float,
    bound: float,
) -> tuple[np.ndarray, float]:
    """Start for the refinement whose free run stays bounded on the training records.

    An equation-error estimate can be frozen-unstable. Scaling ``a_j`` by ``lambda**j`` scales
    every frozen pole by ``lambda``, so ``lambda = 0.98 / max|pole|`` (then smaller, if the
    time-varying run still diverges) gives a frozen-stable start with the same pole pattern.
    """
    alpha, beta = _lpv_fit.split_theta(theta, n_m, n_p)
    pmax = _lpv_fit.largest_frozen_pole(alpha, np.linspace(*rho_range, _lpv_fit.STABILITY_GRID))[0]
    lam = 1.0 if pmax < _lpv_fit.STABILITY_LIMIT else 0.98 / pmax
    for _ in range(20):
        al = alpha * (lam ** np.arange(1, n_m + 1))[:, None]
        th = np.r_[al.ravel(), beta.ravel()]
        if np.isfinite(_cost(rec, th, F0, n_m, n_p, bound)):
            return th, lam
        lam *= 0.95
    raise IdentificationError(
        "lpv: no bounded free run found from the least-squares estimate; try a lower order n_m"
    )


def _cost(
    rec: _lpv_fit.Records, theta: np.ndarray, F0: float, n_m: int, n_p: int, bound: float
) -> float:
    alpha, beta = _lpv_fit.split_theta(theta, n_m, n_p)
    total = 0.0
    for r in range(len(rec.u)):
        y, bad = K.simulate_record(rec.u[r], rec.rho[r], alpha, beta, bound)
        if bad >= 0:
            return float("inf")
        e = y + F0 - rec.F[r]
        total += rec.weights[r] * float(e @ e)
    return total


def _settings_dict(est: Estimator) -> dict[str, Any]:
    out = {}
    for f in dataclasses.fields(est):  # type: ignore[arg-type]
        val = getattr(est, f.name)
        out[f.name] = "given" if isinstance(val, ZoneLaws) else val
    return out


@dataclass
class LTIEstimator(LPVEstimator):
    """Identify an :class:`LTIModel`: the LPV estimator with ``n_rho = 0``."""

    kind: ClassVar[str] = "lti"
    model_cls: ClassVar[type[LPVModel]] = LTIModel
    n_rho: int = 0

    def _validate(self) -> None:
        super()._validate()
        if self.n_rho != 0:
            raise DataValidationError("n_rho", f"an LTI model has n_rho = 0, got {self.n_rho}")


register(LPVEstimator, LPVModel)
register(LTIEstimator, LTIModel)


# ----------------------------------------------------------------------------- order selection
def select_order(
    train: Experiment | Iterable[Experiment],
    validation: Experiment | Iterable[Experiment],
    *,
    orders: Sequence[int] = (1, 2, 3, 4),
    rho_degrees: Sequence[int] = (0, 1, 2),
    **settings: Any,
) -> pd.DataFrame:
    """Fit every ``(n_m, n_rho)`` on ``train`` and score it in free run on ``validation``.

    Returns
    -------
    DataFrame
        One row per candidate: ``n_m, n_rho, n_params, train_esr, val_esr, val_ssse``
        (mean over records), ``max_frozen_pole`` and ``error`` (message when the fit or a
        simulation failed; scores are NaN then). Sorted by ``val_esr``.
    """
    from mrdamper.data import as_experiment_set

    tr = as_experiment_set(train, name="train")
    va = as_experiment_set(validation, name="validation")
    rows = []
    for n_m in orders:
        for n_rho in rho_degrees:
            row: dict[str, Any] = {"n_m": n_m, "n_rho": n_rho, "n_params": 2 * n_m * (n_rho + 1)}
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    m = LPVEstimator(n_m=n_m, n_rho=n_rho, **settings).fit(tr)
                    row["train_esr"] = float(np.mean([m.score(e).esr for e in tr]))
                    sc = [m.score(e) for e in va]
                row.update(
                    val_esr=float(np.mean([s.esr for s in sc])),
                    val_ssse=float(np.mean([s.ssse for s in sc])),
                    max_frozen_pole=m.max_pole_modulus(),
                    error="",
                )
            except (IdentificationError, SimulationDivergedError, DataValidationError) as exc:
                row.update(
                    train_esr=np.nan,
                    val_esr=np.nan,
                    val_ssse=np.nan,
                    max_frozen_pole=np.nan,
                    error=str(exc),
                )
            rows.append(row)
    return pd.DataFrame(rows).sort_values("val_esr", na_position="last").reset_index(drop=True)
