"""Goodness-of-fit indices for force predictions: pure functions of two arrays.

The paper's indices are SSSE (eq 23), which despite its name is the root-mean-square error in
force units, and ESR (eq 24), the mean squared error divided by the variance of the measured force.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike

from mrdamper.errors import DataValidationError

__all__ = ["MIN_SCORED_SAMPLES", "Scores", "esr", "fit_percent", "nrmse", "score_arrays", "ssse"]

#: Fewest samples a record must have for its scores to mean anything (a model's start-up
#: transient alone spans several samples).
MIN_SCORED_SAMPLES = 10
#: Relative standard deviation of the measured force below which it counts as constant [-].
_CONSTANT_FORCE = 1e-9


#: Largest force magnitude [N] scored: squares and sums of larger values overflow.
MAX_FORCE = 1e150


def _pair(measured: ArrayLike, predicted: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    F = np.asarray(measured, dtype=float)
    Fh = np.asarray(predicted, dtype=float)
    if F.shape != Fh.shape or F.ndim != 1:
        raise DataValidationError(
            "predicted", f"shape {Fh.shape} does not match measured shape {F.shape} (1-D expected)"
        )
    if F.size == 0:
        raise DataValidationError("measured", "empty array")
    if not np.all(np.isfinite(Fh)):
        raise DataValidationError("predicted", "contains non-finite values")
    for name, a in (("measured", F), ("predicted", Fh)):
        peak = float(np.max(np.abs(a)))
        if peak > MAX_FORCE:  # its square would overflow: a corrupt value, not a force
            raise DataValidationError(
                name, f"reaches {peak:.3g} N, beyond any force that can be scored ({MAX_FORCE:g} N)"
            )
    return F, Fh


def ssse(measured: ArrayLike, predicted: ArrayLike) -> float:
    """Paper eq. (23): ``sqrt(mean((F - F_hat)**2))`` [N] (an RMS error).

    Parameters
    ----------
    measured, predicted : array_like
        Measured and predicted force [N], same shape.
    """
    F, Fh = _pair(measured, predicted)
    return float(np.sqrt(np.mean((F - Fh) ** 2)))


def esr(measured: ArrayLike, predicted: ArrayLike) -> float:
    """Paper eq. (24): ``mean((F - F_hat)**2) / var(F)`` [-] (error-to-signal ratio).

    Parameters
    ----------
    measured, predicted : array_like
        Measured and predicted force [N], same shape.
    """
    F, Fh = _pair(measured, predicted)
    var = float(np.var(F))
    if var == 0.0 or np.sqrt(var) <= _CONSTANT_FORCE * float(np.max(np.abs(F))):
        raise DataValidationError(
            "measured",
            f"force is constant (standard deviation {np.sqrt(var):.3g} N); ESR is undefined",
        )
    return float(np.mean((F - Fh) ** 2) / var)


def nrmse(measured: ArrayLike, predicted: ArrayLike) -> float:
    """RMS error divided by the standard deviation of the measured force [-] (``sqrt(ESR)``).

    Parameters
    ----------
    measured, predicted : array_like
        Measured and predicted force [N], same shape.
    """
    return float(np.sqrt(esr(measured, predicted)))


def fit_percent(measured: ArrayLike, predicted: ArrayLike) -> float:
    """Normalised fit ``100 * (1 - ||F - F_hat|| / ||F - mean(F)||)`` [%] (100 is perfect).

    Parameters
    ----------
    measured, predicted : array_like
        Measured and predicted force [N], same shape.
    """
    return float(100.0 * (1.0 - nrmse(measured, predicted)))


@dataclass(frozen=True)
class Scores:
    """All indices for one prediction.

    Attributes
    ----------
    esr : float
        Error-to-signal ratio [-] (paper eq. 24).
    ssse : float
        Root-mean-square error [N] (paper eq. 23).
    nrmse : float
        RMS error over standard deviation of the measured force [-].
    fit : float
        Normalised fit [%].
    """

    esr: float
    ssse: float
    nrmse: float
    fit: float

    def to_dict(self) -> dict[str, float]:
        """Return the indices as a plain dict."""
        return asdict(self)


def score_arrays(measured: ArrayLike, predicted: ArrayLike) -> Scores:
    """Compute every index for one measured / predicted force pair.

    Parameters
    ----------
    measured, predicted : array_like
        Measured and predicted force [N], same shape.

    Raises
    ------
    DataValidationError
        Fewer than :data:`MIN_SCORED_SAMPLES` samples, a constant measured force, mismatched
        shapes or a non-finite prediction.
    """
    n = np.asarray(measured).size
    if n < MIN_SCORED_SAMPLES:
        raise DataValidationError(
            "F", f"record has {n} sample(s); scores need at least {MIN_SCORED_SAMPLES}"
        )
    e = esr(measured, predicted)
    return Scores(
        esr=e,
        ssse=ssse(measured, predicted),
        nrmse=float(np.sqrt(e)),
        fit=100 * (1 - float(np.sqrt(e))),
    )
