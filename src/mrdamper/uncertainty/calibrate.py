"""Calibrate a model's prediction band on its own held-out residuals (two-fold cross-fitting).

The training records are split in two folds; the model is fitted on each fold and predicts the
other, so every training sample gets one held-out residual at the cost of two fits on half the
data (about one more fit of the whole, not one per fold of a K-fold scheme):

* several records of at least two excitation conditions (records within
  :data:`CONDITION_TOLERANCE` of each other in displacement range and in band frequency are one
  condition, whatever their current): the conditions, ordered by band frequency then range,
  alternate between the folds, so a fold predicts excitations it was not fitted on and keeps
  every current of its conditions;
* otherwise (one record, or records of one condition), or when a fold's fit fails: every record
  is cut in two time blocks, the first halves form one fold and the second halves the other.

Residuals are normalised by the scale ``s = a + b |F_hat| + c m`` (:class:`~.band.Band`, ``m``
the moving RMS of ``F_hat``), ``a``, ``b`` and ``c`` fitted by non-negative least squares to the
absolute residuals (at most :data:`SCALE_SAMPLES` samples, evenly picked), and the band stores
the split-conformal quantile of ``|F - F_hat| / s`` (the ``ceil((n + 1) level)``-th smallest
of the ``n`` held-out scores). The fold models see half the data, so their residuals are, if
anything, larger than the full model's: the band is conservative rather than optimistic on
records like the training ones. Held-out samples within one record are correlated, so the
finite-sample guarantee of conformal prediction holds only approximately; the benchmark
(``benchmarks/bench_bands.py``) measures the coverage.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.errors import DataValidationError, MrDamperError
from mrdamper.models.envelope import band_frequency
from mrdamper.uncertainty.band import LEVELS, PROVENANCE_KEY, Band, moving_rms
from mrdamper.uncertainty.spectra import relative_error_spectrum

__all__ = [
    "CONDITION_TOLERANCE",
    "SCALE_SAMPLES",
    "calibrate",
    "calibration_folds",
    "fit_with_band",
    "with_band",
]

#: Records within this relative distance in displacement range and band frequency share one
#: excitation condition [-].
CONDITION_TOLERANCE = 0.10
#: Largest number of held-out samples the error scale is fitted on.
SCALE_SAMPLES = 200_000
#: Shortest time block of the block folds [samples].
MIN_BLOCK = 64

Fold = tuple[str, ExperimentSet, ExperimentSet]


def _signature(e: Experiment) -> tuple[float, float]:
    return float(np.ptp(e.x)), band_frequency(e.v, e.dt)


def _near(a: float, b: float) -> bool:
    return abs(a - b) <= CONDITION_TOLERANCE * max(abs(a), abs(b), 1e-12)


def _conditions(exps: ExperimentSet) -> list[list[Experiment]]:
    groups: list[tuple[tuple[float, float], list[Experiment]]] = []
    for e in exps:
        sig = _signature(e)
        for rep, members in groups:
            if _near(sig[0], rep[0]) and _near(sig[1], rep[1]):
                members.append(e)
                break
        else:
            groups.append((sig, [e]))
    groups.sort(key=lambda g: (g[0][1], g[0][0]))
    return [members for _, members in groups]


def _record_folds(exps: ExperimentSet) -> list[Fold] | None:
    groups = _conditions(exps)
    if len(groups) < 2:
        return None
    halves = [[e for g in groups[k::2] for e in g] for k in (0, 1)]
    a, b = (ExperimentSet(h, name=exps.name) for h in halves)
    return [
        (f"conditions {k + 1} of 2: {len(groups[k::2])} condition(s) held out", train, test)
        for k, (train, test) in enumerate(((b, a), (a, b)))
    ]


def _block_folds(exps: ExperimentSet) -> list[Fold]:
    first, second = [], []
    for e in exps:
        cut = e.n // 2
        if cut < MIN_BLOCK:
            raise DataValidationError(
                "data",
                f"record {e.name!r} has {e.n} samples; the band's time blocks need at least "
                f"{2 * MIN_BLOCK}",
            )
        first.append(e.slice(0, cut, name=f"{e.name}[:{cut}]"))
        second.append(e.slice(cut, None, name=f"{e.name}[{cut}:]"))
    a, b = ExperimentSet(first, name=exps.name), ExperimentSet(second, name=exps.name)
    return [("first halves held out", b, a), ("second halves held out", a, b)]


def calibration_folds(data: Experiment | Iterable[Experiment]) -> list[Fold]:
    """The two calibration folds of the training records (see the module text).

    Parameters
    ----------
    data : Experiment or iterable of Experiment
        The training records.

    Returns
    -------
    list of (label, train, held-out)
        Two folds; each sample of ``data`` is held out in exactly one.
    """
    exps = as_experiment_set(data)
    return _record_folds(exps) or _block_folds(exps)


def _held_out(
    estimator: Any, folds: list[Fold], span: float
) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray], list[dict[str, Any]], list[str]]:
    """Measured and predicted force and the prediction's moving RMS of every held-out record,
    their spectra, fold lines."""
    F_all, P_all, M_all, spectra, lines = [], [], [], [], []
    for label, train, test in folds:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = estimator.fit(train).with_range_policy("clip")
        skipped = 0
        for e in test:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    P = np.asarray(model.predict(e), dtype=np.float64)
            except MrDamperError:
                skipped += 1
                continue
            if not np.all(np.isfinite(P)):
                skipped += 1
                continue
            F_all.append(np.asarray(e.F, dtype=np.float64))
            P_all.append(P)
            M_all.append(moving_rms(P, e.dt))
            spec = relative_error_spectrum(e.F, P, e.dt, e.electrical(model.input), span, e.name)
            if spec is not None:
                spectra.append(spec)
        note = f"; {skipped} record(s) diverged, left out" if skipped else ""
        lines.append(f"{label} ({len(test)} record(s){note})")
    return F_all, P_all, M_all, spectra, lines


def _scale(F: np.ndarray, P: np.ndarray, M: np.ndarray) -> tuple[float, float, float]:
    """``a`` [N], ``b`` and ``c`` [-] of the error scale ``a + b |F_hat| + c m`` (non-negative
    least squares on the absolute residuals; ``a`` at least 1 % of the RMS force)."""
    from scipy.optimize import nnls

    step = max(1, F.size // SCALE_SAMPLES)
    r, p, m = np.abs(F - P)[::step], np.abs(P)[::step], M[::step]
    floor = 0.01 * float(np.sqrt(np.mean(F**2))) + 1e-12
    (a, b, c), _ = nnls(np.column_stack([np.ones(r.size), p, m]), r)
    if a + b + c <= 0:
        return max(float(np.mean(r)), floor), 0.0, 0.0
    return max(float(a), floor), float(b), float(c)


def _quantiles(scores: np.ndarray) -> tuple[float, ...]:
    s = np.sort(scores)
    n = s.size
    out = []
    for level in LEVELS:
        rank = min(n, math.ceil((n + 1) * level))  # 1-based rank of the conformal quantile
        out.append(float(s[rank - 1]))
    return tuple(out)


def calibrate(estimator: Any, data: Experiment | Iterable[Experiment], model: Any) -> Band:
    """The prediction band of ``model`` from held-out residuals of ``estimator`` on ``data``.

    Parameters
    ----------
    estimator : Estimator
        The estimator ``model`` was fitted with (its settings are reused on each fold).
    data : Experiment or iterable of Experiment
        The records ``model`` was fitted on.
    model : FittedModel
        The model the band is for (its input range sets the frozen-input test of the spectra).

    Returns
    -------
    Band
        Its ``cost_s`` is the CPU time of the two fold fits and their predictions [s].

    Raises
    ------
    DataValidationError
        No held-out record could be predicted (every fold model diverged).
    """
    c0 = time.process_time()
    exps = as_experiment_set(data)
    span = float(model.input_range[1] - model.input_range[0])
    folds = _record_folds(exps)
    method = "record folds"
    try:
        if folds is None:
            raise ValueError("one condition")
        F_all, P_all, M_all, spectra, lines = _held_out(estimator, folds, span)
    except (MrDamperError, ValueError):
        folds, method = _block_folds(exps), "time blocks"
        F_all, P_all, M_all, spectra, lines = _held_out(estimator, folds, span)
    if not F_all:
        raise DataValidationError(
            "data", f"{model.kind}: no held-out record could be predicted; no band calibrated"
        )
    F, P, M = np.concatenate(F_all), np.concatenate(P_all), np.concatenate(M_all)
    a, b, c = _scale(F, P, M)
    scores = np.abs(F - P) / (a + b * np.abs(P) + c * M)
    return Band(
        a=a,
        b=b,
        c=c,
        quantiles=_quantiles(scores),
        method=method,
        n_samples=int(F.size),
        folds=tuple(lines),
        spectra=tuple(spectra),
        cost_s=time.process_time() - c0,
    )


def with_band(model: Any, band: Band) -> Any:
    """Copy of ``model`` carrying ``band`` in its provenance (saved with it)."""
    return dataclasses.replace(
        model, provenance={**dict(model.provenance), PROVENANCE_KEY: band.to_dict()}
    )


def fit_with_band(estimator: Any, data: Experiment | Iterable[Experiment], **options: Any) -> Any:
    """Fit ``estimator`` on ``data`` and calibrate the model's prediction band.

    Parameters
    ----------
    estimator : Estimator
        Any model kind's estimator (:func:`mrdamper.models.get_estimator`).
    data : Experiment or iterable of Experiment
        Training records.
    **options
        Fit options of the family, passed to the fit of the whole (not to the fold fits).

    Returns
    -------
    FittedModel
        The model fitted on all of ``data``, with its band (:func:`~.band.band_of`).
    """
    exps = as_experiment_set(data)
    model = estimator.fit(exps, **options)
    return with_band(model, calibrate(estimator, exps, model))
