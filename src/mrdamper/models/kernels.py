"""The families' per-sample compiled functions, public for the tools that step a model.

Each function is defined once, in its family's kernel module, and used there by the family's
per-sample step (:mod:`mrdamper.models.step`) and its free-run kernels; the inverse, the quarter
car and the exports of :mod:`mrdamper.control` import them from here instead of keeping copies.

* LPV / LTI (:mod:`mrdamper.models.lpv.step`): :func:`lpv_coefficients` (the output step as a
  polynomial in the present scheduling value), :func:`poly`, :func:`dpoly`, :func:`zone_input`
  (the zone-law input, static or hysteretic; modes :data:`MODE_V`, :data:`MODE_CONTINUOUS`,
  :data:`MODE_LITERAL`);
* every family's drive lag (:mod:`mrdamper.models._lag`): :func:`lag_step`;
* the inverse's allowed interval at one sample, written once (:mod:`mrdamper.models._interval`):
  :func:`allowed_interval` (input limits, drive-lag reach, rate bound), :func:`held_input` (what
  the regularisation pulls towards) and :func:`lag_command`;
* hysteretic input (:mod:`mrdamper.analysis.hysteretic`): :func:`dahl_step`;
* static maps, SP-1..SP-4 and Bingham (:mod:`mrdamper.models.sp.kernels`): :func:`sp_force1`
  (one sample of the map) and :func:`sp_dforce1` (its derivative in the input);
* Spencer (:mod:`mrdamper.models.spencer.kernels`): its form :class:`SpencerForm`, parameter
  order and divergence bounds, for the C rendering of its step;
* tanh, Bouc-Wen, Dahl and LuGre (:mod:`mrdamper.models.hysteresis.kernels`): their form
  :class:`HysteresisForm`, family codes :data:`HYSTERESIS_FAMILIES`, parameter orders
  :data:`HYSTERESIS_PARAM_NAMES` and divergence bound :data:`HYSTERESIS_Z_LIMIT`, for the C
  rendering of their step;
* the forms and constants the C renderers of P-15 (:class:`P15Form`, :data:`P15_GAMMA`,
  :data:`P15_MAX_SUBSTEPS`), NARX (:class:`NARXForm`) and LPV (:data:`LPV_N_HEAD`) read.

Caveat of numba's disk cache: a cached kernel that calls one of these functions is not recompiled
when the function changes; delete the caller's ``__pycache__/*.nb*`` files after editing here.
"""

from __future__ import annotations

from mrdamper.analysis.hysteretic import dahl_step
from mrdamper.models._interval import allowed_interval, held_input, lag_command
from mrdamper.models._inverse_step import _N_BISECT as INVERSE_N_BISECT
from mrdamper.models._inverse_step import reg_solve_poly, reg_solve_static, solve_interval
from mrdamper.models._lag import lag_step
from mrdamper.models.hysteresis.kernels import FAMILIES as HYSTERESIS_FAMILIES
from mrdamper.models.hysteresis.kernels import PARAM_NAMES as HYSTERESIS_PARAM_NAMES
from mrdamper.models.hysteresis.kernels import Z_LIMIT as HYSTERESIS_Z_LIMIT
from mrdamper.models.hysteresis.kernels import HysteresisForm
from mrdamper.models.lpv.step import (
    MODE_CONTINUOUS,
    MODE_LITERAL,
    MODE_V,
    dpoly,
    lpv_coefficients,
    poly,
    zone_input,
)
from mrdamper.models.lpv.step import N_HEAD as LPV_N_HEAD
from mrdamper.models.narx.kernels import NARXForm
from mrdamper.models.p15.kernels import GAMMA as P15_GAMMA
from mrdamper.models.p15.kernels import MAX_SUBSTEPS as P15_MAX_SUBSTEPS
from mrdamper.models.p15.kernels import P15Form
from mrdamper.models.sp.kernels import sp_dforce1, sp_force1
from mrdamper.models.spencer.kernels import PARAM_NAMES as SPENCER_PARAM_NAMES
from mrdamper.models.spencer.kernels import Y_LIMIT as SPENCER_Y_LIMIT
from mrdamper.models.spencer.kernels import Z_LIMIT as SPENCER_Z_LIMIT
from mrdamper.models.spencer.kernels import SpencerForm

__all__ = [
    "HYSTERESIS_FAMILIES",
    "HYSTERESIS_PARAM_NAMES",
    "HYSTERESIS_Z_LIMIT",
    "INVERSE_N_BISECT",
    "LPV_N_HEAD",
    "MODE_CONTINUOUS",
    "MODE_LITERAL",
    "MODE_V",
    "P15_GAMMA",
    "P15_MAX_SUBSTEPS",
    "SPENCER_PARAM_NAMES",
    "SPENCER_Y_LIMIT",
    "SPENCER_Z_LIMIT",
    "HysteresisForm",
    "NARXForm",
    "P15Form",
    "SpencerForm",
    "allowed_interval",
    "dahl_step",
    "dpoly",
    "held_input",
    "lag_command",
    "lag_step",
    "lpv_coefficients",
    "poly",
    "reg_solve_poly",
    "reg_solve_static",
    "solve_interval",
    "sp_dforce1",
    "sp_force1",
    "zone_input",
]
