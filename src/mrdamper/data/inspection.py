"""What is in a record and what looks wrong with it: the summary behind ``mrdamper info``.

:func:`record_summary` gives one record's sizes, ranges and electrical levels as JSON-safe data;
:func:`record_problems` lists what looks wrong (repairs made while reading, implausible values,
clipped force, nearly constant force, current outside the rig's range). :func:`common_input`
is the one rule for which electrical channel a set of records shares.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from mrdamper.data.experiment import ElectricalSource, Experiment

__all__ = [
    "CURRENT_RANGE",
    "MAX_LEVELS",
    "MIN_FORCE_STD",
    "common_input",
    "record_problems",
    "record_summary",
]

#: Coil current range of the rig [A] (paper Section IV); values outside are flagged.
CURRENT_RANGE = (0.0, 4.0)
#: Standard deviation of the force [N] below which the force is reported as nearly constant.
MIN_FORCE_STD = 1.0
#: Most distinct values for an electrical input to be shown as levels rather than a range.
MAX_LEVELS = 8


def _longest_run(mask: np.ndarray) -> int:
    if not mask.any():
        return 0
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return int((np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)).max())


def _levels(values: np.ndarray) -> list[float] | None:
    levels = np.unique(np.round(values, 9))
    return [float(v) for v in levels] if levels.size <= MAX_LEVELS else None


def record_problems(exp: Experiment) -> list[str]:
    """Return human-readable warnings about a record (empty if nothing was found).

    Parameters
    ----------
    exp : Experiment
        The record.

    Returns
    -------
    list of str

    Notes
    -----
    Checks
    ------
    * repairs made while reading (``metadata["repairs"]``: NaN samples, regenerated time, ...);
    * values beyond the plausibility bounds (``metadata["implausible"]``, see
      :mod:`mrdamper.data.plausibility`: usually wrong declared units);
    * a force plateau at its maximum or minimum: the extreme value held for at least
      ``max(10, n / 500)`` consecutive samples (clipping or sensor saturation);
    * force standard deviation below :data:`MIN_FORCE_STD` [N];
    * coil current outside :data:`CURRENT_RANGE` [A].
    """
    problems = [f"repaired: {r}" for r in exp.metadata.get("repairs", ())]
    problems += [f"implausible: {r}" for r in exp.metadata.get("implausible", ())]
    F = exp.F
    min_run = max(10, exp.n // 500)
    for label, extreme in (("maximum", F.max()), ("minimum", F.min())):
        run = _longest_run(F == extreme)
        if run >= min_run:
            problems.append(
                f"F held at its {label} {extreme:.6g} N for {run} consecutive samples "
                "(clipping or saturation?)"
            )
    std = float(np.std(F))
    if std < MIN_FORCE_STD:
        problems.append(f"force nearly constant (standard deviation {std:.3g} N)")
    if exp.i is not None:
        lo, hi = float(exp.i.min()), float(exp.i.max())
        if lo < CURRENT_RANGE[0] - 1e-9 or hi > CURRENT_RANGE[1] + 1e-9:
            problems.append(
                f"current spans [{lo:.4g}, {hi:.4g}] A, outside "
                f"{CURRENT_RANGE[0]:g}..{CURRENT_RANGE[1]:g} A"
            )
    return problems


def record_summary(exp: Experiment) -> dict[str, Any]:
    """Return one record's summary as JSON-safe data (the rows of ``mrdamper info``).

    Keys: ``name, samples, rate_hz, duration_s, x_mm, v_m_s, F_n`` (each range a ``[min, max]``
    pair), ``input`` (``"i"`` or ``"voltage"``), ``levels`` (distinct values, or None if more
    than :data:`MAX_LEVELS`), ``input_range``, ``problems`` and ``source``.

    Parameters
    ----------
    exp : Experiment
        The record.

    Returns
    -------
    dict
    """
    source = exp.electrical_channel
    el = exp.electrical(source)
    return {
        "name": exp.name,
        "samples": exp.n,
        "rate_hz": exp.fs,
        "duration_s": exp.duration,
        "x_mm": [float(exp.x.min() * 1e3), float(exp.x.max() * 1e3)],
        "v_m_s": [float(exp.v.min()), float(exp.v.max())],
        "F_n": [float(exp.F.min()), float(exp.F.max())],
        "input": source,
        "levels": _levels(el),
        "input_range": [float(el.min()), float(el.max())],
        "problems": record_problems(exp),
        "source": str(exp.metadata.get("source", "")),
    }


def common_input(records: Iterable[Any]) -> ElectricalSource | None:
    """The electrical channel every record has: ``"i"`` when all have a current, else
    ``"voltage"`` when all have a voltage, else None.

    Parameters
    ----------
    records : iterable
        Records (:class:`~mrdamper.data.Experiment` or anything with ``channel_names``).

    Returns
    -------
    {"i", "voltage"} or None
    """
    channels = [set(e.channel_names) for e in records]
    if all("i" in c for c in channels):
        return "i"
    if all("voltage" in c for c in channels):
        return "voltage"
    return None
