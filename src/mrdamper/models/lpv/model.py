"""LPV input-output damper model (paper eqs. 7-9, 16-22) and its LTI counterpart.

Discrete transfer function of order ``n_m`` whose coefficients are polynomials of degree ``n_rho``
in the scheduling variable ``rho`` (frozen-coefficient form, reading notes items 3-4)::

    F[k] = y[k] + F0 + k_x x[k]
    y[k] = -sum_{j=1..n_m} a_j(rho[k]) y[k-j] + sum_{j=1..n_m} b_j(rho[k]) u[k-j]     (b0 = 0)
    a_j(rho) = sum_p alpha[j-1, p] rho^p,   b_j(rho) = sum_p beta[j-1, p] rho^p

``rho`` is the electrical input (``input="i"`` coil current [A], or ``"voltage"`` [V]), optionally
through a first-order drive lag ``d rho/dt = -eta (rho - input)``. ``u`` is the scheduling input of
:mod:`mrdamper.analysis` built from the model's :class:`~mrdamper.analysis.ZoneLaws`
(``input_signal="u"``), or the raw velocity (``input_signal="v"``, ablation). The model works at
its own sampling rate ``fs``; records at another rate are resampled on the way in and the force is
interpolated back. ``k_x`` [N/m] is a parallel stiffness on the displacement ``x`` [m] (an
accumulator's gas spring; 0 in the paper's structure), outside the recursion. Free run starts from
rest (zero initial conditions) in every record.

The LTI model (kind ``"lti"``) is the same structure with ``n_rho = 0`` (no scheduling of the
coefficients; paper Fig. 4).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, cast

import numpy as np
import pandas as pd

from mrdamper.analysis import ZoneLaws
from mrdamper.analysis.scheduling import Reading
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models._arrays import readonly
from mrdamper.models.base import (
    FittedModel,
)
from mrdamper.models.lpv import inputs as _lpv_inputs
from mrdamper.models.lpv import kernels as K
from mrdamper.models.lpv import step as _lpv_step
from mrdamper.models.lpv.inputs import LPVInput
from mrdamper.models.protocols import ScheduledForm
from mrdamper.models.rates import (
    to_model_rate,
    to_record_rate,
)
from mrdamper.models.step import Step

__all__ = [
    "InputSignal",
    "LPVModel",
    "LTIModel",
    "TransferFunctionModel",
    "model_signals",
]

InputSignal = Literal["u", "v", "hysteretic"]


# ----------------------------------------------------------------------------- signal pipeline
def model_signals(
    experiment: Experiment,
    electrical: np.ndarray,
    *,
    fs: float,
    eta: float | None,
    lpv_input: LPVInput,
) -> tuple[np.ndarray, np.ndarray]:
    """The LPV model's input ``u`` and scheduling variable ``rho`` at the model rate, one record.

    The one pipeline from a record to the model's signals, used by prediction and identification:

    1. ``rho``: the electrical input [A] or [V] (range policy already applied by the caller),
       through the drive lag ``d rho/dt = -eta (rho - input)`` when ``eta`` is set, resampled
       from the record rate to ``fs``;
    2. the velocity [m/s], resampled to ``fs``;
    3. ``u``: the LPV input built from them (:meth:`~mrdamper.models.lpv.inputs.LPVInput.signal`:
       the zone-law input, the same with a hysteretic pre-yield state, or the velocity).

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
    lpv_input : LPVInput
        The LPV input (:mod:`mrdamper.models.lpv.inputs`).

    Returns
    -------
    u, rho : ndarray
        Contiguous float64 arrays at the model rate: ``u`` [m/s], ``rho`` [A] or [V] (read-only,
        whether resampled or not: one argument type for the kernels, :mod:`mrdamper.compiled`).
    """
    rho = np.ascontiguousarray(electrical, dtype=np.float64)
    if eta is not None:
        rho = K.first_order_lag(rho, experiment.dt, eta)
    rho = to_model_rate(np.asarray(rho, dtype=np.float64), experiment.fs, fs)
    v = readonly(to_model_rate(np.asarray(experiment.v), experiment.fs, fs))
    u = lpv_input.signal(np.asarray(v, dtype=np.float64), rho, 1.0 / fs)
    return np.ascontiguousarray(u, dtype=np.float64), readonly(rho)


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
        Saved name of the LPV input: the scheduling input of the zone laws, the raw velocity, or
        the zone-law input with a hysteretic pre-yield state. The model builds the input object
        from it and the fields below (:attr:`lpv_input`, :mod:`mrdamper.models.lpv.inputs`).
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
    stiffness : float
        Parallel stiffness ``k_x`` [N/m]: ``k_x x`` is added to the force (0: none, the paper's
        structure). ``x`` is the record's displacement as given (its mean is absorbed by ``F0``
        in training).
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
    stiffness: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
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
        lpv_input = _lpv_inputs.from_saved(
            self.input_signal, self.zone_laws, self.reading, self.stroke, self.blend
        )
        set_(self, "_lpv_input", lpv_input)
        saved = lpv_input.saved()
        set_(self, "stroke", saved["stroke"])
        set_(self, "blend", saved["blend"])
        if not self.fs > 0:
            raise DataValidationError("fs", f"expected a positive rate [Hz], got {self.fs}")
        set_(self, "offset", float(self.offset))
        if not np.isfinite(float(self.stiffness)):
            raise DataValidationError(
                "stiffness", f"expected a finite stiffness [N/m], got {self.stiffness!r}"
            )
        set_(self, "stiffness", float(self.stiffness))
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

    @property
    def lpv_input(self) -> LPVInput:
        """The model's LPV input (:mod:`mrdamper.models.lpv.inputs`), built from its fields."""
        return cast(LPVInput, self.__dict__["_lpv_input"])

    def model_signals(self, experiment: Experiment) -> tuple[np.ndarray, np.ndarray]:
        """``(u, rho)`` at the model rate ``fs`` for one record (see :func:`model_signals`)."""
        return model_signals(
            experiment,
            self.electrical_input(experiment),
            fs=self.fs,
            eta=self.eta,
            lpv_input=self.lpv_input,
        )

    def law_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Zone-law arrays of ``u`` as the control kernels take them.

        Returns
        -------
        gamma_m, gamma_c : ndarray, shape (3, degree + 1)
            Slope and intercept laws (float64, C-contiguous); zeros of shape (3, 1) when the input
            is the velocity (``input_signal="v"``).
        mu_high, mu_low : ndarray, shape (2,)
            Breakpoint laws; zeros in the same case.
        """
        a = self.lpv_input.kernel_arrays()
        return a.gamma_m, a.gamma_c, a.mu_high, a.mu_low

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
        F = to_record_rate(y + self.offset, self.fs, experiment)
        if self.stiffness != 0.0:
            F = F + self.stiffness * np.asarray(experiment.x, dtype=np.float64)
        return F

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The model as a per-sample step at its own rate ``fs`` (:mod:`mrdamper.models.step`).

        The state holds the lagged input ``rho`` (with ``eta``), the Dahl state of the hysteretic
        input and the past ``n_m`` outputs and inputs (:mod:`mrdamper.models.lpv.step`); from rest
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
        a = self.lpv_input.kernel_arrays()
        form = _lpv_step.LPVForm(
            np.ascontiguousarray(self.alpha),
            np.ascontiguousarray(self.beta),
            float(self.offset),
            float(self.force_bound),
            -1.0 if self.eta is None else float(self.eta),
            a.mode,
            a.gamma_m,
            a.gamma_c,
            a.mu_high,
            a.mu_low,
            a.blend,
            a.stroke,
            float(self.stiffness),
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
        a = self.lpv_input.kernel_arrays()
        return ScheduledForm(
            alpha=np.ascontiguousarray(self.alpha),
            beta=np.ascontiguousarray(self.beta),
            offset=float(self.offset),
            fs=self.fs,
            eta=self.eta,
            input_signal=self.input_signal,
            reading=self.reading,
            gamma_m=a.gamma_m,
            gamma_c=a.gamma_c,
            mu_high=a.mu_high,
            mu_low=a.mu_low,
            blend=a.blend,
            stroke=a.stroke,
            stiffness=float(self.stiffness),
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
