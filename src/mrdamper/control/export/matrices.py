"""Export an identified LPV (or LTI) model to a file control-design tools read (MATLAB ``.mat`` or
JSON).

The file holds everything needed to rebuild the model outside mrdamper (all arrays ``float64``;
index ``p`` runs over powers of ``rho``, ``p = 0 .. n_rho``; MATLAB's third index is ``p + 1``):

=================  =====================  ======================================================
name               shape                  meaning
=================  =====================  ======================================================
``alpha``          (n_m, n_rho+1)         ``a_j(rho) = sum_p alpha[j-1, p] rho^p`` (eq. 9)
``beta``           (n_m, n_rho+1)         ``b_j(rho) = sum_p beta[j-1, p] rho^p`` [N s/m]
``A_poly``         (n_m, n_m, n_rho+1)    ``A(rho) = sum_p A_poly[:, :, p] rho^p`` (eq. 12,
                                          companion form; the shift ones sit in ``p = 0``)
``B``              (n_m, 1)               ``[0 ... 0 1]^T`` (eq. 13)
``C_poly``         (1, n_m, n_rho+1)      ``C(rho) = sum_p C_poly[:, :, p] rho^p`` (eq. 11)
``D``              (1, 1)                 0 (eq. 15, ``b_0 = 0``)
``Ts``             scalar                 sampling time [s]
``F0``             scalar                 force offset added to ``C z`` [N]
``k_x``            scalar                 parallel stiffness [N/m]: ``k_x x`` (``x`` the
                                          displacement [m]) is added to the force too
``rho_min``,       scalar                 scheduling range the model was identified on
``rho_max``
``rho_name``       string                 ``"i"`` (coil current [A]) or ``"voltage"`` [V]; with a
                                          drive lag ``rho`` is that input through the lag
``eta``            scalar                 drive-lag rate [1/s] (NaN: none),
                                          ``drho/dt = -eta (rho - input)``
``rho_grid``       (G,)                   grid over the scheduling range
``A_grid``         (n_m, n_m, G)          frozen ``A(rho)`` on the grid
``C_grid``         (1, n_m, G)            frozen ``C(rho)`` on the grid
``poles_re``,      (G, n_m)               frozen poles (discrete time) on the grid
``poles_im``
``max_pole_modulus`` (G,)                 largest frozen-pole modulus on the grid (< 1 stable)
``input_signal``   string                 ``"u"`` (zone-law input), ``"hysteretic"`` (zone-law
                                          input with a Dahl pre-yield state) or ``"v"`` (raw
                                          velocity)
``reading``        string                 reading of eq. 22 (``"continuous"`` or ``"literal"``)
``gamma_m``        (3, d+1)               zone slopes ``m_j(rho) = sum_p gamma_m[j-1, p] rho^p``
                                          [N s/m]
``gamma_c``        (3, d+1)               zone intercepts ``c_j(rho)`` [N]
``mu_high``        (2,)                   ``v_high(rho) = mu_high[0] rho + mu_high[1]`` [m/s]
``mu_low``         (2,)                   ``v_low(rho) = mu_low[0] rho + mu_low[1]`` [m/s]
``blend``          scalar                 share ``lambda`` of the Dahl state in ``u`` [-]
                                          (0: static input)
``stroke``         scalar                 stroke scale ``x_y`` of the Dahl state [m] (NaN: none)
``units``          struct / object        unit of every signal
``provenance``     string (JSON)          identification facts of the model
``schema``,        string, scalar         ``"mrdamper.lpv_export"``, version 1
``schema_version``
``model_kind``     string                 ``"lpv"`` or ``"lti"``
``W_level``        (L,)                   frozen input level of each uncertainty weight
                                          (NaN: records with a varying input); only for a model
                                          fitted with a band (:mod:`mrdamper.uncertainty`)
``W_num``,         (L, 2)                 ``W(s) = (W_num[l, 0] s + W_num[l, 1]) /
``W_den``                                 (W_den[l, 0] s + W_den[l, 1])``, a stable first-order
                                          bound of the relative model error ``|F - F_hat| /
                                          |F_hat|`` on held-out records (continuous time)
``W_k``, ``W_wz``, (L,)                   its gain [-] and zero / pole corners [rad/s]
``W_wp``
=================  =====================  ======================================================

With ``input_signal = "v"`` the zone-law arrays are empty. The LPV input is built from velocity
``v`` and ``rho`` as in :mod:`mrdamper.analysis.scheduling`: ``u = v`` between ``v_low`` and
``v_high``; below ``v_low`` (continuous reading) ``u = v_low + m_1/m_2 (v - v_low)``, above
``v_high`` ``u = v_high + m_3/m_2 (v - v_high)``; literal reading ``u = (m_j v + c_j)/m_2``.
With ``input_signal = "hysteretic"`` (continuous reading) a Dahl state ``z_h`` [-] follows the
motion only, from rest ``z_h[0] = 0``: ``z_h[k] = s + (z_h[k-1] - s) exp(-|dx| / stroke)`` with
``dx = (v[k-1] + v[k]) Ts / 2``, ``s = sign(dx)``, and
``u = (1 - r) [(1 - blend) sat(v) + blend y(z_h) z_h] + r v`` with ``sat(v)`` the clip of ``v`` to
``[v_low, v_high]``, ``r = m_3/m_2`` (``m_1/m_2`` for ``v < 0``), ``y = v_high`` for
``z_h >= 0`` and ``-v_low`` otherwise (:mod:`mrdamper.analysis.hysteretic`). The transfer
function from ``u`` to the force, and so every matrix above, is the same for every input.
The state-space system is ``z[k+1] = A(rho[k]) z[k] + B u[k]``, ``F[k] = C(rho[k]) z[k] + F0``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Literal

import numpy as np

from mrdamper._io import FileKind, atomic_write_text, json_kind, mat_kind
from mrdamper._io.atomic import atomic_write_with
from mrdamper._warn import warn_user
from mrdamper.control.export.statespace import state_space
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel, encode_value
from mrdamper.uncertainty.weight import weight_export_data

__all__ = ["EXPORT_SCHEMA", "export_lpv", "lpv_export_data", "warn_if_unstable"]

#: Schema name written into every export file.
EXPORT_SCHEMA = "mrdamper.lpv_export"
_VERSION = 1
_EXPORT_JSON = json_kind("JSON export", EXPORT_SCHEMA)
_EXPORT_MAT = mat_kind("MAT export", EXPORT_SCHEMA)
#: The kind of file :func:`export_lpv` writes, in either format (``force`` replaces only such a
#: file).
EXPORT_FILE = FileKind(
    "state-space export of mrdamper (.mat or .json)",
    lambda p: _EXPORT_JSON.matches(p) or _EXPORT_MAT.matches(p),
)


def lpv_export_data(model: FittedModel, *, rho_grid: Any = None) -> dict[str, Any]:
    """The export content as a dict of plain values and ``float64`` arrays (see the module
    docstring).

    Parameters
    ----------
    model : LPVModel or LTIModel
    rho_grid : array_like, optional
        Scheduling values for the frozen matrices and poles; default 21 points over the range.
    """
    from mrdamper.models.lpv import TransferFunctionModel

    if not isinstance(model, TransferFunctionModel):
        kind = getattr(model, "kind", type(model).__name__)
        raise DataValidationError(
            "model",
            f"state-space export needs an LPV or LTI model (kinds 'lpv', 'lti'), got kind {kind!r}",
        )
    lo, hi = model.rho_range
    grid = (
        np.linspace(lo, hi, 21) if rho_grid is None else np.asarray(rho_grid, dtype=float).ravel()
    )
    if grid.size == 0 or not np.all(np.isfinite(grid)):
        raise DataValidationError(
            "rho_grid", f"expected a non-empty finite array, got {rho_grid!r}"
        )
    n, n_p = model.alpha.shape
    A_poly = np.zeros((n, n, n_p))
    A_poly[:-1, 1:, 0] = np.eye(n - 1)
    A_poly[-1, :, :] = -model.alpha[::-1, :]
    C_poly = np.zeros((1, n, n_p))
    C_poly[0, :, :] = model.beta[::-1, :]
    mats = [state_space(model, float(r)) for r in grid]
    poles = np.array([np.sort_complex(m.poles) for m in mats]).reshape(grid.size, n)
    lpv_input = model.lpv_input
    laws = lpv_input.laws
    saved = lpv_input.saved()  # input_signal; stroke and blend None unless hysteretic
    elec = "A" if model.input == "i" else "V"
    return {
        "schema": EXPORT_SCHEMA,
        "schema_version": _VERSION,
        "model_kind": model.kind,
        "alpha": np.array(model.alpha),
        "beta": np.array(model.beta),
        "A_poly": A_poly,
        "B": mats[0].B.copy(),
        "C_poly": C_poly,
        "D": mats[0].D.copy(),
        "Ts": 1.0 / model.fs,
        "F0": float(model.offset),
        "k_x": float(model.stiffness),
        "rho_min": float(lo),
        "rho_max": float(hi),
        "rho_name": model.input,
        "eta": float("nan") if model.eta is None else float(model.eta),
        "rho_grid": grid,
        "A_grid": np.stack([m.A for m in mats], axis=-1),
        "C_grid": np.stack([m.C for m in mats], axis=-1),
        "poles_re": poles.real.copy(),
        "poles_im": poles.imag.copy(),
        "max_pole_modulus": np.abs(poles).max(axis=1) if n else np.zeros(grid.size),
        "input_signal": saved["input_signal"],
        "reading": model.reading,
        "gamma_m": np.zeros((0, 0)) if laws is None else np.array(laws.gamma_m),
        "gamma_c": np.zeros((0, 0)) if laws is None else np.array(laws.gamma_c),
        "mu_high": np.zeros(0) if laws is None else np.array(laws.mu_high),
        "mu_low": np.zeros(0) if laws is None else np.array(laws.mu_low),
        "blend": 0.0 if saved["blend"] is None else float(saved["blend"]),
        "stroke": float("nan") if saved["stroke"] is None else float(saved["stroke"]),
        "units": {
            "Ts": "s",
            "F0": "N",
            "F": "N",
            "u": "m/s",
            "v": "m/s",
            "x": "m",
            "rho": elec,
            "eta": "1/s",
            "beta": "N s/m",
            "gamma_m": "N s/m",
            "gamma_c": "N",
            "mu_high": "m/s",
            "mu_low": "m/s",
            "blend": "-",
            "stroke": "m",
        },
        "provenance": json.dumps(encode_value(dict(model.provenance)), allow_nan=True, default=str),
    }


def warn_if_unstable(model: FittedModel) -> None:
    """Warn (one line) when ``model`` is not frozen-stable over its scheduling range, or (a P-15
    model) fails its sufficient conditions for stability on its input range.

    Every export (``.mat``, ``.json``, C, FMU) says so the same way; models without frozen poles
    or a stability certificate (static maps) are never warned about.

    Parameters
    ----------
    model : FittedModel
        The model being exported.
    """
    pmax = model.max_pole_modulus() if hasattr(model, "max_pole_modulus") else 0.0
    if pmax >= 1.0:
        warn_user(
            f"{model.kind}: model is not frozen-stable over its scheduling range (largest frozen "
            f"pole modulus {pmax:.4f} >= 1); exporting it anyway, check the poles before control "
            "design",
            RuntimeWarning,
        )
    cert = model.stability_certificate() if hasattr(model, "stability_certificate") else None
    if cert is not None and not cert["stable_by_construction"]:
        worst = min(("c", "m", "a", "b"), key=cert["min_bernstein"].get)
        warn_user(
            f"{model.kind}: model is not stable by construction on its input range (coefficient "
            f"{worst} not positive there: relative Bernstein minimum "
            f"{cert['min_bernstein'][worst]:.3g}); its free run may diverge; exporting it "
            "anyway, check it before control design",
            RuntimeWarning,
        )


def export_lpv(
    model: FittedModel,
    path: str | Path,
    *,
    format: Literal["mat", "json"] = "mat",
    rho_grid: Any = None,
    force: bool = False,
) -> Path:
    """Write the model's matrices for control design, atomically.

    Parameters
    ----------
    model : LPVModel or LTIModel
    path : str or Path
        Output file.
    format : {"mat", "json"}
        MATLAB v5 file (:func:`scipy.io.savemat`; read with ``load`` in MATLAB or
        :func:`scipy.io.loadmat`) or JSON (arrays as ``{"__ndarray__", "dtype", "shape"}``,
        row-major).
    rho_grid : array_like, optional
        Grid of the frozen matrices and poles (default 21 points over the scheduling range).
    force : bool
        Overwrite an existing file.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    DataValidationError
        Not an LPV / LTI model, unknown format, bad grid.
    OutputExistsError
        ``path`` exists and ``force`` is False.
    """
    if format not in ("mat", "json"):
        raise DataValidationError("format", f"expected 'mat' or 'json', got {format!r}")
    data = {**lpv_export_data(model, rho_grid=rho_grid), **weight_export_data(model)}
    warn_if_unstable(model)
    if format == "json":
        text = json.dumps(encode_value(data), indent=1, allow_nan=False)
        return atomic_write_text(path, text + "\n", force=force, kind=EXPORT_FILE)
    from scipy.io import savemat

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            savemat(fh, data, oned_as="column")

    return atomic_write_with(path, write, force=force, kind=EXPORT_FILE)
