"""Groundhook: ``F_d = -c_ground z_u'`` when the damper can give it (``-z_u' v > 0``), else 0."""

from __future__ import annotations

from dataclasses import dataclass

from mrdamper.control.loop.controllers.law import CTRL_GROUNDHOOK, ControllerLaw, hooks


@dataclass(frozen=True)
class Groundhook(ControllerLaw):
    """A damper hooked to the ground on the wheel."""

    def desired(self, vs: float, vu: float, c_sky: float, c_ground: float, alpha: float) -> float:
        return hooks(vs, vu, c_sky, c_ground)[1]


GROUNDHOOK = Groundhook(
    "groundhook",
    CTRL_GROUNDHOOK,
    "semi-active, wheel velocity (road holding)",
    gains=("c_ground",),
    objectives=("rms_tyre_load",),
    front_gains=(500.0, 1000.0, 2000.0, 3000.0, 5000.0, 8000.0, 12000.0, 20000.0),
    colour="C2",
)
