"""Broadband training records from a reference model calibrated on the same measurements.

Constant-current sine tests excite a damper at a few frequencies only; a model identified on
them alone (the LPV transfer function in particular) is free to do anything between and beyond
them. A physical reference model (Spencer's modified Bouc-Wen by default) calibrated on the same
records extrapolates in frequency by its structure; its free-run force on synthetic broadband
motions is a training signal for the data-driven model, added with a chosen weight next to the
measured records (:meth:`~mrdamper.models.lpv.LPVEstimator.fit` ``record_weights``).

What the synthetic records contain (all from the seed, reproducible byte for byte):

* velocity: a logarithmic sine sweep from ``min_frequency`` to ``max_frequency`` (seeded
  amplitude, 40-100 % of the largest training velocity; ``motion="sweep"``, default) or
  band-limited Gaussian noise (zero-phase Butterworth band-pass, order 4) scaled to the largest
  training velocity (``motion="noise"``); displacement its integral, detrended;
* electrical input: an APRBS between the smallest and largest training input, held at least
  ``min_hold`` seconds (the reference model's input dynamics apply);
* force: the reference model's free-run prediction (no noise added).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import scipy.signal as sps

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.signals import aprbs

__all__ = ["reference_records"]


def reference_records(
    train: Experiment | Iterable[Experiment],
    *,
    reference: FittedModel | None = None,
    reference_kind: str = "spencer",
    reference_settings: Mapping[str, Any] | None = None,
    input: ElectricalSource = "i",
    n_records: int = 4,
    duration: float = 20.0,
    fs: float | None = None,
    min_frequency: float = 0.5,
    max_frequency: float = 20.0,
    min_hold: float = 0.5,
    motion: str = "sweep",
    seed: int = 0,
) -> tuple[ExperimentSet, FittedModel]:
    """Synthetic broadband records simulated by a reference model of the training records.

    Parameters
    ----------
    train : Experiment or iterable of Experiment
        Measured training records (calibration data of the reference model; their velocity and
        input ranges bound the synthetic ones).
    reference : FittedModel, optional
        An already calibrated reference model; default: ``reference_kind`` fitted on ``train``.
    reference_kind : str
        Model kind calibrated when ``reference`` is not given.
    reference_settings : mapping, optional
        Estimator settings of that calibration (``input`` is added).
    input : {"i", "voltage"}
        Electrical input channel.
    n_records : int
        Number of synthetic records.
    duration : float
        Length of each record [s].
    fs : float, optional
        Sampling rate [Hz]; default: the lowest training rate.
    min_frequency, max_frequency : float
        Band of the velocity [Hz].
    min_hold : float
        Shortest hold of an input level [s].
    motion : {"sweep", "noise"}
        ``"sweep"``: logarithmic sine sweep of the velocity from ``min_frequency`` to
        ``max_frequency`` with a seeded amplitude between 40 % and 100 % of the largest training
        velocity; ``"noise"``: band-limited Gaussian velocity scaled to that largest velocity.
    seed : int
        Seeds the motions and inputs.

    Returns
    -------
    (ExperimentSet, FittedModel)
        The synthetic records (names ``reference_0``, ...; metadata ``source="reference model"``)
        and the reference model used.
    """
    exps = as_experiment_set(train, name="training")
    if len(exps) == 0:
        raise DataValidationError("train", "no training records given")
    if not (isinstance(n_records, int) and n_records >= 1):
        raise DataValidationError("n_records", f"expected an integer >= 1, got {n_records!r}")
    if motion not in ("sweep", "noise"):
        raise DataValidationError("motion", f"expected 'sweep' or 'noise', got {motion!r}")
    rate = float(fs) if fs is not None else min(e.fs for e in exps)
    if not 0 < min_frequency < max_frequency < rate / 2:
        raise DataValidationError(
            "max_frequency",
            f"expected 0 < min_frequency < max_frequency < fs/2 = {rate / 2:g} Hz, "
            f"got {min_frequency:g} and {max_frequency:g}",
        )
    if reference is None:
        from mrdamper.models.registry import get_estimator

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            reference = get_estimator(
                reference_kind, **{**dict(reference_settings or {}), "input": input}
            ).fit(exps)
    reference = reference.with_range_policy("clip")
    v_max = max(float(np.max(np.abs(e.v))) for e in exps)
    lo = min(float(np.min(e.electrical(input))) for e in exps)
    hi = max(float(np.max(e.electrical(input))) for e in exps)
    n = round(duration * rate)
    t = np.arange(n) / rate
    sos = sps.butter(4, [min_frequency, max_frequency], btype="bandpass", fs=rate, output="sos")
    ramp = np.clip(np.minimum(t, t[-1] - t) / 0.5, 0.0, 1.0)
    out = []
    for k, ss in enumerate(np.random.SeedSequence(seed).spawn(n_records)):
        rng = np.random.default_rng(ss)
        if motion == "sweep":
            amp = v_max * float(rng.uniform(0.4, 1.0))
            v = (
                amp
                * sps.chirp(t, f0=min_frequency, t1=t[-1], f1=max_frequency, method="logarithmic")
                * ramp
            )
        else:
            v = sps.sosfiltfilt(sos, rng.standard_normal(n)) * ramp
            v *= v_max / float(np.max(np.abs(v)))
        x = np.cumsum(v) / rate
        x -= np.linspace(x[0], x[-1], n)  # keep the stroke centred (drift-free displacement)
        level = aprbs(
            rate, duration, low=lo, high=hi, min_hold=min_hold, seed=int(rng.integers(2**31))
        )
        if hi - lo <= 0:
            level = np.full(n, lo)
        e = Experiment(
            t=t,
            x=x,
            v=v,
            F=np.zeros(n),
            name=f"reference_{k}",
            i=level[:n] if input == "i" else None,
            voltage=level[:n] if input == "voltage" else None,
            metadata={"source": "reference model", "reference": reference.kind},
        )
        out.append(e.replace(F=np.asarray(reference.predict(e), dtype=np.float64)))
    return ExperimentSet(out, name="reference records"), reference
