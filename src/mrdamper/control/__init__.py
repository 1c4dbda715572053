"""Control export of the identified models: state-space realisation (eqs. 10-15), frozen-rho LTI
systems (python-control), frozen-pole stability over the scheduling range, the inverse
(current-for-force) model and its check on records, a quarter-car evaluation of semi-active
controllers, the export of the matrices to .mat / JSON and of the model and its inverse to C99."""

from mrdamper.control.export.c_export import C_KINDS, c_source, export_c
from mrdamper.control.export.matrices import EXPORT_SCHEMA, export_lpv, lpv_export_data
from mrdamper.control.export.statespace import (
    ControlGrid,
    StateSpaceMatrices,
    control_grid,
    frozen_stability,
    simulate_state_space,
    state_space,
    to_control,
)
from mrdamper.control.inverse.current import (
    InverseResult,
    driver_command,
    force_authority,
    inverse_current,
)
from mrdamper.control.inverse.inverse_check import InverseCheck, check_inverse, check_inverse_frame
from mrdamper.control.loop.comfort import weighted_rms, wk_response
from mrdamper.control.loop.quarter_car import (
    CONTROLLERS,
    Controller,
    LinearDamper,
    QuarterCar,
    QuarterCarResult,
    Road,
    bump_road,
    iso_road,
    simulate_quarter_car,
)
from mrdamper.control.loop.quarter_car_study import ControllerComparison, compare_controllers

__all__ = [
    "CONTROLLERS",
    "C_KINDS",
    "EXPORT_SCHEMA",
    "ControlGrid",
    "Controller",
    "ControllerComparison",
    "InverseCheck",
    "InverseResult",
    "LinearDamper",
    "QuarterCar",
    "QuarterCarResult",
    "Road",
    "StateSpaceMatrices",
    "bump_road",
    "c_source",
    "check_inverse",
    "check_inverse_frame",
    "compare_controllers",
    "control_grid",
    "driver_command",
    "export_c",
    "export_lpv",
    "force_authority",
    "frozen_stability",
    "inverse_current",
    "iso_road",
    "lpv_export_data",
    "simulate_quarter_car",
    "simulate_state_space",
    "state_space",
    "to_control",
    "weighted_rms",
    "wk_response",
]
