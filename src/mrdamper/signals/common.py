"""Helpers shared by the signal generators and the virtual rig: time grids, seeds, checks."""

from __future__ import annotations

import math

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = [
    "SeedLike",
    "as_rng",
    "as_seed_sequence",
    "check_int_at_least",
    "check_positive",
    "check_range",
    "child_seeds",
    "hold_samples",
    "n_samples",
    "sample_grid",
    "time_grid",
]

#: What a ``seed`` argument accepts: a non-negative int or a :class:`numpy.random.SeedSequence`.
SeedLike = int | np.integer | np.random.SeedSequence


def check_positive(name: str, value: float, unit: str) -> float:
    """Return ``value`` as float or raise naming ``name`` if it is not finite and > 0."""
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise DataValidationError(
            name, f"expected a positive number [{unit}], got {value!r}"
        ) from None
    if not (math.isfinite(f) and f > 0.0):
        raise DataValidationError(name, f"expected a finite value > 0 [{unit}], got {value!r}")
    return f


def check_range(name: str, low: float, high: float, unit: str) -> tuple[float, float]:
    """Return ``(low, high)`` as floats or raise if not finite with ``low < high``."""
    lo, hi = float(low), float(high)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise DataValidationError(
            name, f"expected finite bounds with low < high [{unit}], got ({low!r}, {high!r})"
        )
    return lo, hi


def check_int_at_least(name: str, value: int, minimum: int) -> int:
    """Return ``value`` as int or raise naming ``name`` if it is not an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise DataValidationError(name, f"expected an int >= {minimum}, got {value!r}")
    return int(value)


def n_samples(fs: float, duration: float) -> int:
    """Number of samples of a record of ``duration`` [s] sampled at ``fs`` [Hz].

    The grid is ``t = k / fs`` for ``k = 0 .. round(duration * fs) - 1``, so a 30 s record at
    1 kHz has exactly 30 000 samples.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record duration [s].
    """
    fs = check_positive("fs", fs, "Hz")
    duration = check_positive("duration", duration, "s")
    n = round(duration * fs)
    if n < 2:
        raise DataValidationError(
            "duration", f"{duration:g} s at fs={fs:g} Hz gives {n} sample(s); at least 2 are needed"
        )
    return n


def sample_grid(fs: float, duration: float) -> tuple[int, float]:
    """Validated sample count (:func:`n_samples`) and sampling rate ``fs`` [Hz] as a float."""
    return n_samples(fs, duration), check_positive("fs", fs, "Hz")


def time_grid(fs: float, duration: float) -> np.ndarray:
    """Uniform time grid ``t`` [s] of :func:`n_samples` points starting at 0.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].

    Returns
    -------
    ndarray
        ``arange(n) / fs`` [s].

    Examples
    --------
    >>> time_grid(1000.0, 0.005)
    array([0.   , 0.001, 0.002, 0.003, 0.004])
    """
    return np.arange(n_samples(fs, duration)) / float(fs)


def hold_samples(name: str, period: float, fs: float) -> int:
    """A hold / clock period [s] as a whole number (>= 1) of samples at ``fs`` [Hz]."""
    period = check_positive(name, period, "s")
    k = round(period * fs)
    if k < 1:
        raise DataValidationError(
            name, f"{period:g} s is shorter than one sample at fs={fs:g} Hz (1/fs = {1 / fs:g} s)"
        )
    return k


def as_seed_sequence(seed: SeedLike, name: str = "seed") -> np.random.SeedSequence:
    """Validate an explicit seed and return it as a :class:`numpy.random.SeedSequence`.

    Only non-negative ints and SeedSequences are accepted (``None`` and generators are refused),
    so every random signal is reproducible from a value that can be written into metadata.
    """
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise DataValidationError(
            name, f"expected a non-negative int or numpy.random.SeedSequence, got {seed!r}"
        )
    if int(seed) < 0:
        raise DataValidationError(name, f"expected a non-negative int, got {seed!r}")
    return np.random.SeedSequence(int(seed))


def child_seeds(seed: SeedLike, n: int, name: str = "seed") -> list[np.random.SeedSequence]:
    """The first ``n`` children of ``seed``'s SeedSequence, without mutating ``seed``.

    ``SeedSequence.spawn`` counts the children it has handed out, so spawning twice from the same
    object gives different streams; this helper always returns children ``0 .. n-1`` (the same
    ones a fresh ``SeedSequence(seed).spawn(n)`` gives), so a seed reproduces its bytes every time.
    """
    ss = as_seed_sequence(seed, name)
    return [
        np.random.SeedSequence(
            entropy=ss.entropy, spawn_key=(*ss.spawn_key, k), pool_size=ss.pool_size
        )
        for k in range(n)
    ]


def as_rng(seed: SeedLike, name: str = "seed") -> np.random.Generator:
    """``numpy.random.default_rng`` of an explicit seed (see :func:`as_seed_sequence`)."""
    return np.random.default_rng(as_seed_sequence(seed, name))
