"""Relative (output-multiplicative) error spectra of held-out predictions.

For one held-out record with measured force ``F`` and prediction ``F_hat`` [N], the relative
error at frequency ``f`` is ``|E(f)| / |F_hat(f)|`` with ``E = F - F_hat``, both Hann-windowed
Fourier transforms, pooled over logarithmic frequency bins (:data:`BINS_PER_DECADE`): in each
bin ``sqrt(sum |E|^2 / sum |F_hat|^2)``. Only bins where the prediction carries power (at least
:data:`POWER_FLOOR` of its strongest bin's, 10 % of its amplitude) are kept: elsewhere the ratio
is noise over noise (a sine record's force has power at its harmonics only).

Each spectrum also records the record's electrical level (its mean input, [A] or [V]) and
whether that input is frozen (constant within :data:`FROZEN_SHARE` of the model's input range),
the form the uncertainty weight of :mod:`mrdamper.uncertainty.weight` is fitted per level on.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = [
    "BINS_PER_DECADE",
    "FROZEN_SHARE",
    "POWER_FLOOR",
    "error_spectra",
    "relative_error_spectrum",
]

#: Logarithmic frequency bins per decade.
BINS_PER_DECADE = 8
#: Bins whose prediction power is below this share of the strongest bin's are left out [-].
POWER_FLOOR = 1e-2
#: An input whose range stays within this share of the model's input range is frozen [-].
FROZEN_SHARE = 0.05


def relative_error_spectrum(
    F: np.ndarray,
    F_hat: np.ndarray,
    dt: float,
    electrical: np.ndarray,
    input_span: float,
    name: str = "",
) -> dict[str, Any] | None:
    """The binned relative error spectrum of one held-out record (see the module text).

    Parameters
    ----------
    F, F_hat : ndarray
        Measured and predicted force [N].
    dt : float
        Sampling interval [s].
    electrical : ndarray
        The record's electrical input [A] or [V].
    input_span : float
        Width of the model's input range (the unit of ``electrical``), for the frozen test.
    name : str
        Record name.

    Returns
    -------
    dict or None
        ``{"record", "level", "frozen", "freq" [Hz], "rel" [-]}``; None for a record too short
        or without a prediction to compare with.
    """
    F = np.asarray(F, dtype=np.float64)
    P = np.asarray(F_hat, dtype=np.float64)
    n = F.size
    if n < 16 or not np.all(np.isfinite(P)):
        return None
    w = np.hanning(n)
    E_f = np.abs(np.fft.rfft((F - P) * w)) ** 2
    P_f = np.abs(np.fft.rfft((P - P.mean()) * w)) ** 2
    freq = np.fft.rfftfreq(n, dt)
    f_lo, f_hi = freq[1], freq[-1]
    if not f_hi > f_lo > 0:
        return None
    n_bins = max(1, int(np.ceil(np.log10(f_hi / f_lo) * BINS_PER_DECADE)))
    edges = np.geomspace(f_lo, f_hi * (1 + 1e-12), n_bins + 1)
    k = np.digitize(freq, edges) - 1
    ok = (k >= 0) & (k < n_bins)
    pe = np.bincount(k[ok], weights=E_f[ok], minlength=n_bins)
    pp = np.bincount(k[ok], weights=P_f[ok], minlength=n_bins)
    keep = pp >= POWER_FLOOR * pp.max() if pp.max() > 0 else np.zeros(n_bins, bool)
    if not keep.any():
        return None
    centres = np.sqrt(edges[:-1] * edges[1:])
    e = np.asarray(electrical, dtype=np.float64)
    frozen = bool(np.ptp(e) <= FROZEN_SHARE * input_span) if input_span > 0 else True
    return {
        "record": name,
        "level": float(np.mean(e)),
        "frozen": frozen,
        "freq": centres[keep].tolist(),
        "rel": np.sqrt(pe[keep] / pp[keep]).tolist(),
    }


def error_spectra(model: Any, records: Iterable[Any]) -> list[dict[str, Any]]:
    """Relative error spectra of ``model``'s free-run predictions of ``records``.

    Parameters
    ----------
    model : FittedModel
        The model (predicting with its own range policy; notes of records beyond its training
        envelope are silenced).
    records : iterable of Experiment
        Records to compare with.

    Returns
    -------
    list of dict
        One :func:`relative_error_spectrum` per record that gives one.
    """
    span = float(model.input_range[1] - model.input_range[0])
    out = []
    for e in records:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            P = model.predict(e)
        s = relative_error_spectrum(e.F, P, e.dt, e.electrical(model.input), span, e.name)
        if s is not None:
            out.append(s)
    return out
