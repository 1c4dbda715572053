"""Control export of the LPV model: state-space realisation (eqs. 10-15), frozen-rho LTI systems
(python-control), frozen-pole stability over the scheduling range."""

from mrdamper.control.statespace import (
    StateSpaceMatrices,
    frozen_stability,
    simulate_state_space,
    state_space,
    to_control,
)

__all__ = ["StateSpaceMatrices", "frozen_stability", "simulate_state_space", "state_space", "to_control"]
