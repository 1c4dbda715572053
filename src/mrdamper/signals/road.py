"""Road-profile displacement excitation after ISO 8608, scaled to the rig's stroke.

ISO 8608 describes a road's vertical profile by its one-sided spatial displacement power spectral
density ``Gd(n) = Gd(n0) * (n / n0) ** -2`` [m^3], spatial frequency n [cycles/m], n0 = 0.1
cycles/m, with eight classes A-H whose geometric-mean ``Gd(n0)`` grows by a factor 4 per class
(16e-6 m^3 for A up to 262144e-6 m^3 for H). Driven at speed V [m/s], a point on the road becomes a
time signal with temporal frequency f = n V [Hz] and one-sided PSD ``G(f) = Gd(f / V) / V``
[m^2/Hz], i.e. ``G(f) = Gd(n0) n0^2 V f^-2``: slope -2 on log-log axes.

Synthesis (random-phase spectral method): on the FFT grid of the record, f_k = k fs / N, every
bin inside ``[min_frequency, max_frequency]`` gets amplitude ``sqrt(2 G(f_k) df)`` and a phase drawn
uniformly (seeded); an inverse real FFT sums the cosines. Bins outside the band are zero, so there
is no energy above ``max_frequency`` and the variance equals the band integral of G.

Choices (documented in ``docs/rig.md``):

* The road displacement is applied to the damper directly; no quarter-car / wheel-hop filter is
  applied. A quarter car would reshape the spectrum near the body (~1 Hz) and wheel-hop (~10 Hz)
  modes; the paper only states a maximum excitation frequency per sequence, which the band limit
  reproduces, and the -2 slope keeps the damper velocity spectrum flat in the band.
* Displacement is given about mid-stroke (0 = middle of the rig's stroke). With ``fill`` set, the
  profile is scaled so that its largest excursion is ``fill * stroke / 2``, so it always stays
  inside ``+-stroke / 2`` (paper: 0-0.04 m stroke). With ``fill=None`` the physical ISO amplitude is
  kept and a profile that would leave the stroke raises an error.
* ``taper`` fades the profile in and out with raised-cosine ramps, so the rig starts and ends at
  mid-stroke.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mrdamper.errors import DataValidationError
from mrdamper.signals.common import (
    SeedLike,
    as_rng,
    check_positive,
    check_range,
    child_seeds,
    sample_grid,
)

__all__ = [
    "DEFAULT_STROKE",
    "ISO_8608_CLASSES",
    "N0",
    "band_variance",
    "long_road_profile",
    "road_profile",
    "spatial_psd",
    "temporal_psd",
]

#: Reference spatial frequency of ISO 8608 [cycles/m].
N0 = 0.1

#: Geometric-mean ``Gd(n0)`` of each ISO 8608 road class [m^3] (= 1e-6 * 16 * 4**k).
ISO_8608_CLASSES: dict[str, float] = {c: 16e-6 * 4.0**k for k, c in enumerate("ABCDEFGH")}

#: Stroke of the paper's rig [m] (displacement range 0-0.04 m).
DEFAULT_STROKE = 0.04


def _gd0(road_class: str | float) -> float:
    if isinstance(road_class, str):
        key = road_class.strip().upper()
        if key not in ISO_8608_CLASSES:
            raise DataValidationError(
                "road_class",
                f"expected one of {sorted(ISO_8608_CLASSES)} or Gd(n0) [m^3], got {road_class!r}",
            )
        return ISO_8608_CLASSES[key]
    return check_positive("road_class", road_class, "m^3")


def spatial_psd(n: np.ndarray | float, road_class: str | float) -> np.ndarray:
    """ISO 8608 spatial displacement PSD ``Gd(n) = Gd(n0) (n / n0)^-2`` [m^3].

    Parameters
    ----------
    n : array_like
        Spatial frequency [cycles/m], > 0.
    road_class : str or float
        ISO class letter ``"A"``-``"H"`` or ``Gd(n0)`` itself [m^3].

    Examples
    --------
    >>> float(spatial_psd(0.1, "C"))
    0.000256
    """
    n = np.asarray(n, dtype=float)
    return _gd0(road_class) * (n / N0) ** -2.0


def temporal_psd(f: np.ndarray | float, road_class: str | float, speed: float) -> np.ndarray:
    """One-sided temporal displacement PSD at vehicle speed ``speed`` [m^2/Hz].

    ``G(f) = Gd(f / V) / V`` with ``f`` [Hz] and ``V`` [m/s].

    Parameters
    ----------
    f : ndarray or float
        Temporal frequency [Hz].
    road_class : str or float
        ISO 8608 class (``"A"`` .. ``"H"``) or the reference PSD ``Gd(n0)`` [m^3].
    speed : float
        Vehicle speed [m/s].
    """
    v = check_positive("speed", speed, "m/s")
    f = np.asarray(f, dtype=float)
    return spatial_psd(f / v, road_class) / v


def band_variance(
    road_class: str | float, speed: float, min_frequency: float, max_frequency: float
) -> float:
    """Displacement variance [m^2] of the band ``[min_frequency, max_frequency]``.

    The integral of G over the band.

    Parameters
    ----------
    road_class : str or float
        ISO 8608 class (``"A"`` .. ``"H"``) or the reference PSD ``Gd(n0)`` [m^3].
    speed : float
        Vehicle speed [m/s].
    min_frequency, max_frequency : float
        Temporal frequency band [Hz].
    """
    fmin, fmax = check_range("min_frequency/max_frequency", min_frequency, max_frequency, "Hz")
    v = check_positive("speed", speed, "m/s")
    return _gd0(road_class) * N0**2 * v * (1.0 / fmin - 1.0 / fmax)


def _check_band(fs: float, min_frequency: float, max_frequency: float) -> tuple[float, float]:
    fmin = check_positive("min_frequency", min_frequency, "Hz")
    fmax = check_positive("max_frequency", max_frequency, "Hz")
    if fmin >= fmax:
        raise DataValidationError(
            "min_frequency", f"{fmin:g} Hz must be below max_frequency={fmax:g} Hz"
        )
    if fmax >= fs / 2:
        raise DataValidationError(
            "max_frequency", f"{fmax:g} Hz is not below the Nyquist frequency fs/2 = {fs / 2:g} Hz"
        )
    return fmin, fmax


def _synthesise(
    n: int, fs: float, gd0: float, speed: float, fmin: float, fmax: float, rng: np.random.Generator
) -> np.ndarray:
    """Random-phase sum of cosines on the FFT grid of ``n`` samples (physical metres)."""
    df = fs / n
    k = np.arange(n // 2 + 1)
    f = k * df
    band = (f >= fmin) & (f <= fmax)
    if not band.any():
        raise DataValidationError(
            "min_frequency",
            f"no frequency bin of a {n / fs:g} s record (resolution {df:g} Hz) lies in "
            f"[{fmin:g}, {fmax:g}] Hz; lengthen the record or widen the band",
        )
    phases = rng.uniform(
        0.0, 2.0 * np.pi, size=k.size
    )  # drawn for every bin: band-independent stream
    spec = np.zeros(k.size, dtype=np.complex128)
    g = gd0 * N0**2 * speed / f[band] ** 2
    spec[band] = (n / 2.0) * np.sqrt(2.0 * g * df) * np.exp(1j * phases[band])
    return np.fft.irfft(spec, n)


def _taper(x: np.ndarray, fs: float, taper: float) -> np.ndarray:
    if taper < 0 or not math.isfinite(taper):
        raise DataValidationError("taper", f"expected a finite value >= 0 [s], got {taper!r}")
    m = round(taper * fs)
    if m == 0:
        return x
    if 2 * m > x.size:
        raise DataValidationError(
            "taper", f"{taper:g} s ramps at both ends do not fit in a {x.size / fs:g} s record"
        )
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(m) / m)
    out = x.copy()
    out[:m] *= ramp
    out[-m:] *= ramp[::-1]
    return out


def _to_stroke(x: np.ndarray, stroke: float, fill: float | None) -> np.ndarray:
    stroke = check_positive("stroke", stroke, "m")
    peak = float(np.max(np.abs(x)))
    if fill is None:
        if peak > stroke / 2:
            raise DataValidationError(
                "fill",
                f"the physical profile reaches {peak:.4g} m, outside "
                f"+-stroke/2 = {stroke / 2:.4g} m; choose a milder road class or lower speed, "
                "or give fill to scale it",
            )
        return x
    fill = check_positive("fill", fill, "-")
    if fill > 1.0:
        raise DataValidationError(
            "fill", f"expected 0 < fill <= 1 (fraction of stroke/2), got {fill!r}"
        )
    if peak == 0.0:
        raise DataValidationError("road_class", "the synthesised profile is identically zero")
    return x * (fill * stroke / 2.0 / peak)


def road_profile(
    fs: float,
    duration: float,
    *,
    seed: SeedLike,
    road_class: str | float = "C",
    speed: float = 20.0,
    max_frequency: float = 5.0,
    min_frequency: float = 0.2,
    stroke: float = DEFAULT_STROKE,
    fill: float | None = 0.9,
    taper: float = 0.5,
) -> np.ndarray:
    """Band-limited ISO 8608 road displacement about mid-stroke.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    duration : float
        Record length [s].
    seed : int or numpy.random.SeedSequence
        Seeds the random phases.
    road_class : str or float
        ISO 8608 class ``"A"``-``"H"`` or ``Gd(n0)`` [m^3].
    speed : float
        Vehicle speed [m/s]; maps spatial to temporal frequency (f = n V).
    max_frequency : float
        Upper band limit [Hz] (Table II "max. freq. value"); nothing is synthesised above it.
    min_frequency : float
        Lower band limit [Hz]; the -2 slope puts unbounded displacement at low frequency, so the
        band starts here (default 0.2 Hz, i.e. 0.01 cycles/m at 20 m/s).
    stroke : float
        Rig stroke [m]; the profile is centred at mid-stroke (0).
    fill : float or None
        Largest excursion as a fraction of ``stroke / 2`` (default 0.9). ``None`` keeps the
        physical ISO amplitude and raises if it leaves the stroke.
    taper : float
        Length of the raised-cosine fade-in and fade-out [s] (0 for none).

    Returns
    -------
    ndarray
        Displacement command [m], one value per sample, within ``+-stroke / 2``.

    Examples
    --------
    >>> x = road_profile(1000.0, 30.0, seed=0, max_frequency=5.5)
    >>> round(float(abs(x).max()), 6)
    0.018
    """
    n, fs = sample_grid(fs, duration)
    fmin, fmax = _check_band(fs, min_frequency, max_frequency)
    v = check_positive("speed", speed, "m/s")
    x = _synthesise(n, fs, _gd0(road_class), v, fmin, fmax, as_rng(seed))
    return _to_stroke(_taper(x, fs, float(taper)), stroke, fill)


def long_road_profile(
    fs: float,
    duration: float,
    *,
    seed: SeedLike,
    section_duration: float = 30.0,
    classes: Sequence[str] = ("B", "C", "D"),
    speed_range: tuple[float, float] = (10.0, 30.0),
    crossfade: float = 2.0,
    max_frequency: float = 5.0,
    min_frequency: float = 0.2,
    stroke: float = DEFAULT_STROKE,
    fill: float | None = 0.9,
    taper: float = 0.5,
) -> np.ndarray:
    """A long drive: consecutive road sections of random ISO class and speed, cross-faded.

    Each section of ``section_duration`` has an ISO 8608 class drawn from ``classes`` and a speed
    drawn uniformly from ``speed_range`` (both seeded) and is synthesised like
    :func:`road_profile`; neighbours are joined with power-complementary (sine / cosine) ramps of
    ``crossfade`` seconds. Every section has the same -2 spectral slope, so the whole profile has
    it too, while its amplitude changes from section to section as on a real drive. Any duration
    works; memory grows with one section at a time.

    Parameters
    ----------
    fs, duration, seed, max_frequency, min_frequency, stroke, fill, taper
        As in :func:`road_profile` ([Hz], [s], -, [Hz], [Hz], [m], -, [s]).
    section_duration : float
        Length of one road section [s].
    classes : sequence of str
        ISO classes to draw from.
    speed_range : (float, float)
        Range of vehicle speeds [m/s].
    crossfade : float
        Overlap of neighbouring sections [s] (< ``section_duration``).

    Returns
    -------
    ndarray
        Displacement command [m] about mid-stroke.

    Examples
    --------
    >>> x = long_road_profile(1000.0, 120.0, seed=4, max_frequency=5.5)
    >>> x.size
    120000
    """
    n, fs = sample_grid(fs, duration)
    fmin, fmax = _check_band(fs, min_frequency, max_frequency)
    sec = check_positive("section_duration", section_duration, "s")
    vlo, vhi = check_range("speed_range", speed_range[0], speed_range[1], "m/s")
    if vlo <= 0:
        raise DataValidationError(
            "speed_range", f"expected positive speeds [m/s], got {speed_range!r}"
        )
    if not classes:
        raise DataValidationError("classes", "expected at least one ISO 8608 class")
    gd0s = [_gd0(c) for c in classes]
    if not (math.isfinite(crossfade) and 0 <= crossfade < sec):
        raise DataValidationError(
            "crossfade", f"expected 0 <= crossfade < section_duration={sec:g} s, got {crossfade!r}"
        )
    L = round(sec * fs)
    c = round(crossfade * fs)
    n_sec = max(1, round(n / L))  # a remainder shorter than half a section joins the last one
    edges = [k * L for k in range(n_sec)] + [n]
    seeds = child_seeds(seed, n_sec + 1)
    rng = np.random.default_rng(seeds[0])
    which = rng.integers(0, len(gd0s), size=n_sec)
    speeds = rng.uniform(vlo, vhi, size=n_sec)
    x = np.zeros(n)
    half = c // 2
    for k in range(n_sec):
        a = max(0, edges[k] - half)
        b = min(n, edges[k + 1] + (c - half))
        s = _synthesise(
            b - a,
            fs,
            gd0s[which[k]],
            float(speeds[k]),
            fmin,
            fmax,
            np.random.default_rng(seeds[k + 1]),
        )
        w = np.ones(b - a)
        if k > 0 and c > 0:  # fade in over [k L - half, k L - half + c)
            w[:c] *= np.sin(0.5 * np.pi * (np.arange(c) + 0.5) / c)
        if k < n_sec - 1 and c > 0:  # fade out over the last c samples
            w[-c:] *= np.cos(0.5 * np.pi * (np.arange(c) + 0.5) / c)
        x[a:b] += w * s
    return _to_stroke(_taper(x, fs, float(taper)), stroke, fill)
