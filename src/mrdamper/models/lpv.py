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
from typing import Any, ClassVar, Literal, cast

import numpy as np
import pandas as pd

from mrdamper._warn import warn_user
from mrdamper.analysis import ZoneLaws, fit_zone_laws, zone_fits_binned
from mrdamper.analysis.hysteretic import hysteretic_input
from mrdamper.analysis.scheduling import Reading
from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError, SimulationDivergedError
from mrdamper.models import _lpv_fit, _lpv_inputs, _lpv_step, _scale
from mrdamper.models import _lpv_kernels as K
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
from mrdamper.models.protocols import ScheduledForm
from mrdamper.models.rates import (
    MODEL_FS_REASON,
    model_rate,
    rename_setting,
    to_model_rate,
    to_record_rate,
)
from mrdamper.models.step import Step
from mrdamper.progress import report

__all__ = [
    "LPVEstimator",
    "LPVModel",
    "LTIEstimator",
    "LTIModel",
    "TransferFunctionModel",
    "model_signals",
    "select_order",
]

InputSignal = Literal["u", "v", "hysteretic"]


# ----------------------------------------------------------------------------- signal pipeline
def model_signals(
    experiment: Experiment,
    electrical: np.ndarray,
    *,
    fs: float,
    eta: float | None,
    input_signal: InputSignal,
    zone_laws: ZoneLaws | None,
    reading: Reading,
    stroke: float | None = None,
    blend: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The LPV model's input ``u`` and scheduling variable ``rho`` at the model rate, one record.

    The one pipeline from a record to the model's signals, used by prediction and identification:

    1. ``rho``: the electrical input [A] or [V] (range policy already applied by the caller),
       through the drive lag ``d rho/dt = -eta (rho - input)`` when ``eta`` is set, resampled
       from the record rate to ``fs``;
    2. the velocity [m/s], resampled to ``fs``;
    3. ``u``: the scheduling input of the zone laws at ``(v, rho)`` (``input_signal="u"``,
       reading ``reading`` of eq. 22), the same with a hysteretic pre-yield state driven by the
       displacement (``input_signal="hysteretic"``, :mod:`mrdamper.analysis.hysteretic`), or the
       velocity itself (``input_signal="v"``).

    Parameters
    ----------
    experiment : Experiment
        The record (its velocity, rate and time step are used).
    electrical : ndarray
        Its electrical input [A] or [V], at the record rate.
    fs : float
        Model rate [Hz].
    eta : float or None
        Drive-lag rate [1/s]; None: ``rho`` is the electrical input.
    input_signal : {"u", "v", "hysteretic"}
        LPV input.
    zone_laws : ZoneLaws or None
        Laws that build ``u`` (needed unless ``input_signal="v"``).
    reading : {"continuous", "literal"}
        Reading of eq. (22).
    stroke, blend : float, optional
        Stroke scale [m] and pre-yield share [-] of the hysteretic input (needed for
        ``input_signal="hysteretic"``, ignored otherwise).

    Returns
    -------
    u, rho : ndarray
        Contiguous float64 arrays at the model rate: ``u`` [m/s], ``rho`` [A] or [V].
    """
    rho = np.ascontiguousarray(electrical, dtype=np.float64)
    if eta is not None:
        rho = K.first_order_lag(rho, experiment.dt, eta)
    rho = to_model_rate(np.asarray(rho, dtype=np.float64), experiment.fs, fs)
    v = to_model_rate(np.asarray(experiment.v), experiment.fs, fs)
    if input_signal == "v":
        u = v
    elif zone_laws is None:
        raise DataValidationError(
            "zone_laws", f"input_signal={input_signal!r} needs zone laws to build u"
        )
    elif input_signal == "hysteretic":
        if stroke is None or blend is None:
            raise DataValidationError(
                "stroke", "input_signal='hysteretic' needs both stroke [m] and blend [-]"
            )
        u = hysteretic_input(zone_laws, v, rho, 1.0 / fs, stroke, blend)
    else:
        u = zone_laws.scheduling_input(v, rho, reading=reading)
    return np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(rho, dtype=np.float64)


# ----------------------------------------------------------------------------- fitted models
@dataclass(frozen=True)
class TransferFunctionModel(FittedModel):
    """The input-output transfer-function structure shared by the LPV and LTI models (immutable).

    Use :class:`LPVModel` (scheduled coefficients) or :class:`LTIModel` (``n_rho = 0``); this
    class holds what they share: parameters, signal pipeline, free-run prediction and frozen
    poles.

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

    kind: ClassVar[str] = "abstract"

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
        return np.asarray((r[..., None, None] ** np.arange(self.n_rho + 1) * self.alpha).sum(-1))

    def b(self, rho: Any) -> np.ndarray:
        """Numerator coefficients ``b_1..b_n`` at ``rho`` [N s/m]; shape ``rho.shape + (n_m,)``."""
        r = np.asarray(rho, dtype=float)
        return np.asarray((r[..., None, None] ** np.arange(self.n_rho + 1) * self.beta).sum(-1))

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
        """``(u, rho)`` at the model rate ``fs`` for one record (see :func:`model_signals`)."""
        return model_signals(
            experiment,
            self.electrical_input(experiment),
            fs=self.fs,
            eta=self.eta,
            input_signal=self.input_signal,
            zone_laws=self.zone_laws,
            reading=self.reading,
            stroke=self.stroke,
            blend=self.blend,
        )

    def law_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Zone-law arrays of ``u`` as the control kernels take them.

        Returns
        -------
        gamma_m, gamma_c : ndarray, shape (3, degree + 1)
            Slope and intercept laws (float64, C-contiguous); zeros of shape (3, 1) when the input
            is the velocity (``input_signal="v"``) or the model has no laws.
        mu_high, mu_low : ndarray, shape (2,)
            Breakpoint laws; zeros in the same case.
        """
        laws = self.zone_laws
        if self.input_signal == "v" or laws is None:
            return np.zeros((3, 1)), np.zeros((3, 1)), np.zeros(2), np.zeros(2)
        return (
            np.ascontiguousarray(laws.gamma_m, dtype=np.float64),
            np.ascontiguousarray(laws.gamma_c, dtype=np.float64),
            np.asarray(laws.mu_high, dtype=np.float64),
            np.asarray(laws.mu_low, dtype=np.float64),
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

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The model as a per-sample step at its own rate ``fs`` (:mod:`mrdamper.models.step`).

        The state holds the lagged input ``rho`` (with ``eta``), the Dahl state of the hysteretic
        input and the past ``n_m`` outputs and inputs (:mod:`mrdamper.models._lpv_step`); from rest
        they are zero and ``rho = e[0]``. The input is used as given (no range policy).
        ``feedthrough`` is True for an LPV model without drive lag (the force at a sample is a
        polynomial in the present input); with a lag, or for the LTI model, the present input
        acts only from the next sample on.

        Parameters
        ----------
        dt, vmax : float
            Interval [s] and largest velocity [m/s] the step will see; unused by this family
            (the common signature of :meth:`~mrdamper.models.FittedModel.step`).
        """
        gm, gc, mu_h, mu_l = self.law_arrays()
        if self.input_signal == "v" or self.zone_laws is None:
            mode = _lpv_step.MODE_V
        elif self.reading == "continuous":
            mode = _lpv_step.MODE_CONTINUOUS
        else:
            mode = _lpv_step.MODE_LITERAL
        hys = self.input_signal == "hysteretic"
        form = _lpv_step.LPVForm(
            np.ascontiguousarray(self.alpha),
            np.ascontiguousarray(self.beta),
            float(self.offset),
            float(self.force_bound),
            -1.0 if self.eta is None else float(self.eta),
            mode,
            gm,
            gc,
            mu_h,
            mu_l,
            float(self.blend) if hys and self.blend else 0.0,
            float(self.stroke) if hys and self.stroke else 0.0,
        )
        feedthrough = self.kind == "lpv" and self.eta is None
        return _lpv_step.make_step(self.kind, form, self.fs, feedthrough)

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
        return K.frozen_poles(self.alpha, grid)

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
class LPVModel(TransferFunctionModel):
    """Identified LPV input-output damper model (see :class:`TransferFunctionModel` for the
    attributes). Invertible (:class:`~mrdamper.models.protocols.InvertibleModel`): its force at a
    sample is a polynomial in the present scheduling variable."""

    kind: ClassVar[str] = "lpv"

    def inverse_form(self) -> ScheduledForm:
        """The model as the plain arrays of the control kernels (zone laws included).

        A hysteretic-input model (``input_signal="hysteretic"``) carries its ``blend`` and
        ``stroke``: the kernels step the Dahl state along the motion and rebuild ``u`` from
        ``(v, z, rho)``.
        """
        gm, gc, mu_h, mu_l = self.law_arrays()
        return ScheduledForm(
            alpha=np.ascontiguousarray(self.alpha),
            beta=np.ascontiguousarray(self.beta),
            offset=float(self.offset),
            fs=self.fs,
            eta=self.eta,
            input_signal=self.input_signal,
            reading=self.reading,
            gamma_m=gm,
            gamma_c=gc,
            mu_high=mu_h,
            mu_low=mu_l,
            blend=float(self.blend) if self.input_signal == "hysteretic" and self.blend else 0.0,
            stroke=float(self.stroke) if self.input_signal == "hysteretic" and self.stroke else 0.0,
        )


@dataclass(frozen=True)
class LTIModel(TransferFunctionModel):
    """The LPV structure without scheduling of the coefficients (``n_rho = 0``; paper Fig. 4).

    Not invertible: its force does not depend on the present electrical input.
    """

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
    eta : float, "auto" or None
        Drive-lag rate [1/s] of a first-order lag ``d rho/dt = -eta (rho - input)`` on the
        electrical input. ``"auto"`` (default): identified on the training records when the
        input is a varying command voltage, none otherwise (:mod:`mrdamper.models.lag`); None: no
        lag.
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
    model_class: ClassVar[type[FittedModel]] = LPVModel
    fit_options: ClassVar[tuple[str, ...]] = ("record_weights",)
    per_record_options: ClassVar[tuple[str, ...]] = ("record_weights",)

    n_m: int = 3
    n_rho: int = 2
    input: ElectricalSource = "i"
    eta: float | Literal["auto"] | None = "auto"
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
    range_policy: RangePolicy = "error"
    stability: Literal["enforce", "warn"] = "enforce"
    stroke: float | None = None
    blend: float | None = None
    fs: InitVar[float | None] = None

    renamed_settings: ClassVar[Mapping[str, str]] = {"fs": "model_fs"}

    def __post_init__(self, fs: float | None) -> None:
        self.model_fs = cast(
            "float | None",
            rename_setting(self.kind, "fs", "model_fs", fs, self.model_fs, MODEL_FS_REASON),
        )

    def _validate(self) -> None:
        super()._validate()
        check_int("n_m", self.n_m, 1)
        for name in ("n_rho", "laws_degree", "n_bins", "max_nfev"):
            check_int(name, getattr(self, name), 0)
        check_lag(self.eta)
        check_number("model_fs", self.model_fs, allow_none=True, what="a positive model rate [Hz]")

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
        **options: Any,
    ) -> TransferFunctionModel:
        """Identify the model from one record or a collection (records keep their own start).

        Parameters
        ----------
        data : Experiment or iterable of Experiment
            Training records.
        record_weights : sequence of float, optional
            One non-negative weight per record [-], multiplying that record's share of the
            least-squares and output-error costs (on top of ``weighting``); e.g. to mix measured
            records with synthetic ones without duplicating records. Default: all 1.
        **options
            Refused (an error names the option): the LPV estimator takes no other option.

        Raises
        ------
        IdentificationError
            Rank-deficient regression, too few scheduling levels for ``n_rho``, or (with
            ``stability="enforce"``) no frozen-stable model; the message names the pole.
        """
        self._check_fit_options(options)
        self._validate()
        if _lpv_inputs.needs_choice(self):  # hysteretic input: stroke / blend on training data
            records, opts, segments = self._training_set(data, {"record_weights": record_weights})
            model = cast(
                TransferFunctionModel,
                _lpv_inputs.fit_choosing(self, records, opts["record_weights"]),
            )
            if segments:
                model = dataclasses.replace(
                    model, provenance={**model.provenance, "segments": segments}
                )
        else:
            model = cast(
                TransferFunctionModel, super().fit(data, record_weights=record_weights, **options)
            )
        pmax = float(model.provenance["max_frozen_pole"])
        if pmax >= 1.0:
            lo, hi = model.rho_range
            warn_user(
                f"{self.kind}: identified model is not frozen-stable over rho in "
                f"[{lo:.4g}, {hi:.4g}] (max frozen pole modulus {pmax:.4f} at rho = "
                f"{model.provenance['max_frozen_pole_rho']:.4g})",
                RuntimeWarning,
            )
        return model

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Joint least squares, then output-error refinement under frozen stability."""
        exps = data.records
        record_weights = options.get("record_weights")
        user_w = _record_weights(record_weights, len(exps))
        fs = model_rate([e.fs for e in exps], self.model_fs, self.kind)
        eta = resolved(self.eta)
        rhos = [
            K.first_order_lag(r, e.dt, eta) if eta is not None else r
            for r, e in zip(data.electrical, exps)
        ]
        prov: dict[str, Any] = {}
        report("zone laws")
        laws = self._laws(exps, rhos, prov, single=data.single)
        F, U, R, w = [], [], [], []
        for k, (e, el) in enumerate(zip(exps, data.electrical)):
            report("LPV input signals", k, len(exps))
            e.require_samples(self.n_m + 2, "LPV identification")
            u, rho = model_signals(
                e,
                el,
                fs=fs,
                eta=eta,
                input_signal=self.input_signal,
                zone_laws=laws,
                reading=self.reading,
                stroke=self.stroke,
                blend=self.blend,
            )
            Fr = np.ascontiguousarray(to_model_rate(np.asarray(e.F), e.fs, fs), dtype=np.float64)
            F.append(Fr)
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
        rec = _lpv_fit.Records(F=F, u=U, rho=R, weights=weights)
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
        return Identified(
            parameters={
                "alpha": alpha,
                "beta": beta,
                "offset": fit.offset,
                "fs": fs,
                "input_signal": self.input_signal,
                "reading": self.reading,
                "zone_laws": laws,
                "eta": eta,
                "rho_range": rho_range,
                "force_bound": bound,
                **_lpv_inputs.model_settings(self),
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
