"""The prediction band of a model: a scaled conformal band stored in the model file.

A :class:`Band` turns a free-run force prediction ``F_hat`` [N] into a lower and an upper force
at a coverage level::

    s(t)     = a + b |F_hat(t)| + c m(t)           (scale of the error at the operating point)
    F_lo,hi  = F_hat(t) -/+ q(level) s(t)

with ``m(t)`` the RMS of ``F_hat`` over a centred window of :data:`WINDOW_S` seconds (the force
level of the current cycle: the error of a damper model grows with the force amplitude, current
and speed, more than with the instantaneous force, which crosses zero where the hysteresis turns).

``q(level)`` is the conformal quantile of the normalised held-out residuals
``|F - F_hat| / s`` (:mod:`mrdamper.uncertainty.calibrate`), stored on a grid of levels
:data:`LEVELS` (0.50 to 0.99 in steps of 0.01) and interpolated linearly between them.

The band lives in the model's provenance under ``"band"`` (a mapping of numbers and lists, so
that every model file, old or new, reads the same way and a file without it still loads):
:func:`band_of` reads it back and checks it, naming the field of a damaged entry.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError, SchemaError

__all__ = ["LEVELS", "PROVENANCE_KEY", "WINDOW_S", "Band", "band_of", "check_level", "moving_rms"]

#: Coverage levels whose quantiles a band stores [-].
LEVELS: tuple[float, ...] = tuple(round(0.50 + 0.01 * k, 2) for k in range(50))
#: Key of the band in a model's provenance.
PROVENANCE_KEY = "band"
#: Window of the moving RMS force level ``m(t)`` [s].
WINDOW_S = 1.0


def moving_rms(F: np.ndarray, dt: float, window: float = WINDOW_S) -> np.ndarray:
    """RMS of ``F`` [N] over a centred window of ``window`` seconds (shortened at the ends).

    Parameters
    ----------
    F : ndarray
        Force [N], uniformly sampled.
    dt : float
        Sampling interval [s].
    window : float
        Window length [s].
    """
    a = np.asarray(F, dtype=np.float64)
    half = max(0, round(window / dt) // 2)
    c = np.concatenate([[0.0], np.cumsum(a * a)])
    k = np.arange(a.size)
    lo, hi = np.clip(k - half, 0, a.size), np.clip(k + half + 1, 0, a.size)
    return np.sqrt(np.maximum(c[hi] - c[lo], 0.0) / (hi - lo))


def check_level(level: Any, field_name: str = "interval") -> float:
    """The coverage level as a float in [0.5, 0.99], or one line naming ``field_name``.

    Parameters
    ----------
    level : float
        Nominal coverage [-], e.g. 0.9.
    field_name : str
        Name of the option or argument in the message.
    """
    ok = isinstance(level, (int, float)) and not isinstance(level, bool)
    if not ok or not (LEVELS[0] <= float(level) <= LEVELS[-1]):
        raise DataValidationError(
            field_name,
            f"expected a coverage level between {LEVELS[0]} and {LEVELS[-1]}, got {level!r}",
        )
    return float(level)


@dataclass(frozen=True)
class Band:
    """A calibrated prediction band (see the module text).

    Attributes
    ----------
    a : float
        Constant part of the error scale [N] (> 0).
    b : float
        Part of the error scale proportional to ``|F_hat|`` [-] (>= 0).
    c : float
        Part proportional to the moving RMS ``m`` of ``F_hat`` [-] (>= 0).
    quantiles : tuple of float
        Conformal quantile of ``|F - F_hat| / s`` at each level of :data:`LEVELS` [-].
    method : str
        How the held-out residuals were obtained (``"record folds"``, ``"time blocks"``).
    n_samples : int
        Number of held-out samples the quantiles come from.
    folds : tuple of str
        One line per calibration fold (what it held out).
    spectra : tuple of mapping
        Relative-error spectra of the held-out records (:mod:`mrdamper.uncertainty.spectra`),
        the data of the uncertainty weight (:mod:`mrdamper.uncertainty.weight`).
    cost_s : float
        CPU time of the calibration fits [s].
    """

    a: float
    b: float
    quantiles: tuple[float, ...]
    c: float = 0.0
    method: str = "record folds"
    n_samples: int = 0
    folds: tuple[str, ...] = ()
    spectra: tuple[Mapping[str, Any], ...] = field(default=(), repr=False)
    cost_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.a) and self.a > 0):
            raise DataValidationError("band.a", f"expected a positive scale [N], got {self.a!r}")
        for name in ("b", "c"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise DataValidationError(f"band.{name}", f"expected a scale >= 0, got {value!r}")
        q = tuple(float(v) for v in self.quantiles)
        if len(q) != len(LEVELS) or not all(math.isfinite(v) and v >= 0 for v in q):
            raise DataValidationError(
                "band.quantiles", f"expected {len(LEVELS)} finite numbers >= 0 (one per level)"
            )
        object.__setattr__(self, "quantiles", tuple(np.maximum.accumulate(q).tolist()))

    def quantile(self, level: float) -> float:
        """The normalised half-width ``q(level)`` [-] (linear between stored levels)."""
        lv = check_level(level)
        return float(np.interp(lv, LEVELS, self.quantiles))

    def scale(self, F_hat: np.ndarray, dt: float) -> np.ndarray:
        """The error scale ``s = a + b |F_hat| + c m`` [N] at each sample (``dt`` [s])."""
        F = np.asarray(F_hat, dtype=np.float64)
        s = self.a + self.b * np.abs(F)
        return s + self.c * moving_rms(F, dt) if self.c else s

    def interval(
        self, F_hat: np.ndarray, level: float = 0.9, dt: float = 1e-3
    ) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper force [N] around the prediction ``F_hat`` [N] (sampled every ``dt``
        [s]) at ``level``."""
        F = np.asarray(F_hat, dtype=np.float64)
        half = self.quantile(level) * self.scale(F, dt)
        return F - half, F + half

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data (stored in the model's provenance under ``"band"``)."""
        return {
            "a": float(self.a),
            "b": float(self.b),
            "c": float(self.c),
            "window_s": WINDOW_S,
            "levels": list(LEVELS),
            "quantiles": [float(v) for v in self.quantiles],
            "method": self.method,
            "n_samples": int(self.n_samples),
            "folds": list(self.folds),
            "spectra": [dict(s) for s in self.spectra],
            "cost_s": float(self.cost_s),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Band:
        """Rebuild a band from :meth:`to_dict` data, naming the field of a damaged entry.

        Raises
        ------
        SchemaError
            A missing or malformed field (``provenance.band.<field>: ...``).
        """
        where = f"provenance.{PROVENANCE_KEY}"
        if not isinstance(data, Mapping):
            raise SchemaError(f"{where}: expected an object, got {type(data).__name__}")
        for key in ("a", "b", "quantiles"):
            if key not in data:
                raise SchemaError(f"{where}.{key}: missing from model file")
        levels = _numbers(data.get("levels", list(LEVELS)), f"{where}.levels")
        if tuple(round(v, 2) for v in levels) != LEVELS:
            raise SchemaError(f"{where}.levels: expected the levels {LEVELS[0]}..{LEVELS[-1]}")
        quantiles = _numbers(data["quantiles"], f"{where}.quantiles")
        spectra = data.get("spectra", [])
        if not isinstance(spectra, list) or not all(isinstance(s, Mapping) for s in spectra):
            raise SchemaError(f"{where}.spectra: expected a list of objects")
        try:
            return cls(
                a=float(data["a"]),
                b=float(data["b"]),
                c=float(data.get("c", 0.0)),
                quantiles=tuple(quantiles),
                method=str(data.get("method", "")),
                n_samples=int(data.get("n_samples", 0)),
                folds=tuple(str(f) for f in data.get("folds", [])),
                spectra=tuple(dict(s) for s in spectra),
                cost_s=float(data.get("cost_s", 0.0)),
            )
        except DataValidationError as exc:
            raise SchemaError(f"provenance.{exc}") from None
        except (TypeError, ValueError) as exc:
            raise SchemaError(f"{where}: does not make a band ({exc})") from None


def _numbers(value: Any, where: str) -> list[float]:
    if not isinstance(value, Sequence) or isinstance(value, str):
        raise SchemaError(f"{where}: expected a list of numbers")
    out = []
    for k, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise SchemaError(f"{where}[{k}]: expected a finite number, got {v!r}")
        out.append(float(v))
    return out


def band_of(model: Any) -> Band | None:
    """The band stored with ``model`` (a :class:`~mrdamper.models.FittedModel`), or None.

    Raises
    ------
    SchemaError
        The stored band is damaged (names the field).
    """
    data = dict(getattr(model, "provenance", None) or {}).get(PROVENANCE_KEY)
    return None if data is None else Band.from_dict(data)
