"""Passive soft: the lowest input all the time."""

from mrdamper.control.loop.controllers.law import CTRL_PASSIVE, ControllerLaw

SOFT = ControllerLaw("soft", CTRL_PASSIVE, "passive, constant lowest input")
