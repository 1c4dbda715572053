"""Integration-step check of stiff models: halving the step must not change the free run.

Used by the P-15 and Spencer estimators after identification. Each training record is simulated
with the model's own step and with half of it; the discrepancy is measured in the units of ESR
(paper eq. 24): ``mean((F_h - F_h/2)^2) / var(F_measured)``. Above ``tolerance`` the step is too
coarse for the identified coefficients: a :class:`RuntimeWarning` names the model, the record and
the discrepancy, and the result (always) goes to the model's provenance.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.data import Experiment
from mrdamper.errors import SimulationDivergedError

__all__ = ["step_halving_check"]


def step_halving_check(
    kind: str,
    records: Iterable[Experiment],
    simulate: Callable[[Experiment, int], np.ndarray],
    tolerance: float,
) -> dict[str, Any]:
    """Compare each record's free run at the nominal step and at half of it.

    Parameters
    ----------
    kind : str
        Model kind (named in the warning).
    records : iterable of Experiment
        Training records (those whose nominal free run did not diverge).
    simulate : callable
        ``simulate(record, k)``: free-run force [N] with ``k`` times the nominal number of
        integration steps per sample (``k`` is 1 or 2).
    tolerance : float
        Largest accepted discrepancy (ESR units).

    Returns
    -------
    dict
        ``tolerance``, ``discrepancy`` (record -> value), ``max_discrepancy``, ``worst_record``,
        ``passed``.
    """
    disc: dict[str, float] = {}
    for e in records:
        var = float(np.var(e.F)) or 1.0
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                d = float(np.mean((simulate(e, 1) - simulate(e, 2)) ** 2) / var)
        except SimulationDivergedError:
            d = float("inf")
        disc[e.name] = d
    worst = max(disc, key=lambda k: disc[k]) if disc else ""
    dmax = disc[worst] if disc else 0.0
    passed = bool(dmax <= tolerance)
    if not passed:
        warn_user(
            f"{kind}: halving the integration step changes the free run of training record "
            f"{worst!r} by {dmax:.3g} (ESR units), above the tolerance {tolerance:g}; the "
            "integration step is too coarse for these coefficients",
            RuntimeWarning,
        )
    return {
        "tolerance": float(tolerance),
        "discrepancy": disc,
        "max_discrepancy": float(dmax),
        "worst_record": worst,
        "passed": passed,
    }
