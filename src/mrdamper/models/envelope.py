"""The training envelope of a model: how far its identification data moved the damper.

Stored at fit time in ``provenance["envelope"]`` (:meth:`mrdamper.models.base.Estimator.fit`), so
a tool that uses the model elsewhere (the quarter car) can say how far it leaves it. The same
function measures the envelope of any motion (a loop run), so the two are comparable.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

__all__ = ["SWITCH_FRACTION", "envelope_of", "excursions", "training_envelope"]

#: A sample "switches" when its input changes by more than this fraction of the input range [-].
SWITCH_FRACTION = 0.05


def envelope_of(
    x: Sequence[np.ndarray], v: Sequence[np.ndarray], e: Sequence[np.ndarray], F: Any = None
) -> dict[str, Any]:
    """Envelope of records (lists of per-record arrays).

    Returns
    -------
    dict
        ``v_max`` largest ``|v|`` [m/s]; ``x_range`` [min, max] displacement [m]; ``e_range``
        [min, max] electrical input [A] or [V]; ``v_switch`` largest ``|v|`` [m/s] at a sample
        where the input changes by more than :data:`SWITCH_FRACTION` of its range (current
        switching while moving; 0 when it never switches); ``f_max`` largest ``|F|`` [N] when
        ``F`` is given.
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
    return out


def training_envelope(records: Iterable[Any], electrical: Sequence[np.ndarray]) -> dict[str, Any]:
    """:func:`envelope_of` the training records (``electrical``: their input channel)."""
    recs = list(records)
    return envelope_of(
        [r.x for r in recs], [r.v for r in recs], list(electrical), [r.F for r in recs]
    )


def excursions(trained: dict[str, Any], seen: dict[str, Any]) -> dict[str, float]:
    """How far ``seen`` leaves ``trained`` (ratios > 1 leave it).

    Returns
    -------
    dict
        ``velocity`` seen / trained ``v_max``; ``stroke`` seen / trained displacement span;
        ``switching`` seen / trained ``v_switch`` (inf when training never switched while moving
        and the run does).
    """

    def ratio(a: float, b: float) -> float:
        return float(a / b) if b > 0 else (float("inf") if a > 0 else 0.0)

    span_t = trained["x_range"][1] - trained["x_range"][0]
    span_s = seen["x_range"][1] - seen["x_range"][0]
    return {
        "velocity": ratio(seen["v_max"], trained["v_max"]),
        "stroke": ratio(span_s, span_t),
        "switching": ratio(seen["v_switch"], trained["v_switch"]),
    }
