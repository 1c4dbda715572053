"""The training envelope of a model: how far its identification data moved the damper.

Stored at fit time in ``provenance["envelope"]`` (:meth:`mrdamper.models.base.Estimator.fit`), so
a tool that uses the model elsewhere (the quarter car, :meth:`~mrdamper.models.FittedModel.predict`
on a new record, the study) can say how far it leaves it. The same function measures the envelope
of any motion (a loop run, a record), so the two are comparable.

The dimensions: velocity (largest ``|v|``), displacement (the ``x`` range), frequency content (the
band holding :data:`BAND_SHARE` of the velocity's power, when sampling intervals are given) and
electrical input (its range). :func:`envelope_note` says in one line which of them a record
leaves, and by how much.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

__all__ = [
    "BAND_SHARE",
    "CORE_SHARE",
    "ENVELOPE_TOLERANCE",
    "SWITCH_FRACTION",
    "band_frequency",
    "envelope_note",
    "envelope_of",
    "excursions",
    "leaves",
    "training_envelope",
]

#: A sample "switches" when its input changes by more than this fraction of the input range [-].
SWITCH_FRACTION = 0.05
#: Share of the samples whose electrical input lies in ``e_core_range`` [-] (the rest, split
#: evenly below and above, are spikes such as a drive's switching transients).
CORE_SHARE = 0.99
#: Share of the velocity's power below the frequency band measure ``f_band`` [-].
BAND_SHARE = 0.95
#: A record leaves the envelope in a dimension when it exceeds the training value by more than
#: this fraction (velocity, displacement reach, frequency band) or leaves the electrical range by
#: more than this fraction of its width [-].
ENVELOPE_TOLERANCE = 0.05


def band_frequency(v: np.ndarray, dt: float, share: float = BAND_SHARE) -> float:
    """Frequency below which ``share`` of the velocity's power lies [Hz] (0 for no motion).

    Parameters
    ----------
    v : ndarray
        Velocity [m/s], uniformly sampled.
    dt : float
        Sampling interval [s].
    share : float
        Power share [-], in (0, 1].
    """
    a = np.asarray(v, dtype=np.float64)
    if a.size < 4:
        return 0.0
    p = np.abs(np.fft.rfft(a - a.mean())) ** 2
    c = np.cumsum(p)
    if c[-1] <= 0.0:
        return 0.0
    k = int(np.searchsorted(c, share * c[-1]))
    return float(k / (a.size * dt))


def envelope_of(
    x: Sequence[np.ndarray],
    v: Sequence[np.ndarray],
    e: Sequence[np.ndarray],
    F: Any = None,
    dt: Sequence[float] | None = None,
) -> dict[str, Any]:
    """Envelope of records (lists of per-record arrays).

    Parameters
    ----------
    x, v, e : sequence of ndarray
        Displacement [m], velocity [m/s] and electrical input [A] or [V] of each record.
    F : sequence of ndarray, optional
        Force [N] of each record (gives ``f_max``).
    dt : sequence of float, optional
        Sampling interval [s] of each record (gives ``f_band``).

    Returns
    -------
    dict
        ``v_max`` largest ``|v|`` [m/s]; ``x_range`` [min, max] displacement [m]; ``e_range``
        [min, max] electrical input [A] or [V]; ``v_switch`` largest ``|v|`` [m/s] at a sample
        where the input changes by more than :data:`SWITCH_FRACTION` of its range (current
        switching while moving; 0 when it never switches); ``f_max`` largest ``|F|`` [N] when
        ``F`` is given; ``f_band`` the highest :func:`band_frequency` of a record [Hz] when
        ``dt`` is given.
    """
    lo = min(float(np.min(a)) for a in e)
    hi = max(float(np.max(a)) for a in e)
    thr = SWITCH_FRACTION * (hi - lo)
    v_switch = 0.0
    for vk, ek in zip(v, e):
        if thr > 0 and ek.size > 1:
            moving = np.abs(np.diff(ek)) > thr
            if moving.any():
                v_switch = max(v_switch, float(np.max(np.abs(vk[1:][moving]))))
    out: dict[str, Any] = {
        "v_max": max(float(np.max(np.abs(a))) for a in v),
        "x_range": [min(float(np.min(a)) for a in x), max(float(np.max(a)) for a in x)],
        "e_range": [lo, hi],
        "v_switch": v_switch,
    }
    if F is not None:
        out["f_max"] = max(float(np.max(np.abs(a))) for a in F)
    if dt is not None:
        out["f_band"] = max(band_frequency(vk, float(h)) for vk, h in zip(v, dt))
    return out


def training_envelope(records: Iterable[Any], electrical: Sequence[np.ndarray]) -> dict[str, Any]:
    """:func:`envelope_of` the training records (``electrical``: their input channel), plus
    ``e_core_range``: the range holding :data:`CORE_SHARE` of the input samples (quantiles over
    all records) [A] or [V]."""
    recs = list(records)
    e = list(electrical)
    out = envelope_of(
        [r.x for r in recs],
        [r.v for r in recs],
        e,
        [r.F for r in recs],
        [r.dt for r in recs],
    )
    tails = [0.5 * (1.0 - CORE_SHARE), 1.0 - 0.5 * (1.0 - CORE_SHARE)]
    out["e_core_range"] = [float(b) for b in np.quantile(np.concatenate(e), tails)]
    return out


def _ratio(seen: float, trained: float) -> float:
    """``seen / trained`` (inf when nothing was trained and something is seen, 0 when neither)."""
    return float(seen / trained) if trained > 0 else (float("inf") if seen > 0 else 0.0)


def _frequency_ratio(trained: dict[str, Any], seen: dict[str, Any]) -> float | None:
    """``f_band`` seen / trained, or None when either envelope lacks it."""
    ft, fs = trained.get("f_band"), seen.get("f_band")
    if not ft or fs is None:
        return None
    return _ratio(float(fs), float(ft))


def excursions(trained: dict[str, Any], seen: dict[str, Any]) -> dict[str, float]:
    """How far ``seen`` leaves ``trained`` (ratios > 1 leave it).

    Returns
    -------
    dict
        ``velocity`` seen / trained ``v_max``; ``stroke`` seen / trained displacement span;
        ``switching`` seen / trained ``v_switch`` (inf when training never switched while moving
        and the run does); ``frequency`` seen / trained ``f_band`` when both carry it (the
        frequency below which :data:`BAND_SHARE` of the velocity's power lies).
    """

    span_t = trained["x_range"][1] - trained["x_range"][0]
    span_s = seen["x_range"][1] - seen["x_range"][0]
    out = {
        "velocity": _ratio(seen["v_max"], trained["v_max"]),
        "stroke": _ratio(span_s, span_t),
        "switching": _ratio(seen["v_switch"], trained["v_switch"]),
    }
    frequency = _frequency_ratio(trained, seen)
    if frequency is not None:
        out["frequency"] = frequency
    return out


def _times(ratio: float) -> str:
    """A ratio as ``1.07`` (or ``3.2e+302`` when absurdly large: never hundreds of digits)."""
    return f"{ratio:.2f}" if ratio < 1e4 else f"{ratio:.3g}"


def leaves(trained: dict[str, Any], seen: dict[str, Any]) -> dict[str, tuple[float, str]]:
    """The dimensions in which ``seen`` leaves ``trained`` by more than
    :data:`ENVELOPE_TOLERANCE`: dimension -> (ratio, one-phrase description).

    ``velocity``: largest ``|v|`` seen / trained; ``displacement``: largest distance from the
    training range's centre, seen / trained half-span; ``frequency``: ``f_band`` seen / trained
    (when both carry it); ``electrical``: distance outside the training range / its width.
    """
    out: dict[str, tuple[float, str]] = {}
    tol = ENVELOPE_TOLERANCE
    vt, vs = float(trained["v_max"]), float(seen["v_max"])
    if vt > 0 and vs > (1 + tol) * vt:
        text = f"velocity {vs:.3g} m/s against {vt:.3g} m/s ({_times(vs / vt)} x)"
        out["velocity"] = (vs / vt, text)
    lo, hi = (float(b) for b in trained["x_range"])
    slo, shi = (float(b) for b in seen["x_range"])
    half, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
    reach = max(abs(shi - mid), abs(slo - mid))
    if half > 0 and reach > (1 + tol) * half:
        out["displacement"] = (
            reach / half,
            (
                f"displacement [{slo * 1e3:.3g}, {shi * 1e3:.3g}] mm against [{lo * 1e3:.3g}, "
                f"{hi * 1e3:.3g}] mm ({_times(reach / half)} x the reach)"
            ),
        )
    r = _frequency_ratio(trained, seen)
    if r is not None and r > 1 + tol:
        ft, fs = float(trained["f_band"]), float(seen["f_band"])
        out["frequency"] = (
            r,
            (
                f"frequency content up to {fs:.3g} Hz against {ft:.3g} Hz "
                f"({_times(r)} x; {BAND_SHARE:.0%} of the velocity power)"
            ),
        )
    elo, ehi = (float(b) for b in trained["e_range"])
    sel, seh = (float(b) for b in seen["e_range"])
    beyond = max(seh - ehi, elo - sel, 0.0)
    if ehi - elo <= 1e-9 * max(1.0, abs(ehi)):  # one level trained: no range to compare with
        level = abs(ehi) if ehi != 0.0 else 1.0
        if beyond / level > tol:
            out["electrical"] = (
                1.0 + beyond / level,
                (
                    f"electrical input [{sel:.3g}, {seh:.3g}] against the one level trained, "
                    f"{elo:.3g} ({beyond:.3g} beyond it)"
                ),
            )
        return out
    out_by = beyond / (ehi - elo)
    if out_by > tol:
        out["electrical"] = (
            1.0 + out_by,
            (
                f"electrical input [{sel:.3g}, {seh:.3g}] against [{elo:.3g}, {ehi:.3g}] "
                f"({out_by:.0%} of the range outside)"
            ),
        )
    return out


def envelope_note(kind: str, record: str, trained: dict[str, Any], seen: dict[str, Any]) -> str:
    """One line saying how record ``record`` leaves the ``kind`` model's training envelope, or
    ``""`` when it stays inside (see :func:`leaves`)."""
    out = leaves(trained, seen)
    if not out:
        return ""
    what = "; ".join(text for _, text in out.values())
    return f"{kind}: record {record!r} leaves the model's training envelope: {what}"
