"""Figures of the paper, one function each; every function takes ``ax=None`` (or ``axes=None``) and
returns what it drew on.

========================  ============================================================
paper figure              function
========================  ============================================================
Fig. 1 F-v map            :func:`plot_fv_map`
Fig. 2 zone regression    :func:`plot_zone_fit`
Fig. 3 laws vs current    :func:`plot_zone_laws`
Fig. 4 LTI on hysteresis  :func:`plot_lti_hysteresis`
Fig. 6 LPV tracking       :func:`plot_model_tracking`
Figs. 7, 8 box plots      :func:`plot_index_boxes`
Fig. 9 force-time         :func:`plot_force_time`
Fig. 10 F-v all models    :func:`plot_fv_models`
Figs. 9-11 small multiples :func:`plot_model_panels` (overlay + one panel per model; F-t, F-v, F-x)
========================  ============================================================
"""

from mrdamper.plotting._common import PRINT_STYLE
from mrdamper.plotting.comparison import plot_force_time, plot_fv_models, plot_index_boxes
from mrdamper.plotting.fv import plot_fv_map, plot_zone_fit
from mrdamper.plotting.laws import plot_zone_laws
from mrdamper.plotting.panels import plot_model_panels
from mrdamper.plotting.timeseries import plot_lti_hysteresis, plot_model_tracking

__all__ = [
    "PRINT_STYLE",
    "plot_force_time",
    "plot_fv_map",
    "plot_fv_models",
    "plot_index_boxes",
    "plot_lti_hysteresis",
    "plot_model_panels",
    "plot_model_tracking",
    "plot_zone_fit",
    "plot_zone_laws",
]
