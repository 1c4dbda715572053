"""Control export of the LPV model: state-space realisation (eqs. 10-15), frozen-rho LTI systems
(python-control), frozen-pole stability over the scheduling range, the inverse (current-for-force)
model and the export of the matrices to .mat / JSON."""

from mrdamper.control.export import EXPORT_SCHEMA, export_lpv, lpv_export_data
from mrdamper.control.inverse import InverseResult, driver_command, inverse_current
from mrdamper.control.statespace import (
    StateSpaceMatrices,
    frozen_stability,
    simulate_state_space,
    state_space,
    to_control,
)

__all__ = [
    "EXPORT_SCHEMA",
    "InverseResult",
    "StateSpaceMatrices",
    "driver_command",
    "export_lpv",
    "frozen_stability",
    "inverse_current",
    "lpv_export_data",
    "simulate_state_space",
    "state_space",
    "to_control",
]
