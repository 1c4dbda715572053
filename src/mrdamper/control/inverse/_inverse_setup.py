"""What the inverse reads from a model: input limits, the arrays of its force, the force
authority, the default regularisation weight and the drive-lag horizon.

Used by :func:`mrdamper.control.inverse_current`, the quarter car and the C export (re-exported
by :mod:`mrdamper.control.inverse.current`). The LPV input's arrays come from the model's input
object
(:mod:`mrdamper.models.lpv.inputs`), the static maps' from their
:class:`~mrdamper.models.protocols.StaticMapForm`.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from mrdamper.control.damper import DamperModel
from mrdamper.errors import DataValidationError
from mrdamper.models.kernels import sp_force1
from mrdamper.models.lpv import TransferFunctionModel
from mrdamper.models.protocols import (
    InvertibleModel,
    StaticMapForm,
    StepInvertibleModel,
    scheduled_form,
)

__all__ = [
    "DEFAULT_REG_FRACTION",
    "DEFAULT_REG_TIME",
    "dahl_along",
    "default_reg",
    "force_authority",
    "horizon_samples",
    "lpv_hysteresis",
    "lpv_inverse_fields",
    "lpv_law_arrays",
    "model_input_limits",
    "reg_settings",
    "static_map_arrays",
]


def model_input_limits(model: DamperModel) -> tuple[float, float]:
    """Default input limits: the identified ``input_range``.

    For an LPV model (or a static map with a drive lag) it is intersected with the scheduling range
    ``rho_range`` the model was identified on (beyond it the coefficients are extrapolated).
    """
    lo, hi = (float(b) for b in model.input_range)
    rr = getattr(model, "rho_range", None)
    if rr is not None and rr[1] > rr[0]:
        lo, hi = max(lo, float(rr[0])), min(hi, float(rr[1]))
    return lo, hi


def static_map_arrays(model: DamperModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A static map as the arrays of :func:`~mrdamper.models.kernels.sp_force1`.

    SP-1..SP-4 map directly; a Bingham model is ``fc(i) sign(v) + c0(i) v + f0`` with the sign
    written as ``tanh(v / v_eps)`` (``tanh(1e300 v)``, i.e. the exact sign, when ``v_eps = 0``).

    Returns
    -------
    comp, power : ndarray of int64
    theta : ndarray
    f0 : float [N]
    """
    form = model.inverse_form() if isinstance(model, InvertibleModel) else None
    if isinstance(form, StaticMapForm):
        return form.comp, form.power, form.theta, float(form.f0)
    raise TypeError(
        f"model: kind {getattr(model, 'kind', type(model).__name__)!r} is not a static map"
    )


def force_authority(model: DamperModel, v_ref: float) -> float:
    """Steady force range per unit input at velocity ``v_ref`` [N/A] or [N/V].

    ``|F(v_ref, hi) - F(v_ref, lo)| / (hi - lo)`` over the model's ``input_range`` at ``x = 0``;
    for an LPV model the force is the frozen-``rho`` steady state
    ``F0 + sum_j b_j(rho) / (1 + sum_j a_j(rho)) u(v_ref, rho)`` (hysteretic input: with the Dahl
    state of a steady motion, ``z = sign(v_ref)``). It sets the scale of the default
    regularisation weight.

    Parameters
    ----------
    model : InvertibleModel
        LPV model or static map.
    v_ref : float
        Velocity at which the steady force is taken [m/s].
    """
    lo, hi = model_input_limits(model)
    if not hi > lo:
        raise DataValidationError("input_range", f"expected low < high, got {(lo, hi)}")
    if isinstance(model, StepInvertibleModel):  # measured on the model's step
        return model.force_authority(float(v_ref))
    if scheduled_form(model) is not None:
        lpv = cast(TransferFunctionModel, model)
        lpv_input = lpv.lpv_input

        def steady(r: float) -> float:
            gain = float(np.sum(lpv.b(r)) / (1.0 + np.sum(lpv.a(r))))
            return gain * float(lpv_input.steady(float(v_ref), r))

        return abs(steady(hi) - steady(lo)) / (hi - lo)
    comp, power, theta, f0 = static_map_arrays(model)
    return abs(
        sp_force1(0.0, float(v_ref), hi, comp, power, theta, f0)
        - sp_force1(0.0, float(v_ref), lo, comp, power, theta, f0)
    ) / (hi - lo)


#: Default regularisation weight at 200 Hz as a fraction of :func:`force_authority` (where it was
#: chosen).
DEFAULT_REG_FRACTION = 0.5
#: Smoothing time constant of the default weight [s]: the fraction 0.5 at 200 Hz (see
#: :func:`default_reg`).
DEFAULT_REG_TIME = 0.005 / float(np.log(5.0))


def default_reg(
    model: DamperModel, v_ref: float, dt: float, authority: float | None = None
) -> float:
    """Default regularisation weight [N/A] or [N/V] for an inverse running every ``dt`` [s].

    Per sample the regularised input is, to first order, ``q i[k-1] + (1 - q) i_exact`` with
    ``q = reg^2 / (s^2 + reg^2)`` where ``s = |dF/di|``. The default makes this a first-order
    smoothing of time constant :data:`DEFAULT_REG_TIME` where ``s`` equals the force authority at
    ``v_ref`` (:func:`force_authority`), whatever the sample rate::

        reg = force_authority(model, v_ref) * sqrt(q / (1 - q)),   q = exp(-dt / DEFAULT_REG_TIME)

    At 200 Hz this is :data:`DEFAULT_REG_FRACTION` (0.5) times the authority; at 3 kHz about 3.0.
    ``authority`` [N per input unit], when given, replaces :func:`force_authority` (a model
    stepped through its per-sample step, whose authority is measured on the step).
    """
    if not (np.isfinite(dt) and dt > 0):
        raise DataValidationError("dt", f"expected a positive sampling interval [s], got {dt!r}")
    q = float(np.exp(-dt / DEFAULT_REG_TIME))
    auth = force_authority(model, v_ref) if authority is None else float(authority)
    return float(np.sqrt(q / (1.0 - q))) * auth


def reg_settings(
    model: DamperModel, v: np.ndarray, reg: Any, rate: Any, lo: float, hi: float, dt: float
) -> tuple[float, float]:
    """The regularisation weight ``reg`` (default :func:`default_reg` at the peak of ``v``) and
    the input rate bound per second ``rate`` (default none: ``inf``), validated."""
    if reg is None:
        vpk = float(np.max(np.abs(v))) if v.size else 0.0
        lam = default_reg(model, vpk, dt) if vpk > 0 else 0.0
    else:
        if (
            isinstance(reg, bool)
            or not isinstance(reg, (int, float, np.floating))
            or not (np.isfinite(reg) and reg >= 0)
        ):
            raise DataValidationError(
                "reg", f"expected a regularisation weight >= 0 [N per input unit], got {reg!r}"
            )
        lam = float(reg)
    if rate is None:
        step_rate = np.inf
    else:
        if (
            isinstance(rate, bool)
            or not isinstance(rate, (int, float, np.floating))
            or not rate > 0
        ):
            raise DataValidationError(
                "rate", f"expected a positive input rate bound [A/s] or [V/s], got {rate!r}"
            )
        step_rate = float(rate)
    return lam, step_rate


def horizon_samples(eta: float | None, dt: float, horizon: float | None = None) -> int:
    """Samples of the lead horizon of the drive-lag inverse: ``round(horizon / dt)``, at least 1.

    ``horizon`` [s] defaults to the lag time constant ``1 / eta`` [s]; without a drive lag
    (``eta`` None) the horizon is 1 (the present sample).
    """
    if eta is None:
        return 1
    T = 1.0 / float(eta) if horizon is None else float(horizon)
    return max(1, round(T / dt))


def lpv_law_arrays(
    model: TransferFunctionModel,
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Zone-law arrays of an LPV or LTI model for the kernels: ``(mode, gamma_m, gamma_c,
    mu_high, mu_low)`` of its input (:meth:`~mrdamper.models.lpv.inputs.LPVInput.kernel_arrays`;
    :func:`lpv_hysteresis` gives its other settings)."""
    a = model.lpv_input.kernel_arrays()
    return a.mode, a.gamma_m, a.gamma_c, a.mu_high, a.mu_low


def lpv_hysteresis(model: TransferFunctionModel) -> tuple[float, float]:
    """``(blend, stroke)`` of an LPV or LTI model's hysteretic input [-], [m]; ``(0.0, 0.0)`` for
    the static inputs ``"u"`` and ``"v"`` (``blend = 0`` is the static input in every kernel)."""
    a = model.lpv_input.kernel_arrays()
    return a.blend, a.stroke


def lpv_inverse_fields(model: TransferFunctionModel) -> dict[str, Any]:
    """The LPV part of an :class:`~mrdamper.control.inverse._forms.InverseForm` for ``model`` (an
    LPV or
    LTI model): ``is_lpv``, the coefficients ``alpha``, ``beta``, ``offset`` [N], ``stiffness``
    [N/m] of its
    scheduled form and its input's arrays (:func:`lpv_law_arrays`, :func:`lpv_hysteresis`), as
    keyword arguments of :func:`~mrdamper.control.inverse._forms.inverse_form`."""
    form = scheduled_form(model)
    if form is None:
        raise DataValidationError("model", f"expected an LPV or LTI model, got {model.kind!r}")
    mode, gm, gc, mu_h, mu_l = lpv_law_arrays(model)
    blend, stroke = lpv_hysteresis(model)
    return {
        "is_lpv": True,
        "alpha": form.alpha,
        "beta": form.beta,
        "offset": form.offset,
        "mode": mode,
        "gm": gm,
        "gc": gc,
        "mu_high": mu_h,
        "mu_low": mu_l,
        "blend": blend,
        "stroke": stroke,
        "stiffness": float(form.stiffness),
    }


def dahl_along(model: TransferFunctionModel, v: np.ndarray, dt: float) -> tuple[float, np.ndarray]:
    """``(blend, z)``: the Dahl state [-] along the velocity ``v`` [m/s] at the model rate, from
    rest, as the model's own prediction computes it (zeros for a static input)."""
    lpv_input = model.lpv_input
    return lpv_input.kernel_arrays().blend, lpv_input.dahl_along(v, dt)
