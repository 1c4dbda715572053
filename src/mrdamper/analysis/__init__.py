"""Force-velocity analysis: three-zone regression (eq. 17) and its outer slopes re-estimated on
post-yield samples, records grouped into electrical levels, laws across current (eq. 18) and the
LPV scheduling input ``u(v, i)`` (eqs. 19-22), and the energy dissipated per displacement cycle."""

from mrdamper.analysis.energy import cycle_starts, energy_per_cycle
from mrdamper.analysis.laws import (
    ZoneLaws,
    ZoneLawWarning,
    fit_zone_laws,
    zone_fits_binned,
    zone_fits_by_level,
)
from mrdamper.analysis.levels import GroupBy, level_grouping, plateau_tolerance, pool_by_level
from mrdamper.analysis.scheduling import Reading, scheduling_input_arrays
from mrdamper.analysis.zones import ZoneFit, fit_zones, post_yield_slopes, segment_plateaus

__all__ = [
    "GroupBy",
    "Reading",
    "ZoneFit",
    "ZoneLawWarning",
    "ZoneLaws",
    "cycle_starts",
    "energy_per_cycle",
    "fit_zone_laws",
    "fit_zones",
    "level_grouping",
    "plateau_tolerance",
    "pool_by_level",
    "post_yield_slopes",
    "scheduling_input_arrays",
    "segment_plateaus",
    "zone_fits_binned",
    "zone_fits_by_level",
]
