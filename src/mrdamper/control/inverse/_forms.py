"""The forms the compiled controller reads: the damper model's inverse and the controller.

A form is a ``NamedTuple`` of plain numbers and arrays, built once in Python and passed whole to
the numba kernels (as the models' per-sample steps pass theirs, :mod:`mrdamper.models.step`), so
the kernels' argument lists are written once, here:

* :class:`InverseForm`: the damper model as its inverse reads it (a static map or an LPV model
  with its drive lag and zone-law / hysteretic input) and the inverse's settings; read by the
  offline inverse (:func:`~mrdamper.control.inverse._inverse_kernels.lpv_inverse_reg_hys`), the
  drive-lag
  horizon step and the controller;
* :class:`ControllerForm`: the controller (code, gains, input limits, rate bound, control
  sample) with its :class:`InverseForm`; read by
  :func:`~mrdamper.control.loop._quarter_car_kernels.control_sample` in the quarter-car kernels.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

__all__ = ["ControllerForm", "InverseForm", "frozen", "inverse_form"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def frozen(a: npt.ArrayLike, dtype: type = np.float64) -> npt.NDArray[Any]:
    """``a`` as a read-only C-contiguous array of ``dtype`` (a view, no copy, when it already
    has that type and layout).

    Every array of a form is read-only, whatever the model it comes from (a frozen LPV model's
    coefficients are; the empty defaults built here would not be): a read-only and a writable
    array are different argument types to numba, so the controller's kernels compile once for
    every kind instead of once per mutability.
    """
    out: npt.NDArray[Any] = np.ascontiguousarray(a, dtype=dtype)
    if out.flags.writeable:
        out = out.view()
        out.flags.writeable = False
    return out


class InverseForm(NamedTuple):
    """The damper model as its inverse reads it, and the inverse's settings.

    Attributes
    ----------
    is_lpv : bool
        LPV model (``alpha`` .. ``stroke``) or static map (``comp`` .. ``f0``).
    comp, power : ndarray of int64
        Static map: term codes and powers (:func:`~mrdamper.models.kernels.sp_force1`).
    theta : ndarray
        Static map: coefficients.
    f0 : float
        Static map: force at rest [N].
    alpha, beta : ndarray, shape (n_m, n_p)
        LPV denominator / numerator coefficients (polynomials in ``rho``).
    offset : float
        LPV output offset ``F0`` [N].
    lag : float
        Drive lag over one sample, ``exp(-eta dt)`` [-]; negative: no lag.
    mode : int
        Zone-law reading of the LPV input (:data:`~mrdamper.models.kernels.MODE_V` ...).
    gm, gc : ndarray, shape (3, degree + 1)
        Zone-law slopes and intercepts.
    mu_high, mu_low : ndarray, shape (2,)
        Breakpoint laws [m/s].
    blend : float
        Share of the Dahl state in the LPV input (0: static input).
    stroke : float
        Stroke scale of the Dahl state [m].
    stiffness : float
        LPV parallel stiffness ``k_x`` [N/m]: the force is the polynomial in ``rho`` plus
        ``k_x x`` (the inverse takes it out of the target).
    horizon : int
        Lead horizon of the inverse with a drive lag [samples] (1: the present sample only).
    lam2 : float
        Square of the regularisation weight [N^2 per input unit^2].
    n_grid : int
        Intervals of the inverse's search grid.
    """

    is_lpv: bool
    comp: IntArray
    power: IntArray
    theta: FloatArray
    f0: float
    alpha: FloatArray
    beta: FloatArray
    offset: float
    lag: float
    mode: int
    gm: FloatArray
    gc: FloatArray
    mu_high: FloatArray
    mu_low: FloatArray
    blend: float
    stroke: float
    stiffness: float
    horizon: int
    lam2: float
    n_grid: int


class ControllerForm(NamedTuple):
    """The controller as :func:`~mrdamper.control.loop._quarter_car_kernels.control_sample` reads
    it.

    Attributes
    ----------
    ctrl : int
        Controller code (:mod:`mrdamper.control.loop._quarter_car_kernels`).
    gains : ndarray
        ``[c_sky, c_gnd, alpha, i_const]`` [N s/m, N s/m, -, input unit].
    lo, hi : float
        Input limits [input unit].
    rate_step : float
        Largest input change per control sample [input unit].
    dt_c : float
        Control sample [s].
    inverse : InverseForm
        The damper model's inverse.
    """

    ctrl: int
    gains: FloatArray
    lo: float
    hi: float
    rate_step: float
    dt_c: float
    inverse: InverseForm


def inverse_form(
    *,
    lam: float,
    n_grid: int,
    horizon: int = 1,
    lag: float = -1.0,
    is_lpv: bool = False,
    comp: IntArray | None = None,
    power: IntArray | None = None,
    theta: FloatArray | None = None,
    f0: float = 0.0,
    alpha: FloatArray | None = None,
    beta: FloatArray | None = None,
    offset: float = 0.0,
    mode: int = 0,
    gm: FloatArray | None = None,
    gc: FloatArray | None = None,
    mu_high: FloatArray | None = None,
    mu_low: FloatArray | None = None,
    blend: float = 0.0,
    stroke: float = 0.0,
    stiffness: float = 0.0,
) -> InverseForm:
    """An :class:`InverseForm` with the kernels' types (the parts not given are empty; every
    array read-only, :func:`frozen`).

    Parameters
    ----------
    lam : float
        Regularisation weight [N per input unit] (the form holds its square).
    n_grid, horizon, lag, is_lpv, comp, power, theta, f0, alpha, beta, offset, mode, gm, gc, \
mu_high, mu_low, blend, stroke, stiffness
        As the attributes of :class:`InverseForm`.
    """
    empty2 = np.zeros((1, 1))

    def arr(a: npt.ArrayLike | None, default: FloatArray) -> FloatArray:
        return frozen(default if a is None else a)

    def ints(a: npt.ArrayLike | None) -> IntArray:
        return frozen(np.zeros(0, np.int64) if a is None else a, np.int64)

    return InverseForm(
        bool(is_lpv),
        ints(comp),
        ints(power),
        arr(theta, np.zeros(0)),
        float(f0),
        arr(alpha, empty2),
        arr(beta, empty2),
        float(offset),
        float(lag),
        int(mode),
        arr(gm, np.zeros((3, 1))),
        arr(gc, np.zeros((3, 1))),
        arr(mu_high, np.zeros(2)),
        arr(mu_low, np.zeros(2)),
        float(blend),
        float(stroke),
        float(stiffness),
        int(horizon),
        float(lam) * float(lam),
        int(n_grid),
    )
