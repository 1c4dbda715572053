"""State-space realisation of the LPV input-output model (paper eqs. 10-15).

Controllable canonical form with ``B = [0 ... 0 1]^T`` (eq. 13; reading notes item 3)::

    z[k+1] = A(rho) z[k] + B u[k]
    f[k]   = C(rho) z[k] + D u[k] (+ F0 + k_x x[k])

    A(rho) = companion matrix, last row [-a_n(rho) ... -a_1(rho)]
    C(rho) = [b_n(rho) ... b_1(rho)]      (b0 = 0, so D = 0, eq. 15)

At a constant ``rho`` this realisation has exactly the transfer function of eqs. (7-9). When
``rho`` varies the input-output model identified in the paper (coefficients evaluated at ``rho[k]``
for every lag) and the state-space model with ``A(rho[k])`` are different LPV systems; the
state-space form is the one to use for LPV control design, and it agrees with the identified model
whenever ``rho`` is constant (or slowly varying). The offset ``F0`` and a parallel stiffness
``k_x`` [N/m] on the displacement ``x`` are static terms outside the linear system from ``u``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.damper import DamperModel
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models.lpv import TransferFunctionModel

__all__ = [
    "ControlGrid",
    "StateSpaceMatrices",
    "control_grid",
    "frozen_stability",
    "simulate_state_space",
    "state_space",
    "to_control",
]


def _check_model(model: DamperModel) -> None:
    if not (hasattr(model, "alpha") and hasattr(model, "beta") and hasattr(model, "fs")):
        raise DataValidationError(
            "model",
            f"expected an LPV or LTI model (kinds 'lpv', 'lti'), got {type(model).__name__}",
        )


@dataclass(frozen=True, eq=False)
class StateSpaceMatrices:
    """Frozen-``rho`` realisation of an LPV model.

    Attributes
    ----------
    A : ndarray, shape (n_m, n_m)
    B : ndarray, shape (n_m, 1)
    C : ndarray, shape (1, n_m)
        Maps the state to force [N].
    D : ndarray, shape (1, 1)
    dt : float
        Sampling interval [s].
    rho : float
        Scheduling value the matrices were evaluated at.
    offset : float
        Output force offset ``F0`` [N] added to ``C z`` (not part of the linear system).
    stiffness : float
        Parallel stiffness ``k_x`` [N/m]: ``k_x x`` is added to the force too (not part of the
        linear system from ``u``).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float
    rho: float
    offset: float
    stiffness: float = 0.0

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A`` (discrete-time poles)."""
        return np.linalg.eigvals(self.A)

    def to_frame(self) -> pd.DataFrame:
        """The four matrices stacked as one table ``[[A, B], [C, D]]``."""
        top = np.hstack((self.A, self.B))
        bottom = np.hstack((self.C, self.D))
        n = self.A.shape[0]
        return pd.DataFrame(
            np.vstack((top, bottom)),
            index=[f"z{k + 1}" for k in range(n)] + ["f"],
            columns=[f"z{k + 1}" for k in range(n)] + ["u"],
        )


def state_space(model: TransferFunctionModel, rho: float) -> StateSpaceMatrices:
    """Evaluate ``A(rho), B, C(rho), D`` (eqs. 10-15) for one scheduling value.

    Parameters
    ----------
    model : LPVModel or LTIModel
        Identified model.
    rho : float
        Scheduling value (current [A] or filtered voltage [V]).

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.models.lpv import LPVModel
    >>> m = LPVModel(alpha=np.array([[-0.5]]), beta=np.array([[2.0]]), fs=100.0, input_signal="v")
    >>> ss = state_space(m, 0.0)
    >>> ss.A, ss.C
    (array([[0.5]]), array([[2.]]))
    """
    _check_model(model)
    r = float(rho)
    if not np.isfinite(r):
        raise DataValidationError("rho", f"expected a finite scheduling value, got {rho!r}")
    n = model.n_m
    a = model.a(r)
    b = model.b(r)
    A = np.zeros((n, n))
    A[:-1, 1:] = np.eye(n - 1)
    A[-1, :] = -a[::-1]
    B = np.zeros((n, 1))
    B[-1, 0] = 1.0
    C = b[::-1].reshape(1, n).copy()
    D = np.zeros((1, 1))
    return StateSpaceMatrices(
        A=A,
        B=B,
        C=C,
        D=D,
        dt=1.0 / model.fs,
        rho=r,
        offset=float(model.offset),
        stiffness=float(model.stiffness),
    )


def to_control(model: TransferFunctionModel, rho: float) -> Any:
    """Frozen-``rho`` model as a discrete ``control.StateSpace`` (needs the ``control`` extra).

    Parameters
    ----------
    model : LPVModel or LTIModel
        The transfer-function model.
    rho : float
        Frozen scheduling value.

    Raises
    ------
    ImportError
        If python-control is not installed (``pip install "mrdamper[control]"``).
    """
    try:
        import control
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise ImportError(
            "to_control needs python-control; install the extra with: "
            'pip install "mrdamper[control]"'
        ) from exc
    ss = state_space(model, rho)
    return control.ss(ss.A, ss.B, ss.C, ss.D, ss.dt)


def frozen_stability(
    model: TransferFunctionModel, n_grid: int = 51, rho: Any = None
) -> pd.DataFrame:
    """Frozen-pole stability over the scheduling range.

    Parameters
    ----------
    model : LPVModel or LTIModel
    n_grid : int
        Number of grid points over ``model.rho_range`` (when ``rho`` is not given).
    rho : array_like, optional
        Scheduling values to check.

    Returns
    -------
    DataFrame
        Columns ``rho``, ``max_pole_modulus`` and ``stable`` (all frozen poles inside the unit
        circle). Frozen stability is necessary, not sufficient, under fast-varying ``rho``.
    """
    _check_model(model)
    if rho is None:
        rho_lo, rho_hi = model.rho_range
        grid = np.linspace(rho_lo, rho_hi, n_grid)
    else:
        grid = np.atleast_1d(np.asarray(rho, float))
    mods = [float(np.max(np.abs(state_space(model, r).poles))) for r in grid]
    return pd.DataFrame({"rho": grid, "max_pole_modulus": mods, "stable": np.array(mods) < 1.0})


def simulate_state_space(
    model: TransferFunctionModel, u: Any, rho: Any, *, bound: float | None = None, x: Any = None
) -> np.ndarray:
    """Simulate the state-space LPV system ``z[k+1] = A(rho[k]) z[k] + B u[k]``,
    ``f = C(rho[k]) z + F0 + k_x x[k]``.

    Parameters
    ----------
    model : LPVModel or LTIModel
    u : array_like
        LPV input at the model rate [m/s].
    rho : array_like or float
        Scheduling variable at the model rate (a scalar means constant).
    bound : float, optional
        Output magnitude regarded as divergence [N]; default the model's ``force_bound``.
    x : array_like, optional
        Displacement at the model rate [m]; needed when the model has a stiffness ``k_x``.

    Returns
    -------
    ndarray
        Force [N] from zero initial state.
    """
    _check_model(model)
    u = np.asarray(u, dtype=float)
    k_x = float(model.stiffness)
    if k_x != 0.0:
        if x is None:
            raise DataValidationError(
                "x", f"the model has a stiffness k_x = {k_x:.4g} N/m; give the displacement [m]"
            )
        xs = np.asarray(x, dtype=float)
        if xs.shape != u.shape:
            raise DataValidationError("x", f"expected shape {u.shape} (as u), got {xs.shape}")
    rho_a = np.broadcast_to(np.asarray(rho, dtype=float), u.shape)
    lim = model.force_bound if bound is None else bound
    n = model.n_m
    z = np.zeros(n)
    out = np.empty(u.size)
    cache: dict[float, StateSpaceMatrices] = {}
    for k in range(u.size):
        r = float(rho_a[k])
        ss = cache.get(r)
        if ss is None:
            ss = state_space(model, r)
            if len(cache) < 64:
                cache[r] = ss
        f = float(ss.C[0] @ z)
        if not abs(f) <= lim:
            raise SimulationDivergedError(model.kind, k, f"state-space output exceeded {lim:.3g} N")
        out[k] = f + ss.offset + (k_x * xs[k] if k_x != 0.0 else 0.0)
        z = ss.A @ z + ss.B[:, 0] * u[k]
    return out


@dataclass(frozen=True, eq=False)
class ControlGrid:
    """Frozen-``rho`` python-control systems of an LPV model on a grid of scheduling values.

    Attributes
    ----------
    rho : ndarray
        Scheduling values [A] or [V].
    systems : list of control.StateSpace
        Discrete systems (sampling time ``1 / fs``) from the LPV input ``u`` [m/s] to the force
        ``C z`` [N] (the offset ``F0`` is not part of the linear system), one per ``rho``. The
        same for every LPV input; a hysteretic input's ``u`` is rebuilt from the motion with the
        model's ``stroke`` and ``blend`` (:mod:`mrdamper.analysis.hysteretic`).
    stability : DataFrame
        :func:`frozen_stability` on the same grid, with the DC gain of each system [N s/m] (the
        static slope ``F / u`` at constant ``rho``; NaN where the system has a pole at 1).
    """

    rho: np.ndarray
    systems: list[Any]
    stability: pd.DataFrame

    def to_frame(self) -> pd.DataFrame:
        """The stability table."""
        return self.stability

    def __getitem__(self, k: int) -> Any:
        return self.systems[k]

    def __len__(self) -> int:
        return len(self.systems)


def control_grid(model: TransferFunctionModel, rho: Any = None, n_grid: int = 11) -> ControlGrid:
    """python-control systems of the LPV model at ``rho`` (default ``n_grid`` points over its
    range).

    Parameters
    ----------
    model : LPVModel or LTIModel
        The transfer-function model.
    rho : array_like, optional
        Scheduling values at which to freeze the model; default ``n_grid`` points over
        ``rho_range``.
    n_grid : int
        Number of grid points when ``rho`` is None.

    Raises
    ------
    ImportError
        If python-control is not installed (``pip install "mrdamper[control]"``).
    """
    import control

    _check_model(model)
    if rho is None:
        lo, hi = (float(b) for b in model.rho_range)
        grid = np.linspace(lo, hi, n_grid)
    else:
        grid = np.atleast_1d(np.asarray(rho, dtype=float))
    if grid.size == 0 or not np.all(np.isfinite(grid)):
        raise DataValidationError("rho", f"expected a non-empty finite grid, got {rho!r}")
    systems = [to_control(model, float(r)) for r in grid]
    table = frozen_stability(model, rho=grid)
    gains = []
    for s in systems:
        try:
            gains.append(float(np.real(control.dcgain(s))))
        except (ValueError, np.linalg.LinAlgError, ZeroDivisionError):
            gains.append(float("nan"))
    table["dc_gain"] = gains
    return ControlGrid(rho=grid, systems=systems, stability=table)
