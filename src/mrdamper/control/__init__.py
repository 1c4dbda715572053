"""Control export of the LPV model: state-space realisation (eqs. 10-15), frozen-rho LTI systems
(python-control), frozen-pole stability over the scheduling range, the inverse (current-for-force)
model."""

from mrdamper.control.inverse import InverseResult, driver_command, inverse_current
from mrdamper.control.statespace import (
    StateSpaceMatrices,
    frozen_stability,
    simulate_state_space,
    state_space,
    to_control,
)

__all__ = [
    "InverseResult",
    "StateSpaceMatrices",
    "driver_command",
    "frozen_stability",
    "inverse_current",
    "simulate_state_space",
    "state_space",
    "to_control",
]
