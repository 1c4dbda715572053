"""Grouping records into electrical levels: the one rule the analysis and the study share.

Zone regression (eq. 17) needs force-velocity samples at constant electrical input. Records give
them in two ways:

* ``"current"``: each record is held at one level, named by its metadata ``current`` [A]
  (constant-current sine records); records of equal current are pooled;
* ``"plateaus"``: the electrical input steps between levels (stepped-current SC records); each
  record is cut into constant plateaus (:func:`~mrdamper.analysis.segment_plateaus`) and
  plateaus of equal level (within a tolerance) are pooled across records.

:func:`level_grouping` chooses between them (``"current"`` when every record has the metadata),
:func:`pool_by_level` does the pooling. :func:`~mrdamper.analysis.zone_fits_by_level` and the
study's force-velocity curves both call them, so a record lands in the same level everywhere.
(The LPV estimator's ``laws_by="bins"``, equal-count bins of a continuously varying scheduling
variable, is a different grouping for records without constant levels.)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Literal

import numpy as np

from mrdamper.analysis.zones import segment_plateaus
from mrdamper.data import Experiment, as_experiment_set
from mrdamper.errors import DataValidationError

__all__ = ["GroupBy", "level_grouping", "plateau_tolerance", "pool_by_level"]

#: How records are grouped into levels.
GroupBy = Literal["current", "plateaus"]
#: Pooled samples of one level: ``(v [m/s], F [N])`` pieces, one per record or plateau.
Pieces = list[tuple[np.ndarray, np.ndarray]]


def level_grouping(records: Iterable[Experiment]) -> GroupBy:
    """``"current"`` when every record carries metadata ``current``, else ``"plateaus"``.

    Parameters
    ----------
    records : iterable of Experiment
        The records to group (only their metadata is looked at).

    Returns
    -------
    {"current", "plateaus"}
    """
    return "current" if all("current" in e.metadata for e in records) else "plateaus"


def plateau_tolerance(signals: Sequence[np.ndarray]) -> float:
    """Default level tolerance of plateaus: 2 % of the largest range of the signals [A or V].

    Parameters
    ----------
    signals : sequence of ndarray
        Electrical inputs of the records.

    Returns
    -------
    float
        The tolerance (at least 1e-9).
    """
    span = max((float(np.ptp(s)) for s in signals), default=0.0)
    return max(0.02 * span, 1e-9)


def pool_by_level(
    data: Experiment | Iterable[Experiment],
    *,
    by: GroupBy = "current",
    source: Literal["i", "voltage"] = "i",
    tolerance: float | None = None,
    min_duration: float = 1.0,
    settle: float = 0.2,
) -> dict[float, Pieces]:
    """Pool the force-velocity samples of ``data`` per electrical level.

    Parameters
    ----------
    data : Experiment or iterable of Experiment
        Records.
    by : {"current", "plateaus"}
        Grouping (see the module docstring; :func:`level_grouping` chooses it from metadata).
    source : {"i", "voltage"}
        Electrical channel cut into plateaus.
    tolerance : float, optional
        Level tolerance of plateaus [A or V]; default :func:`plateau_tolerance`.
    min_duration : float
        Shortest plateau kept [s].
    settle : float
        Time skipped after each step [s].

    Returns
    -------
    dict
        Level [A or V] -> list of ``(v, F)`` pieces, levels in increasing order.

    Raises
    ------
    DataValidationError
        ``by="current"`` and a record lacks metadata ``current``, or ``by`` is unknown.
    """
    exps = as_experiment_set(data, name="levels")
    pools: dict[float, Pieces] = {}
    if by == "current":
        for e in exps:
            if "current" not in e.metadata:
                raise DataValidationError(
                    "current", f"record {e.name!r} has no metadata 'current'; use by='plateaus'"
                )
            pools.setdefault(float(e.metadata["current"]), []).append((e.v, e.F))
    elif by == "plateaus":
        sig = [np.asarray(e.electrical(source)) for e in exps]
        tol = tolerance if tolerance is not None else plateau_tolerance(sig)
        for e, s in zip(exps, sig):
            for a, b, lev in segment_plateaus(
                s, e.dt, tolerance=tol, min_duration=min_duration, settle=settle
            ):
                key = next((k for k in pools if abs(k - lev) <= tol), lev)
                pools.setdefault(key, []).append((e.v[a:b], e.F[a:b]))
    else:
        raise DataValidationError("by", f"expected 'current' or 'plateaus', got {by!r}")
    return {lev: pools[lev] for lev in sorted(pools)}
