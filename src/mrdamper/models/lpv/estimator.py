"""Estimators of the LPV input-output model and of its LTI counterpart, and order selection.

:class:`LPVEstimator` identifies an :class:`~mrdamper.models.lpv.LPVModel` (joint least squares,
then output-error refinement under frozen stability, :mod:`mrdamper.models.lpv.fit`);
:class:`LTIEstimator` is the same with ``n_rho = 0``. :func:`select_order` scores a grid of
orders in free run on validation records.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import InitVar, dataclass
from typing import Any, ClassVar, Literal, cast

import numpy as np
import pandas as pd

from mrdamper._warn import warn_user
from mrdamper.analysis import ZoneLaws, fit_zone_laws, zone_fits_binned
from mrdamper.analysis.laws import OuterSlopes, laws_keeping_eq_20
from mrdamper.analysis.scheduling import Reading
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _scale
from mrdamper.models._arrays import readonly
from mrdamper.models.base import (
    Choice,
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
    check_number,
)
from mrdamper.models.lag import check_lag, resolved
from mrdamper.models.lpv import choice as _lpv_choice
from mrdamper.models.lpv import fit as _lpv_fit
from mrdamper.models.lpv import inputs as _lpv_inputs
from mrdamper.models.lpv import kernels as K
from mrdamper.models.lpv.inputs import LPVInput
from mrdamper.models.lpv.model import (
    InputSignal,
    LPVModel,
    LTIModel,
    TransferFunctionModel,
    model_signals,
)
from mrdamper.models.rates import (
    MODEL_FS_REASON,
    model_rate,
    rename_setting,
    to_model_rate,
)
from mrdamper.models.settings import literal_choices, type_hints
from mrdamper.progress import report

__all__ = [
    "MIN_MODEL_FS",
    "LPVEstimator",
    "LTIEstimator",
    "outer_slope_choices",
    "select_order",
]

#: Lowest default model rate of the LPV family [Hz]. The paper's transfer function has no direct
#: feed-through, so the force answers the input one model sample later: 10 ms at a 100 Hz record
#: rate, 5 ms at 200 Hz. Records sampled slower are up-sampled to this rate (``model_fs`` sets any
#: rate). Measured (``docs/results.md``, "The LPV family's model rate"): Labcontrol (100 Hz)
#: test ESR 0.0164 ->
#: 0.0138, Quiroz up to 3 Hz -> 4 Hz 0.0147 -> 0.0118.
MIN_MODEL_FS: float = 500.0


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
    eta : float, "auto", "identify" or None
        Drive-lag rate [1/s] of a first-order lag ``d rho/dt = -eta (rho - input)`` on the
        electrical input. ``"auto"`` (default): identified on the training records when the
        input is a varying command voltage, none otherwise (:mod:`mrdamper.models.lag`);
        ``"identify"``: identified whenever the input switches within a record, a measured
        current included (the field's lag); None: no
        lag.
    input_signal : {"hysteretic", "u", "v"}
        LPV input: the zone-law input with a hysteretic pre-yield state (default,
        :mod:`mrdamper.analysis.hysteretic`), the paper's static zone-law input ``u`` (needed by
        the inverse and the state-space / C exports), or the raw velocity (ablation).
    stroke, blend : float, optional
        Stroke scale [m] and pre-yield share [-] of the hysteretic input; when either is None
        it is chosen over a grid (lowest mean free-run ESR where ``choose_on`` says).
    choose_on : {"beyond", "training", "held-out"}
        Where the open ``stroke`` / ``blend`` candidates are scored
        (:mod:`mrdamper.models.lpv.choice`). ``"beyond"`` (default): on held-out records inside
        and beyond the training envelope (the ``"held-out"`` folds of whole records, plus the
        records of the highest frequency band held out when they are at most a third of the
        records), each fitted on the others; as ``"training"`` when there is neither.
        ``"training"``: on the training records themselves. ``"held-out"``: on records held out
        of them (three folds, each holding out every third record of each electrical level; the
        last 30 % of every record when a fold would hold out fewer than two records). Unused
        when nothing is open.
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
    outer_slopes : {"auto", "post-yield", "zones"}
        Outer (post-yield) slopes of each level's zone fit: ``"zones"`` as the three-zone
        regression gives them (the paper's), ``"post-yield"`` re-estimated on the samples beyond
        three zone limits (:func:`mrdamper.analysis.zones.post_yield_slopes`: samples just past
        the limit that have not yielded make the regression's outer slopes too steep, and the
        model over-predicts the force at high velocity). ``"auto"`` (default): ``"post-yield"``
        for the hysteretic input, ``"zones"`` for the paper's static input.
    n_bins : int
        Number of ``rho`` bins for ``laws_by="bins"``.
    model_fs : float, optional
        Model rate [Hz]; default: the lowest sampling rate of the training records, at least
        :data:`MIN_MODEL_FS` (records at other rates are resampled, with a note; slower records
        are up-sampled by linear interpolation). ``fs`` is its old name, still accepted.
    offset : bool
        Estimate an output force offset ``F0``.
    stiffness : float, "auto" or "identify"
        Parallel stiffness ``k_x`` [N/m] of ``F = y + F0 + k_x x`` (``x`` the displacement [m]):
        a damper's accumulator or gas spring, a force in phase with the travel that the filtered
        velocity input cannot give. ``"auto"`` (default): when the hysteretic input's settings
        are chosen on records given to the fit (``choice_records``, e.g. held-out loop records),
        those records also decide between no stiffness and an identified one
        (:mod:`mrdamper.models.lpv.choice`); otherwise none, the paper's structure.
        ``"identify"``: estimated by the output-error refinement with the other unknowns
        (:func:`mrdamper.models.lpv.fit.identify`); a number fixes it (``0``: none). Not
        identified by default otherwise: on the beyond-envelope folds it trades off against the
        pre-yield blend, and on the virtual rig's sines it tripled the chirp's test ESR
        (``docs/results.md``, "Parallel stiffness").
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

    Notes
    -----
    ``fit(data, record_weights=None)`` is the fit template of
    :class:`~mrdamper.models.base.Estimator`; its one option ``record_weights`` gives one
    non-negative weight per record [-], multiplying that record's share of the least-squares and
    output-error costs (on top of ``weighting``), e.g. to mix measured records with synthetic ones
    without duplicating records (default: all 1). A hysteretic input with ``stroke`` or ``blend``
    left None has them chosen first (the template's settings-choice hook); the option
    ``choice_records`` (records not in the training set) then scores the candidates instead of
    the inner folds (with ``choose_on="held-out"`` or ``"beyond"``; the model is fitted on the
    training records alone). The fit raises
    :class:`~mrdamper.errors.IdentificationError` for a rank-deficient regression, too few
    scheduling levels for ``n_rho``, or (with ``stability="enforce"``) no frozen-stable model,
    naming the pole.
    """

    kind: ClassVar[str] = "lpv"
    model_class: ClassVar[type[FittedModel]] = LPVModel
    fit_options: ClassVar[tuple[str, ...]] = ("record_weights", "choice_records")
    per_record_options: ClassVar[tuple[str, ...]] = ("record_weights",)
    choice_options: ClassVar[tuple[str, ...]] = ("choice_records",)

    n_m: int = 3
    n_rho: int = 2
    input: ElectricalSource = "i"
    eta: float | Literal["auto", "identify"] | None = "auto"
    input_signal: InputSignal = "hysteretic"
    reading: Reading = "continuous"
    zone_laws: ZoneLaws | None = None
    laws_by: Literal["auto", "current", "plateaus", "bins"] = "auto"
    laws_degree: int = 2
    outer_slopes: Literal["auto", "post-yield", "zones"] = "auto"
    n_bins: int = 5
    model_fs: float | None = None
    offset: bool = True
    stiffness: float | Literal["auto", "identify"] = "auto"
    weighting: Literal["esr", "sse"] = "esr"
    refine: bool = True
    max_nfev: int = 60
    oe_solver: Literal["gauss-newton", "least_squares"] = "gauss-newton"
    range_policy: RangePolicy = "error"
    stability: Literal["enforce", "warn"] = "enforce"
    stroke: float | None = None
    blend: float | None = None
    choose_on: Literal["beyond", "training", "held-out"] = "beyond"
    fs: InitVar[float | None] = None

    renamed_settings: ClassVar[Mapping[str, str]] = {"fs": "model_fs"}
    min_model_fs: ClassVar[float | None] = MIN_MODEL_FS

    def __post_init__(self, fs: float | None) -> None:
        self.model_fs = cast(
            "float | None",
            rename_setting(self.kind, "fs", "model_fs", fs, self.model_fs, MODEL_FS_REASON),
        )

    def _validate(self) -> None:
        super()._validate()
        self._input_class().open_settings(self.reading, self.stroke, self.blend)
        check_int("n_m", self.n_m, 1)
        for name in ("n_rho", "laws_degree", "n_bins", "max_nfev"):
            check_int(name, getattr(self, name), 0)
        check_lag(self.eta)
        check_number("model_fs", self.model_fs, allow_none=True, what="a positive model rate [Hz]")
        if self.stiffness not in ("auto", "identify"):
            check_number(
                "stiffness",
                self.stiffness,
                low=-math.inf,
                what="'auto', 'identify' or a finite stiffness [N/m]",
            )

    def _laws(
        self,
        exps: Sequence[Experiment],
        rhos: list[np.ndarray],
        prov: dict[str, Any],
        single: bool = False,
    ) -> ZoneLaws | None:
        if not self._input_class().needs_laws:
            return None
        if self.zone_laws is not None:
            prov["outer_slopes"] = "given with the laws (zone_laws)"
            return self.zone_laws
        by = self.laws_by
        if by == "auto":
            lacking = [e.name for e in exps if "current" not in e.metadata]
            if lacking and len(lacking) < len(exps):
                raise DataValidationError(
                    "laws_by",
                    "'auto' needs metadata 'current' on every record or on none; "
                    f"{len(lacking)} of "
                    f"{len(exps)} records lack it (first: {lacking[0]!r}); set laws_by='bins' or "
                    f"'plateaus', or give the laws (zone_laws=)",
                )
            by = "bins" if lacking else "current"
            if lacking:
                prov["laws_note"] = (
                    "laws_by='auto': no record carries metadata 'current'; laws fitted on rho bins"
                )
        outer = self.resolved_outer_slopes()
        if outer != "post-yield":
            prov["outer_slopes"] = outer
            return self._fit_laws(exps, rhos, by, outer, single)
        laws, used, note = laws_keeping_eq_20(
            lambda o, strict: self._fit_laws(exps, rhos, by, o, single, strict=strict),
            strict=True,
        )
        prov["outer_slopes"] = used
        if note:
            prov["outer_slopes_note"] = note
        return laws

    def _fit_laws(
        self,
        exps: Sequence[Experiment],
        rhos: list[np.ndarray],
        by: str,
        outer: OuterSlopes,
        single: bool,
        strict: bool = True,
    ) -> ZoneLaws:
        """Zone laws of the training records, grouped ``by`` level, with ``outer`` slopes
        (``strict``: laws that break the paper's assumptions raise, see :func:`fit_zone_laws`)."""
        if by == "bins":
            v, F, r = _scale.strided(
                [[e.v for e in exps], [e.F for e in exps], rhos]
            )  # long campaigns
            fits = zone_fits_binned(v, F, r, n_bins=self.n_bins, outer_slopes=outer)
            degree = min(self.laws_degree, max(len(fits) - 1, 0))
            return fit_zone_laws(fits, degree=degree, strict=strict)
        return fit_zone_laws(
            exps,
            degree=0 if single else self.laws_degree,
            by=by,
            source=self.input,
            outer_slopes=outer,
            strict=strict,
        )

    def resolved_outer_slopes(self) -> OuterSlopes:
        """The outer-slope estimate the zone laws use (``"auto"`` resolved by the input): the
        laws a study's force-velocity analysis hands to this estimator."""
        if self.outer_slopes == "auto":
            return "post-yield" if self.input_signal == "hysteretic" else "zones"
        return self.outer_slopes

    def resolved_stiffness(self) -> float | Literal["identify"]:
        """The stiffness the identification uses: ``"auto"`` left unresolved by a choice on given
        records is none (0)."""
        return 0.0 if self.stiffness == "auto" else self.stiffness

    def _open_settings(self) -> bool:
        """True when the hysteretic input's ``stroke`` or ``blend`` is left None."""
        return bool(self._input_class().open_settings(self.reading, self.stroke, self.blend))

    def _choose_settings(self, records: ExperimentSet, options: Mapping[str, Any]) -> Choice:
        """The hysteretic input's ``stroke`` / ``blend`` left None, chosen where ``choose_on``
        says (:func:`mrdamper.models.lpv.choice.fit_choosing`)."""
        return _lpv_choice.fit_choosing(
            self, records, options.get("record_weights"), options.get("choice_records")
        )

    def _input_class(self) -> type[LPVInput]:
        return _lpv_inputs.input_class(self.input_signal)

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Joint least squares, then output-error refinement under frozen stability."""
        exps = data.records
        record_weights = options.get("record_weights")
        user_w = _record_weights(record_weights, len(exps))
        fs = model_rate([e.fs for e in exps], self.model_fs, self.kind, self.min_model_fs)
        eta = resolved(self.eta)
        rhos = [
            K.first_order_lag(r, e.dt, eta) if eta is not None else r
            for r, e in zip(data.electrical, exps)
        ]
        prov: dict[str, Any] = {}
        report("zone laws")
        laws = self._laws(exps, rhos, prov, single=data.single)
        lpv_input = _lpv_inputs.from_saved(
            self.input_signal, laws, self.reading, self.stroke, self.blend
        )
        stiffness = self.resolved_stiffness()
        F, U, R, X, w = [], [], [], [], []
        for k, (e, el) in enumerate(zip(exps, data.electrical)):
            report("LPV input signals", k, len(exps))
            e.require_samples(self.n_m + 2, "LPV identification")
            u, rho = model_signals(e, el, fs=fs, eta=eta, lpv_input=lpv_input)
            # read-only whether resampled or not: one argument type for the kernels
            Fr = readonly(to_model_rate(np.asarray(e.F), e.fs, fs))
            F.append(Fr)
            if stiffness != 0:  # the displacement only where a stiffness needs it
                X.append(readonly(to_model_rate(np.asarray(e.x), e.fs, fs)))
            U.append(u)
            R.append(rho)
            var = float(np.var(Fr))
            w.append(1.0 / (Fr.size * var) if self.weighting == "esr" and var > 0 else 1.0)
        weights = np.asarray(w) * user_w
        weights = weights / weights.mean()
        rho_range = _scale.input_range_of(R)
        n_p = self.n_rho + 1
        if data.single:
            n_p = 1  # one level: coefficients and laws are constants (higher powers exactly 0)
        else:
            tol = 1e-9 * max(1.0, abs(rho_range[1]))
            n_lev = _scale.distinct_levels(R, tol)
            if n_lev < n_p:
                raise IdentificationError(
                    f"{self.kind}: rho takes {n_lev} distinct value(s) in the training data; "
                    f"degree n_rho={self.n_rho} needs at least {self.n_rho + 1} (use more current "
                    "levels or lower n_rho)"
                )
        rec = _lpv_fit.Records(F=F, u=U, rho=R, weights=weights, x=X or None)
        f_scale = max(max(float(np.max(np.abs(f))) for f in F), 1.0)
        bound = 1e3 * f_scale
        prov.update(
            {
                "training_records": list(exps.names),
                "n_samples": int(sum(a.size for a in F)),
                "settings": _settings_dict(self),
            }
        )
        if record_weights is not None:
            prov["record_weights"] = [float(x) for x in user_w]
        fit = _lpv_fit.identify(
            rec,
            self.n_m,
            n_p,
            offset=self.offset,
            bound=bound,
            refine=self.refine,
            max_nfev=self.max_nfev,
            solver=self.oe_solver,
            enforce_stability=self.stability == "enforce",
            rho_range=rho_range,
            windows=lambda r: _scale.window_records(r, fs),  # long campaigns
            stiffness=None if stiffness == "identify" else float(stiffness),
        )
        prov.update(fit.provenance)
        pmax, rho_at, pole = fit.largest_pole
        if self.stability == "enforce" and not pmax < 1.0:
            raise IdentificationError(
                f"{self.kind}: no frozen-stable model: frozen pole z = "
                f"{pole.real:.4f}{pole.imag:+.4f}j (|z| = {pmax:.4f}) at rho = {rho_at:.4g} of "
                f"the identified range [{rho_range[0]:.4g}, {rho_range[1]:.4g}]"
                + (
                    ""
                    if self.refine
                    else "; the least-squares estimate is unstable, set refine=True"
                )
                + " (stability='warn' returns it with a warning)"
            )
        alpha, beta = (
            np.pad(c, ((0, 0), (0, self.n_rho + 1 - n_p)))
            for c in K.split_theta(fit.theta, self.n_m, n_p)
        )
        prov.update(max_frozen_pole=pmax, max_frozen_pole_rho=rho_at, frozen_stable=pmax < 1.0)
        if pmax >= 1.0:  # stability="warn"
            warn_user(
                f"{self.kind}: identified model is not frozen-stable over rho in "
                f"[{rho_range[0]:.4g}, {rho_range[1]:.4g}] (max frozen pole modulus {pmax:.4f} at "
                f"rho = {rho_at:.4g})",
                RuntimeWarning,
            )
        return Identified(
            parameters={
                "alpha": alpha,
                "beta": beta,
                "offset": fit.offset,
                "stiffness": fit.stiffness,
                "fs": fs,
                "reading": self.reading,
                "zone_laws": laws,
                "eta": eta,
                "rho_range": rho_range,
                "force_bound": bound,
                **lpv_input.saved(),  # input_signal, stroke, blend
            },
            provenance=prov,
        )


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
    model_class: ClassVar[type[FittedModel]] = LTIModel
    n_rho: int = 0

    def _validate(self) -> None:
        super()._validate()
        if self.n_rho != 0:
            raise DataValidationError("n_rho", f"an LTI model has n_rho = 0, got {self.n_rho}")


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

    Parameters
    ----------
    train, validation : Experiment or iterable of Experiment
        Records that identify / score every candidate.
    orders : sequence of int
        Candidate model orders ``n_m``.
    rho_degrees : sequence of int
        Candidate degrees ``n_rho``.
    **settings
        Other :class:`LPVEstimator` settings.

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
                    est = LPVEstimator(n_m=n_m, n_rho=n_rho, **settings)
                    m = cast(TransferFunctionModel, est.fit(tr))
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


def outer_slope_choices() -> tuple[str, ...]:
    """The values :class:`LPVEstimator`'s ``outer_slopes`` setting takes (for command lines)."""
    choices, _ = literal_choices(type_hints(LPVEstimator)["outer_slopes"]) or ((), False)
    return tuple(choices)
