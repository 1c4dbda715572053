"""An uncertainty weight W(s) for robust control: a bound of the relative model error.

Robust LPV / H-infinity design takes a nominal model ``G`` and a set
``{G (1 + W Delta) : ||Delta||_inf <= 1}``: the weight ``W(s)`` must bound the relative
(output-multiplicative) error ``|F - F_hat| / |F_hat|`` at every frequency. The band's
calibration (:mod:`mrdamper.uncertainty.calibrate`) stores that error, measured on the held-out
records of its folds (:mod:`mrdamper.uncertainty.spectra`). Here, per frozen electrical level
(held-out records whose input is constant, grouped within
:data:`~mrdamper.uncertainty.spectra.FROZEN_SHARE` of the model's input range; records with a
varying input form one more group, level NaN), a stable first-order weight::

    W(s) = k (s / w_z + 1) / (s / w_p + 1),     k, w_z, w_p > 0

is fitted as the tightest bound (smallest mean log-ratio ``log |W(j w)| / rel``) over a grid of
corner frequencies, with ``k`` the smallest gain that bounds every measured point: on the
records it is built from it holds by construction, at every measured frequency bin.
:func:`bound_share` says how often it holds on other records.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.uncertainty.band import band_of
from mrdamper.uncertainty.spectra import FROZEN_SHARE

__all__ = ["Weight", "bound_share", "fit_weight", "uncertainty_weights", "weight_export_data"]

#: Candidate corner frequencies per decade of the grid search.
CORNERS_PER_DECADE = 6


@dataclass(frozen=True)
class Weight:
    """One first-order uncertainty weight ``W(s) = k (s/w_z + 1)/(s/w_p + 1)``.

    Attributes
    ----------
    level : float
        The frozen electrical level [A] or [V] (NaN: records with a varying input).
    k : float
        Low-frequency gain [-].
    w_z, w_p : float
        Zero and pole corner frequencies [rad/s].
    records : tuple of str
        Held-out records it was fitted on.
    """

    level: float
    k: float
    w_z: float
    w_p: float
    records: tuple[str, ...] = ()

    @property
    def num(self) -> tuple[float, float]:
        """Numerator coefficients, descending powers of s."""
        return (self.k / self.w_z, self.k)

    @property
    def den(self) -> tuple[float, float]:
        """Denominator coefficients, descending powers of s."""
        return (1.0 / self.w_p, 1.0)

    def magnitude(self, freq_hz: np.ndarray) -> np.ndarray:
        """``|W(j 2 pi f)|`` [-] at frequencies ``freq_hz`` [Hz]."""
        w = 2 * np.pi * np.asarray(freq_hz, dtype=np.float64)
        return self.k * np.abs((1j * w / self.w_z + 1) / (1j * w / self.w_p + 1))

    def transfer_function(self) -> Any:
        """The weight as a python-control ``TransferFunction`` (continuous time)."""
        import control

        return control.tf(list(self.num), list(self.den))


def fit_weight(
    freq_hz: np.ndarray, rel: np.ndarray, level: float = float("nan"), records: Sequence[str] = ()
) -> Weight:
    """The tightest first-order weight bounding every point ``(freq_hz, rel)``.

    Parameters
    ----------
    freq_hz : ndarray
        Frequencies [Hz] of the measured relative errors.
    rel : ndarray
        Relative error magnitudes [-] (> 0).
    level : float
        Electrical level the points belong to.
    records : sequence of str
        Names of the records the points come from.
    """
    f = np.asarray(freq_hz, dtype=np.float64)
    r = np.maximum(np.asarray(rel, dtype=np.float64), 1e-12)
    if f.size == 0 or f.size != r.size:
        raise DataValidationError("rel", "expected as many relative errors as frequencies (> 0)")
    w = 2 * np.pi * f
    lo, hi = w.min() / 10, w.max() * 10
    n = max(2, int(np.ceil(np.log10(hi / lo) * CORNERS_PER_DECADE)) + 1)
    grid = np.geomspace(lo, hi, n)
    best: tuple[float, float, float, float] | None = None
    for wz in grid:
        for wp in grid:
            shape = np.abs((1j * w / wz + 1) / (1j * w / wp + 1))
            k = float(np.max(r / shape))
            cost = float(np.mean(np.log(k * shape / r)))
            if best is None or cost < best[0] - 1e-12:
                best = (cost, k, float(wz), float(wp))
    assert best is not None
    _, k, wz, wp = best
    return Weight(float(level), k * (1 + 1e-9), wz, wp, tuple(records))


def _groups(spectra: Sequence[Mapping[str, Any]], span: float) -> list[list[Mapping[str, Any]]]:
    frozen = sorted((s for s in spectra if s.get("frozen")), key=lambda s: float(s["level"]))
    groups: list[list[Mapping[str, Any]]] = []
    for s in frozen:
        if groups and abs(float(s["level"]) - float(groups[-1][0]["level"])) <= FROZEN_SHARE * span:
            groups[-1].append(s)
        else:
            groups.append([s])
    varying = [s for s in spectra if not s.get("frozen")]
    return groups + ([varying] if varying else [])


def uncertainty_weights(model: Any) -> list[Weight]:
    """The uncertainty weights of ``model``: one per frozen level of its held-out records.

    Parameters
    ----------
    model : FittedModel
        A model with a band (:func:`mrdamper.uncertainty.fit_with_band`).

    Raises
    ------
    DataValidationError
        The model carries no band (so no held-out error to bound).
    """
    band = band_of(model)
    if band is None:
        raise DataValidationError(
            "model", f"{model.kind}: no band stored, so no uncertainty weight (fit with --band)"
        )
    span = float(model.input_range[1] - model.input_range[0])
    out = []
    for group in _groups(band.spectra, span):
        f = np.concatenate([np.asarray(s["freq"], dtype=np.float64) for s in group])
        r = np.concatenate([np.asarray(s["rel"], dtype=np.float64) for s in group])
        level = float(np.mean([s["level"] for s in group])) if group[0].get("frozen") else np.nan
        out.append(fit_weight(f, r, level, [str(s["record"]) for s in group]))
    return out


def bound_share(weights: Sequence[Weight], spectra: Sequence[Mapping[str, Any]]) -> float:
    """Share of the measured points of ``spectra`` that the weight of their level bounds [-].

    A spectrum is compared with the weight of the nearest frozen level (the varying-input
    weight for a varying input, else the nearest level's).
    """
    frozen = [w for w in weights if np.isfinite(w.level)]
    varying = [w for w in weights if not np.isfinite(w.level)]
    held = total = 0
    for s in spectra:
        pool = varying if (not s.get("frozen") and varying) else (frozen or varying)
        if not pool:
            continue
        w = min(pool, key=lambda c: abs(c.level - float(s["level"])) if frozen else 0.0)
        r = np.asarray(s["rel"], dtype=np.float64)
        held += int(np.sum(r <= w.magnitude(np.asarray(s["freq"]))))
        total += r.size
    return held / total if total else float("nan")


def weight_export_data(model: Any) -> dict[str, Any]:
    """The weights as arrays for a ``.mat`` / JSON export ({} for a model without a band).

    ``W_level`` (L,) [A] or [V] (NaN: varying input), ``W_num`` and ``W_den`` (L, 2) the
    coefficients of ``W(s)`` in descending powers of ``s``, ``W_k``, ``W_wz``, ``W_wp`` (L,)
    gain [-] and corners [rad/s].
    """
    if band_of(model) is None:
        return {}
    ws = uncertainty_weights(model)
    return {
        "W_level": np.array([w.level for w in ws], dtype=np.float64),
        "W_num": np.array([w.num for w in ws], dtype=np.float64).reshape(-1, 2),
        "W_den": np.array([w.den for w in ws], dtype=np.float64).reshape(-1, 2),
        "W_k": np.array([w.k for w in ws], dtype=np.float64),
        "W_wz": np.array([w.w_z for w in ws], dtype=np.float64),
        "W_wp": np.array([w.w_p for w in ws], dtype=np.float64),
    }
