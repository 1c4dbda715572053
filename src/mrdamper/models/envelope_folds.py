"""Folds that leave the training envelope: for :func:`mrdamper.study.select` and the LPV
estimator's ``choose_on="beyond"`` (:mod:`mrdamper.models.lpv.choice`).

Cross-validation inside the envelope (leave a condition, a record or a time block out) rewards
models that interpolate. These folds hold out what lies beyond the rest of the data:

* several records: the records with the largest displacement range (``"largest amplitude held
  out"``), and those with the highest frequency content (the band of
  :func:`mrdamper.models.envelope.band_frequency`; ``"highest frequency held out"``), or, when the
  frequency fold holds out the same records or none, those with the largest velocity; then those
  with the lowest frequency content (``"lowest frequency held out"``: a slower test than any
  training record), unless an earlier fold holds out the same records. A group is
  the records within :data:`GROUP_TOLERANCE` of the largest value (all the currents of one sine
  condition); the fold exists only when the training records then stay below the held-out ones by
  more than that tolerance.
* one record: the later block whose displacement reach or largest velocity exceeds that of the
  earlier part the most (the cut is searched between :data:`CUTS`); the earlier part trains. No
  fold when no later block leaves the earlier part's range by more than the tolerance.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.models.envelope import band_frequency

__all__ = ["CUTS", "GROUP_TOLERANCE", "envelope_folds"]

#: Records within this fraction of the largest value are held out together [-]; the training
#: records must stay below the held-out ones by more than it.
GROUP_TOLERANCE = 0.10
#: Candidate cuts of a single record (fraction of its samples that trains) [-].
CUTS: tuple[float, ...] = (0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85)

Fold = tuple[str, ExperimentSet, ExperimentSet]


def _span(e: Experiment) -> float:
    return float(np.ptp(e.x))


def _band(e: Experiment) -> float:
    return band_frequency(e.v, e.dt)


def _vmax(e: Experiment) -> float:
    return float(np.max(np.abs(e.v)))


_MEASURES: tuple[tuple[str, Callable[[Experiment], float], str, float], ...] = (
    ("largest amplitude", _span, "mm range", 1e3),
    ("highest frequency", _band, "Hz", 1.0),
    ("largest velocity", _vmax, "m/s", 1.0),
)


def _held_out(
    exps: ExperimentSet, measure: Callable[[Experiment], float], low: bool = False
) -> set[str] | None:
    """The group of records of the largest value of ``measure`` (of the smallest with ``low``,
    taken as the largest of its reciprocal), or None when the others do not stay short of it by
    more than :data:`GROUP_TOLERANCE`."""
    vals = {e.name: measure(e) for e in exps}
    if low:
        if min(vals.values()) <= 0:
            return None
        vals = {n: 1.0 / v for n, v in vals.items()}
    top = max(vals.values())
    if top <= 0:
        return None
    held = {n for n, v in vals.items() if v >= top / (1 + GROUP_TOLERANCE)}
    rest = [v for n, v in vals.items() if n not in held]
    if not rest or max(rest) * (1 + GROUP_TOLERANCE) > min(vals[n] for n in held):
        return None
    return held


def _record_folds(exps: ExperimentSet) -> list[Fold]:
    out: list[Fold] = []
    used: list[set[str]] = []

    def add(
        label: str,
        held: set[str],
        measure: Callable[[Experiment], float],
        unit: str,
        scale: float,
        low: bool,
    ) -> None:
        used.append(held)
        train = ExperimentSet([e for e in exps if e.name not in held], name=exps.name)
        test = ExperimentSet([e for e in exps if e.name in held], name=exps.name)
        near, far, sign = (max, min, "<") if low else (min, max, ">")
        a = near(measure(e) for e in test) * scale
        b = far(measure(e) for e in train) * scale
        out.append((f"beyond: {label} held out ({a:.3g} {unit} {sign} {b:.3g})", train, test))

    for label, measure, unit, scale in _MEASURES:
        if label == "largest velocity" and len(out) >= 2:
            break
        held = _held_out(exps, measure)
        if held is None or held in used:
            continue
        add(label, held, measure, unit, scale, low=False)
    # the other end of the frequency band: a slower test than any training record
    held = _held_out(exps, _band, low=True)
    if held is not None and held not in used:
        add("lowest frequency", held, _band, "Hz", 1.0, low=True)
    return out


def _reach(e: Experiment, mid: float) -> float:
    return float(np.max(np.abs(e.x - mid)))


def _time_fold(e: Experiment) -> list[Fold]:
    best: tuple[float, int] | None = None
    for frac in CUTS:
        cut = round(frac * e.n)
        if cut < 2 or e.n - cut < 2:
            continue
        early, late = e.x[:cut], e.x[cut:]
        mid = 0.5 * (float(np.min(early)) + float(np.max(early)))
        half = 0.5 * float(np.ptp(early))
        v_early = float(np.max(np.abs(e.v[:cut])))
        ratios = [
            float(np.max(np.abs(late - mid))) / half if half > 0 else 0.0,
            float(np.max(np.abs(e.v[cut:]))) / v_early if v_early > 0 else 0.0,
        ]
        r = max(ratios)
        if r > 1 + GROUP_TOLERANCE / 2 and (best is None or r > best[0]):
            best = (r, cut)
    if best is None:
        return []
    r, cut = best
    train = ExperimentSet([e.slice(0, cut, name=f"{e.name}[:{cut}]")])
    test = ExperimentSet([e.slice(cut, None, name=f"{e.name}[{cut}:]")])
    return [(f"beyond: later block [{cut}:] reaches {r:.2f} x the earlier range", train, test)]


def envelope_folds(exps: ExperimentSet) -> list[Fold]:
    """Training / left-out splits whose left-out part leaves the training part's envelope.

    Parameters
    ----------
    exps : ExperimentSet
        The user's records.

    Returns
    -------
    list of (label, train, test)
        Possibly empty (records that all share one envelope, a record that never exceeds its
        earlier range); labels start with ``"beyond: "``.
    """
    if len(exps) == 1:
        return _time_fold(exps[0])
    return _record_folds(exps)
