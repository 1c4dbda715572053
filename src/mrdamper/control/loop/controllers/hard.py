"""Passive hard: the highest input all the time."""

from __future__ import annotations

from dataclasses import dataclass

from mrdamper.control.loop.controllers.law import CTRL_PASSIVE, ControllerLaw


@dataclass(frozen=True)
class Hard(ControllerLaw):
    """The highest input of the range."""

    def constant_input(self, lo: float, hi: float) -> float:
        return hi


HARD = Hard("hard", CTRL_PASSIVE, "passive, constant highest input")
