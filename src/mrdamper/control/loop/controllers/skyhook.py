"""Skyhook: ``F_d = c_sky z_s'`` when the damper can give it (``z_s' v > 0``), else 0."""

from __future__ import annotations

from dataclasses import dataclass

from mrdamper.control.loop.controllers.law import CTRL_SKYHOOK, ControllerLaw, hooks


@dataclass(frozen=True)
class Skyhook(ControllerLaw):
    """A damper hooked to the sky on the body."""

    def desired(self, vs: float, vu: float, c_sky: float, c_ground: float, alpha: float) -> float:
        return hooks(vs, vu, c_sky, c_ground)[0]


SKYHOOK = Skyhook(
    "skyhook",
    CTRL_SKYHOOK,
    "semi-active, body velocity (comfort)",
    gains=("c_sky",),
    objectives=("a_w",),
    front_gains=(500.0, 1000.0, 2000.0, 3000.0, 5000.0, 8000.0, 12000.0, 20000.0),
    colour="C0",
)
