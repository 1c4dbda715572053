"""Turn a data set and a :class:`~mrdamper.study.protocol.Protocol` into folds.

A fold is one (analysis, training, scoring) triple. Every scored row of a study names its fold, and
:func:`roles_frame` lists which record played which role in which fold, so any overlap between
training and scoring is visible in the report.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from mrdamper.errors import SchemaError
from mrdamper.study.protocol import Protocol
from mrdamper.study.records import Record, Records, as_list, same_kind

__all__ = ["Fold", "make_folds", "roles_frame"]


@dataclass(frozen=True, eq=False)
class Fold:
    """One training / scoring arrangement.

    Attributes
    ----------
    name : str
        Fold name (``"all"``, ``"condition=5mm_3Hz"``, ``"time 70/30"``).
    analysis : ExperimentSet or SourceSet
        Records of the force-velocity analysis (may be empty).
    train : ExperimentSet or SourceSet
        Records that identify the models.
    score : ExperimentSet or SourceSet
        Records that are scored.

    The sets are of the kind of the study's data: records in memory, or sources read where they
    are used (:class:`~mrdamper.data.RecordSource`).
    """

    name: str
    analysis: Records
    train: Records
    score: Records


def _without(data: Records, names: set[str]) -> Records:
    return same_kind(data, [e for e in data if e.name not in names])


def _time_part(e: Record, fraction: float, head: bool) -> Record:
    cut = round(fraction * e.n)
    if cut < 2 or e.n - cut < 2:
        raise SchemaError(
            f"split.fraction: record {e.name!r} has {e.n} samples, too few to cut at {fraction:g}"
        )
    pct = f"{fraction:.0%}"
    if head:
        return e.slice(0, cut, name=f"{e.name}[:{pct}]")
    return e.slice(cut, None, name=f"{e.name}[{pct}:]")


def make_folds(data: Records, protocol: Protocol) -> list[Fold]:
    """Build the folds of ``protocol`` on ``data``.

    Parameters
    ----------
    data : ExperimentSet or SourceSet
        Every record of the study (only headers are needed, except for time splits, which read
        a source once to time its parts).
    protocol : Protocol
        Selections and split.

    Returns
    -------
    list of Fold

    Raises
    ------
    SchemaError
        If a fold would have no training or no scoring record; the message names the selection.
    """
    analysis = (
        protocol.analysis.select(data) if protocol.analysis is not None else same_kind(data, [])
    )
    train = protocol.train.select(data)
    score = protocol.score.select(data)
    split = protocol.split
    folds: list[Fold] = []
    if split.kind == "fixed":
        sc = (
            _without(score, set(train.names) | set(analysis.names))
            if protocol.exclude_trained
            else score
        )
        folds.append(Fold("all", analysis, train, sc))
    elif split.kind == "time":
        f = float(split.fraction)
        folds.append(
            Fold(
                f"time {f:.0%}/{1 - f:.0%}",
                same_kind(data, [_time_part(e, f, True) for e in analysis]),
                same_kind(data, [_time_part(e, f, True) for e in train]),
                same_kind(data, [_time_part(e, f, False) for e in score]),
            )
        )
    elif split.kind == "k-fold":
        k = min(int(split.k), len(score))
        for j in range(k):
            scored = {e.name for pos, e in enumerate(as_list(score)) if pos % k == j}
            tr = same_kind(data, [e for e in train if e.name not in scored])
            an = same_kind(data, [e for e in analysis if e.name not in scored])
            sc = same_kind(data, [e for e in score if e.name in scored])
            if protocol.exclude_trained:
                sc = _without(sc, set(tr.names) | set(an.names))
            folds.append(Fold(f"fold {j + 1} of {k}", an, tr, sc))
    else:
        label = split.key or "group"
        order: list[object] = []
        for e in score:
            g = split.group_of(e)
            if g not in order:
                order.append(g)
        for g in order:
            tr = same_kind(data, [e for e in train if split.group_of(e) != g])
            an = same_kind(data, [e for e in analysis if split.group_of(e) != g])
            sc = same_kind(data, [e for e in score if split.group_of(e) == g])
            if protocol.exclude_trained:
                sc = _without(sc, set(tr.names) | set(an.names))
            folds.append(Fold(f"{label}={g}", an, tr, sc))
    for fold in folds:
        if len(fold.train) == 0:
            raise SchemaError(
                f"train: fold {fold.name!r} has no training record (selection: "
                f"{protocol.train.describe()}; data: {len(data)} records)"
            )
    if not folds or sum(len(f.score) for f in folds) == 0:
        raise SchemaError(
            f"score: no record left to score (selection: {protocol.score.describe()}; "
            f"exclude_trained={protocol.exclude_trained}; data: {len(data)} records)"
        )
    return folds


def roles_frame(folds: list[Fold]) -> pd.DataFrame:
    """One row per (fold, record, role) with role in ``analysis``, ``train``, ``score``."""
    rows = []
    for f in folds:
        for role, s in (("analysis", f.analysis), ("train", f.train), ("score", f.score)):
            for e in s:
                rows.append(
                    {
                        "fold": f.name,
                        "record": e.name,
                        "role": role,
                        "samples": e.n,
                        "duration_s": e.duration,
                    }
                )
    return pd.DataFrame(rows, columns=["fold", "record", "role", "samples", "duration_s"])
