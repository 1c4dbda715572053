"""The force-velocity analysis step of a study (paper III-C).

Zone fits per level and laws across current.

Records with metadata ``current`` (constant-current tests such as the Quiroz sine records) are
grouped by it; otherwise each record's electrical input is cut into constant plateaus (the
stepped-current SC experiments 6-8 of Table II). The outcome feeds Figs. 1-3 of the report and,
where an estimator takes them, the LPV model's laws.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from mrdamper.data import ExperimentSet
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import interrupt_in_chain

if TYPE_CHECKING:
    from mrdamper.analysis.levels import GroupBy

__all__ = ["AnalysisOutcome", "fv_curves", "run_analysis"]

#: Largest number of (v, F) points kept per level for the F-v map figure.
_MAX_POINTS = 4000


@dataclass(frozen=True, eq=False)
class AnalysisOutcome:
    """Result of the F-v analysis of one fold.

    Attributes
    ----------
    fits : tuple of ZoneFit
        Three-zone fits, one per level, sorted by level.
    laws : ZoneLaws or None
        Laws across current, or None when they could not be fitted (see ``error``).
    by : str
        ``"current"`` (metadata) or ``"plateaus"`` (segmented stepped input).
    curves : dict
        ``level -> (v [m/s], F [N])`` samples per level (subsampled) for the F-v map.
    error : str
        Why the analysis (or the laws) failed; empty on success.
    notes : str
        Warnings raised by the analysis (e.g. a central slope that is not the steepest).
    post_yield_laws : ZoneLaws or None
        The same laws with each level's outer slopes re-estimated on its post-yield samples
        (:func:`mrdamper.analysis.post_yield_slopes`), for the models whose setting
        ``outer_slopes`` asks for them (the default LPV input); ``laws`` stay the paper's. None
        when they break eq. (20) where the paper's laws do not (a note says so): such models
        get the paper's laws.
    """

    fits: tuple[Any, ...] = ()
    laws: Any = None
    by: str = ""
    curves: dict[float, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    error: str = ""
    notes: str = ""
    post_yield_laws: Any = None

    def laws_for(self, outer_slopes: str) -> Any:
        """The laws a model with the resolved setting ``outer_slopes`` is given (the paper's when
        there are no post-yield laws)."""
        if outer_slopes == "post-yield" and self.post_yield_laws is not None:
            return self.post_yield_laws
        return self.laws

    @property
    def ok(self) -> bool:
        """True when laws across current were fitted."""
        return self.laws is not None


def _thin(v: np.ndarray, F: np.ndarray, n: int = _MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    if v.size <= n:
        return v, F
    step = int(np.ceil(v.size / n))
    return v[::step], F[::step]


class PlateauOptions(TypedDict, total=False):
    """Plateau settings of the level grouping (see :func:`plateau_options`)."""

    min_duration: float
    settle: float


def plateau_options(records: ExperimentSet) -> PlateauOptions:
    """Plateau settings scaled to the records: the analysis defaults (1 s plateaus, 0.2 s settling)
    for records of 12 s or more, proportionally shorter for shortened records (``scale`` < 1)."""
    shortest = min((e.duration for e in records), default=12.0)
    min_duration = min(1.0, shortest / 12.0)
    return PlateauOptions(min_duration=min_duration, settle=min(0.2, min_duration / 5.0))


def fv_curves(
    records: ExperimentSet, source: ElectricalSource = "i", by: GroupBy | None = None
) -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """Pool (v, F) samples per electrical level, as the analysis groups them.

    Parameters
    ----------
    records : ExperimentSet
        Constant-level records (metadata ``current``) or stepped-input records.
    source : {"i", "voltage"}
        Electrical channel for plateau segmentation.
    by : {"current", "plateaus"}, optional
        Grouping; default ``"current"`` when every record has metadata ``current``.
    """
    from mrdamper.analysis import level_grouping, pool_by_level

    group = by or level_grouping(records)
    opts = plateau_options(records) if group == "plateaus" else PlateauOptions()
    pools = pool_by_level(records, by=group, source=source, **opts)
    return {
        lev: _thin(np.concatenate([p[0] for p in pieces]), np.concatenate([p[1] for p in pieces]))
        for lev, pieces in pools.items()
    }


def run_analysis(
    records: ExperimentSet, source: ElectricalSource = "i", degree: int = 2
) -> AnalysisOutcome:
    """Zone fits per level and laws across level; failures are reported, never raised.

    Parameters
    ----------
    records : ExperimentSet
        Analysis records of one fold.
    source : {"i", "voltage"}
        Electrical channel.
    degree : int
        Polynomial degree of the slope and intercept laws (2 in the paper).
    """
    if len(records) == 0:
        return AnalysisOutcome(error="no analysis records selected")
    try:
        from mrdamper.analysis import (
            ZoneLaws,
            fit_zone_laws,
            level_grouping,
            zone_fits_by_level,
        )
        from mrdamper.analysis.laws import OuterSlopes, laws_keeping_eq_20
    except ImportError as exc:  # pragma: no cover - analysis ships with the package
        return AnalysisOutcome(error=f"analysis unavailable: {exc}")
    by = level_grouping(records)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fits: Sequence[Any] = ()
        curves: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        try:
            curves = fv_curves(records, source, by)
            opts = plateau_options(records) if by == "plateaus" else PlateauOptions()
            fits = zone_fits_by_level(records, by=by, source=source, **opts)
            laws = fit_zone_laws(fits, degree=degree, strict=False)

            def fit_laws(outer: OuterSlopes, strict: bool) -> ZoneLaws:
                if outer == "zones":
                    return laws  # the paper's, fitted above
                post = zone_fits_by_level(
                    records,
                    by=by,
                    source=source,
                    outer_slopes=outer,
                    **opts,
                )
                return fit_zone_laws(post, degree=degree, strict=strict)

            post_laws: Any
            post_laws, used, why = laws_keeping_eq_20(fit_laws, strict=False)
            if used == "zones":  # every LPV uses the paper's laws
                warnings.warn(why, UserWarning, stacklevel=1)
                post_laws = None
            error = ""
        except Exception as exc:
            if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
                raise KeyboardInterrupt from exc
            laws, post_laws, error = None, None, f"{type(exc).__name__}: {exc}"
    notes = " | ".join(dict.fromkeys(str(w.message).replace("\n", " ")[:200] for w in caught))
    return AnalysisOutcome(tuple(fits), laws, by, curves, error, notes, post_laws)
