"""Inverse damper model: the electrical input that makes the model produce a desired force.

A semi-active controller asks for a force; the damper can only be told a coil current (or a
driver voltage). :func:`inverse_current` returns, for a measured motion and a desired force
trajectory, the admissible input whose model force is closest to the desired force, the force the
model actually produces with it (free run) and where the desired force cannot be reached.

What is solved
--------------
Regularised inverse (``method="regularised"``, the default), every supported kind
    Causal, one pass: ``i[k]`` minimises ``(F_k(i) - F_desired[k])^2 + reg^2 (i - i[k-1])^2`` over
    the input range intersected with the rate bound ``|i - i[k-1]| <= rate dt`` (first sample
    free) and, for a model with a drive lag (LPV, or a static map with ``eta``), the lag's reach
    (the static map is then evaluated at the lagged input ``rho`` and the command is
    :func:`driver_command` of it). ``F_k`` is the model force at
    sample k given its past (LPV: a polynomial in ``rho[k]``; static map: the map at ``x[k]``,
    ``v[k]``). Where ``|dF/di|`` is small against ``reg`` the input holds; where it is large the
    input follows the exact solution. Minimum: grid of ``n_grid`` intervals, then the zero of the
    objective's slope next to the best grid point, bisected to machine precision. ``reg`` defaults
    to :func:`default_reg` (rate independent: a smoothing time constant ``DEFAULT_REG_TIME``).
    For an LPV model with a drive lag the force term is, from the third sample on, the mean over a
    lead horizon (default one lag time constant ``1/eta``) of the model force with the implied
    command held, the velocity held and the present desired force (:func:`horizon_samples`),
    minimised on the grid and then by golden-section search. Records at another rate than an LPV
    model's are resampled to it and the input interpolated back.

The exact per-sample inverse (``method="exact"``):

LPV model (kind ``"lpv"``), causal and in one pass
    At sample ``k`` the model force is a polynomial of degree ``n_rho`` in the present scheduling
    value ``rho[k]`` once the past outputs and LPV inputs are fixed (eq. 9: every coefficient is
    evaluated at ``rho[k]``; ``u[k]`` itself only enters later samples). The inverse takes the
    admissible ``rho[k]`` as follows: ``rho[k-1]`` itself when its force is within ``tol`` of
    ``F_desired[k]`` (the command is held); otherwise the exact solution ``F = F_desired[k]``
    nearest ``rho[k-1]``; if there is none, the nearest edge of the band
    ``|F - F_desired| <= tol``. Solutions are bisected to machine precision from the sign changes
    on a uniform grid of ``n_grid`` intervals. When no admissible
    ``rho`` qualifies it minimises ``|F - F_desired|`` exactly (an end of the interval or a
    stationary point of the polynomial, also bisected) and flags the sample ``saturated``. Then
    ``u[k]`` follows from ``v[k]`` and ``rho[k]`` through the zone laws and the next sample is
    solved. With the hysteretic input (``input_signal="hysteretic"``) ``u[k]`` also needs the Dahl
    state ``z[k]``, which depends on the motion only: it is computed first along the record at
    the model rate (:func:`mrdamper.analysis.hysteretic.dahl_state`, from rest ``z = 0``), exactly
    as the model's prediction does, so ``u[k]`` is a static map of ``(v[k], z[k], rho[k])``.
    Only present and past motion is used, as in a real-time loop. The record must be sampled at
    the model rate ``fs``.

    Why a tolerance band and holding: a change of ``rho[k]`` also changes ``u[k]``, which enters
    the force of the next samples; re-solving every sample exactly makes tiny rounding differences
    of ``rho`` grow from sample to sample (unstable zero dynamics of the exact inverse, seen on
    identified models) until the command chatters between its limits. Holding the command while
    the force is within ``tol`` removes that drift.
Drive lag (LPV, and tanh, Bouc-Wen, Dahl, LuGre with ``eta``)
    ``rho`` is then the lagged input ``rho[k] = e rho[k-1] + (1 - e) w[k-1]``, ``e = exp(-eta dt)``.
    The command ``w`` within the limits reaches only
    ``rho[k] in [e rho[k-1] + (1-e) lo, e rho[k-1] + (1-e) hi]``, which is the interval searched at
    sample ``k``; the command is the exact discrete inverse of the lag (a lead filter,
    :func:`driver_command`). The command ``w[k-1]`` is known only once ``F_desired[k]`` is: the
    controller needs the desired force one sample ahead. The lag starts at rest
    (``rho[1] = rho[0]``).
Static maps (SP-1..SP-4, Bingham)
    Per sample, vectorised over the record: the force on a grid of ``n_grid + 1`` inputs; the
    lowest-input sign change of ``F - F_desired`` is bisected (the plain bisection of a monotone
    map); without a sign change the grid minimum of ``|F - F_desired|`` is refined by golden-section
    search on its two neighbouring intervals. Among several exact solutions the lowest input wins.

``saturated`` marks samples where no admissible input reaches the desired force (a force
opposite to the motion beyond what the damper can dissipate, or more than the largest current
gives): the input returned is then the one giving the closest force.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import pandas as pd

from mrdamper.control.damper import StaticMapModel
from mrdamper.control.inverse import _inverse_kernels as K
from mrdamper.control.inverse._inverse_setup import (
    DEFAULT_REG_FRACTION,
    DEFAULT_REG_TIME,
    default_reg,
    force_authority,
    horizon_samples,
    lpv_hysteresis,
    lpv_inverse_fields,
    lpv_law_arrays,
    model_input_limits,
    reg_settings,
    static_map_arrays,
)
from mrdamper.control.inverse._record_inverse import (
    driver_command,
    lpv_any_rate,
    lpv_reg,
    static_exact,
)
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, OutOfRangeError
from mrdamper.models.base import FittedModel
from mrdamper.models.levels import check_levels
from mrdamper.models.lpv import TransferFunctionModel
from mrdamper.models.protocols import InvertibleModel, StepInvertibleModel, scheduled_form

__all__ = [
    "DEFAULT_REG_FRACTION",
    "DEFAULT_REG_TIME",
    "InverseResult",
    "default_reg",
    "driver_command",
    "force_authority",
    "horizon_samples",
    "inverse_current",
    "lpv_hysteresis",
    "lpv_inverse_fields",
    "lpv_law_arrays",
    "model_input_limits",
    "static_map_arrays",
]


@dataclass(frozen=True, eq=False)
class InverseResult:
    """Electrical input found by :func:`inverse_current` and the force it gives.

    Attributes
    ----------
    t : ndarray
        Time [s].
    F_desired : ndarray
        Desired force [N].
    i : ndarray
        Electrical input to apply: coil current [A] (or voltage [V] when ``input == "voltage"``);
        for an LPV model with a drive lag this is the driver command.
    rho : ndarray
        Scheduling value the model sees (equals ``i`` without a drive lag) [A] or [V].
    F_achieved : ndarray
        Model force with ``i`` in free run [N].
    saturated : ndarray of bool
        True where no admissible input reaches ``F_desired``.
    input : {"i", "voltage"}
        Name of the electrical input.
    model_kind : str
        Kind of the inverted model.
    i_range : (float, float)
        Range the input was confined to.
    """

    t: np.ndarray
    F_desired: np.ndarray
    i: np.ndarray
    rho: np.ndarray
    F_achieved: np.ndarray
    saturated: np.ndarray
    input: str
    model_kind: str
    i_range: tuple[float, float]

    @property
    def error(self) -> np.ndarray:
        """``F_achieved - F_desired`` [N]."""
        return np.asarray(self.F_achieved - self.F_desired)

    @property
    def saturated_fraction(self) -> float:
        """Fraction of samples where the desired force is out of reach [-]."""
        return float(np.mean(self.saturated)) if self.saturated.size else 0.0

    def to_frame(self) -> pd.DataFrame:
        """Columns ``t, F_desired, <input>, rho, F_achieved, saturated`` [s, N, A|V, A|V, N, -]."""
        return pd.DataFrame(
            {
                "t": self.t,
                "F_desired": self.F_desired,
                self.input: self.i,
                "rho": self.rho,
                "F_achieved": self.F_achieved,
                "saturated": self.saturated,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """Desired and achieved force (saturated samples marked) and the input on a twin axis.

        Returns
        -------
        Axes
            The force axes (the input is drawn on its twin).
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 3))
        ax.plot(self.t, self.F_desired, lw=0.8, label="desired")
        ax.plot(self.t, self.F_achieved, lw=0.8, label=f"achieved ({self.model_kind})")
        if np.any(self.saturated):
            ax.plot(
                self.t[self.saturated],
                self.F_achieved[self.saturated],
                ".",
                ms=2,
                label="saturated",
            )
        ax.set_xlabel("t [s]")
        ax.set_ylabel("F [N]")
        ax.legend(loc="upper left")
        ax2 = ax.twinx()
        ax2.plot(self.t, self.i, lw=0.6, color="0.4")
        ax2.set_ylabel(f"{self.input} [{'A' if self.input == 'i' else 'V'}]")
        return ax


# ----------------------------------------------------------------------------- helpers
def _motion(data: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if isinstance(data, Experiment):
        return np.asarray(data.t), np.asarray(data.x), np.asarray(data.v)
    if isinstance(data, Mapping):
        missing = [k for k in ("t", "x", "v") if k not in data]
        if missing:
            raise DataValidationError(
                "experiment_or_arrays", f"mapping lacks key(s) {missing}; expected t, x, v"
            )
        out = []
        for k in ("t", "x", "v"):
            a = np.asarray(data[k], dtype=float)
            if a.ndim != 1 or not np.all(np.isfinite(a)):
                raise DataValidationError(k, f"expected a finite 1-D array, got shape {a.shape}")
            out.append(a)
        t, x, v = out
        if not (t.size == x.size == v.size):
            raise DataValidationError("x", f"lengths differ: t {t.size}, x {x.size}, v {v.size}")
        return t, x, v
    raise DataValidationError(
        "experiment_or_arrays",
        f"expected an Experiment or a mapping with t, x, v, got {type(data).__name__}",
    )


def _range(model: FittedModel, i_range: Any) -> tuple[float, float]:
    lo_m, hi_m = model_input_limits(model)
    if i_range is None:
        lo, hi = lo_m, hi_m
    else:
        try:
            lo, hi = (float(b) for b in i_range)
        except (TypeError, ValueError) as exc:
            raise DataValidationError("i_range", f"expected (low, high), got {i_range!r}") from exc
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise DataValidationError("i_range", f"expected finite low <= high, got {i_range!r}")
        slack = 1e-9 * max(hi_m - lo_m, 1.0)
        if lo < lo_m - slack or hi > hi_m + slack:
            raise OutOfRangeError(
                f"i_range: {(lo, hi)} leaves the range the {model.kind} model was identified on "
                f"{(lo_m, hi_m)}; the inverse only uses inputs inside it"
            )
    check_levels(model, f"no {getattr(model, 'input', 'i')} can be chosen to give a force")
    if not hi > lo:
        raise DataValidationError("i_range", f"expected a non-empty input range, got {(lo, hi)}")
    return lo, hi


def _record(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, F: np.ndarray, model: FittedModel, w: np.ndarray
) -> Experiment:
    if model.input == "voltage":
        return Experiment(t=t, x=x, v=v, F=F, voltage=w, name="inverse")
    return Experiment(t=t, x=x, v=v, F=F, i=w, name="inverse")


# ----------------------------------------------------------------------------- public
def inverse_current(
    model: FittedModel,
    experiment_or_arrays: Experiment | Mapping[str, Any],
    F_desired: Any,
    *,
    i_range: tuple[float, float] | None = None,
    n_grid: int = 32,
    tol: float | None = None,
    method: str = "regularised",
    reg: float | None = None,
    rate: float | None = None,
    horizon: float | None = None,
) -> InverseResult:
    """Electrical input that makes ``model`` produce ``F_desired`` for the given motion.

    Parameters
    ----------
    model : FittedModel
        An LPV model (kind ``"lpv"``), a static map (``"sp1"``..``"sp4"``, ``"bingham"``), a
        model solved through its own step (``"tanh"``, ``"boucwen"``, ``"dahl"``, ``"lugre"``:
        closed form per sample, their ``invert_record``; with a drive lag for the lagged input,
        then the command through :func:`driver_command`), or any other model with a per-sample
        step (``"spencer"``, ``"p15"``, ``"lti"``, ``"narx"``: the quarter car's inverse through
        the step along the record,
        :func:`~mrdamper.control.inverse.step_inverse.invert_through_step`;
        regularised only).
    experiment_or_arrays : Experiment or mapping
        The motion: a record (its force and electrical channels are not used) or a mapping with
        arrays ``t`` [s], ``x`` [m], ``v`` [m/s].
    F_desired : array_like
        Desired force [N], one value per sample.
    i_range : (float, float), optional
        Input range to use [A] or [V]; must lie inside the model's ``input_range`` (the default).
    n_grid : int
        Grid intervals of the per-sample search (roots closer together than a grid step can be
        missed; the result is then the closest force found).
    tol : float, optional
        Force tolerance [N] of the LPV inverse (see the module docstring); default
        ``1e-6 * max(1, max|F_desired|)``. Static maps are solved to machine precision and
        flagged saturated when no input gives the force exactly. Used by ``method="exact"``.
    method : {"regularised", "exact"}
        ``"regularised"`` (default): per sample the input minimises
        ``(F(i) - F_desired)^2 + reg^2 (i - i_prev)^2`` within the limits and the rate bound (see
        the module docstring). ``"exact"``: the exact per-sample solution described above.
    reg : float, optional
        Regularisation weight [N/A] or [N/V] of the regularised inverse; default
        ``default_reg(model, max|v|, dt)`` with ``dt`` the model sample time (LPV) or the record's
        (static maps): a smoothing time constant :data:`DEFAULT_REG_TIME`, the same at every rate.
        0 gives the exact least-squares solution per sample.
    rate : float, optional
        Largest change of the input per second [A/s] or [V/s] (regularised method); default none.
    horizon : float, optional
        Lead horizon [s] of the regularised inverse of an LPV model with a drive lag: the command is
        chosen for the mean force error over this time with the command held (see the module
        docstring); default one lag time constant ``1 / eta``; 0 decides on the present sample
        only. Ignored for models without a drive lag and for static maps.

    Returns
    -------
    InverseResult

    Raises
    ------
    TypeError
        For an object with neither an inverse form nor a per-sample step.
    DataValidationError
        Bad lengths or values. (An LPV record at another rate than the model is solved at the
        model rate and interpolated back, with a note.)
    OutOfRangeError
        ``i_range`` outside the model's identified input range.
    """
    stepped = not isinstance(model, (InvertibleModel, StepInvertibleModel))
    if stepped and not callable(getattr(model, "step", None)):
        raise TypeError(
            f"model: no inverse for {getattr(model, 'kind', type(model).__name__)!r}: neither an "
            "inverse form nor a per-sample step"
        )
    sched = scheduled_form(model)
    if horizon is not None and (sched is None or sched.eta is None or method != "regularised"):
        raise DataValidationError(
            "horizon",
            f"a lead horizon is a setting of the regularised inverse of an LPV model with a drive "
            f"lag; this {model.kind} model's {method} inverse has none (drop it)",
        )
    if isinstance(n_grid, bool) or not isinstance(n_grid, (int, np.integer)) or n_grid < 1:
        raise DataValidationError("n_grid", f"expected a positive integer, got {n_grid!r}")
    t, x, v = _motion(experiment_or_arrays)
    Fd = np.asarray(F_desired, dtype=float)
    if Fd.ndim != 1 or Fd.size != t.size:
        raise DataValidationError(
            "F_desired", f"expected {t.size} values (one per sample), got shape {Fd.shape}"
        )
    if not np.all(np.isfinite(Fd)):
        raise DataValidationError("F_desired", "contains non-finite values")
    lo, hi = _range(model, i_range)
    # an LPV model's stiffness force is not the input's to give: its inverses solve for the rest
    Fd_poly = Fd - sched.stiffness * x if sched is not None else Fd
    if tol is None:
        tol = 1e-6 * max(1.0, float(np.max(np.abs(Fd))) if Fd.size else 1.0)
    if (
        isinstance(tol, bool)
        or not isinstance(tol, (int, float, np.floating))
        or not (np.isfinite(tol) and tol >= 0)
    ):
        raise DataValidationError("tol", f"expected a force tolerance >= 0 [N], got {tol!r}")
    if method not in ("regularised", "exact"):
        raise DataValidationError("method", f"expected 'regularised' or 'exact', got {method!r}")
    if stepped:  # no inverse form: solved per sample on its step, the quarter car's inverse
        if method == "exact":
            raise DataValidationError(
                "method", f"the {model.kind} model is inverted through its step: 'regularised' only"
            )
        from mrdamper.control.inverse.step_inverse import invert_through_step

        dt = float(t[1] - t[0]) if t.size > 1 else DEFAULT_REG_TIME
        w, sat = invert_through_step(model, x, v, Fd, dt, (lo, hi), reg=reg, rate=rate)
        rho = w
    elif isinstance(model, StepInvertibleModel):  # closed form per sample through its step
        dt = float(t[1] - t[0]) if t.size > 1 else DEFAULT_REG_TIME
        lam, step_rate = (
            (0.0, np.inf) if method == "exact" else reg_settings(model, v, reg, rate, lo, hi, dt)
        )
        rho, sat = model.invert_record(x, v, Fd, dt, lo, hi, reg=lam, max_change=step_rate * dt)
        w = rho if model.eta == 0.0 else driver_command(rho, model.eta, dt, (lo, hi))
    elif method == "regularised":
        if sched is not None:
            dt_inv = 1.0 / sched.fs
        else:
            dt_inv = float(t[1] - t[0]) if t.size > 1 else DEFAULT_REG_TIME
        lam, step_rate = reg_settings(model, v, reg, rate, lo, hi, dt_inv)
        if horizon is not None and (
            isinstance(horizon, bool)
            or not isinstance(horizon, (int, float, np.floating))
            or not (np.isfinite(horizon) and horizon >= 0)
        ):
            raise DataValidationError(
                "horizon", f"expected a lead horizon >= 0 [s], got {horizon!r}"
            )
        if sched is not None:
            n_h = horizon_samples(sched.eta, 1.0 / sched.fs, horizon)
            rho, w, sat = lpv_reg(
                cast(TransferFunctionModel, model),
                t,
                v,
                Fd_poly,
                lo,
                hi,
                int(n_grid),
                lam,
                step_rate,
                n_h,
            )
        else:
            comp, power, theta, f0 = static_map_arrays(model)
            dt = float(t[1] - t[0]) if t.size > 1 else 1.0
            eta = getattr(model, "eta", None)
            lag = -1.0 if eta is None else float(np.exp(-eta * dt))
            rho, sat = K.static_inverse_reg(
                np.ascontiguousarray(x, dtype=np.float64),
                np.ascontiguousarray(v, dtype=np.float64),
                Fd,
                comp,
                power,
                theta,
                f0,
                lo,
                hi,
                lo,
                int(n_grid),
                lam,
                step_rate * dt,
                lag,
            )
            w = rho if eta is None else driver_command(rho, eta, dt, (lo, hi))
    elif sched is not None:
        rho, w, sat = lpv_any_rate(
            cast(TransferFunctionModel, model), t, v, Fd_poly, lo, hi, int(n_grid), float(tol)
        )
    else:
        if getattr(model, "eta", None) is not None:
            raise DataValidationError(
                "method",
                f"the exact inverse of a static map with a drive lag (eta) is not implemented; "
                f"use method='regularised' for this {model.kind} model",
            )
        rho, sat = static_exact(cast(StaticMapModel, model), x, v, Fd, lo, hi, int(n_grid))
        w = rho
    rec = _record(t, x, v, Fd, model, w)
    F_ach = model.with_range_policy("clip").predict(rec)
    return InverseResult(
        t=t,
        F_desired=Fd,
        i=w,
        rho=rho,
        F_achieved=np.asarray(F_ach, dtype=float),
        saturated=sat,
        input=model.input,
        model_kind=model.kind,
        i_range=(lo, hi),
    )
