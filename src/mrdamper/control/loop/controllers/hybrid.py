"""Hybrid: ``alpha`` skyhook + ``(1 - alpha)`` groundhook."""

from __future__ import annotations

from dataclasses import dataclass

from mrdamper.control.loop.controllers.law import CTRL_HYBRID, ControllerLaw, hooks


@dataclass(frozen=True)
class Hybrid(ControllerLaw):
    """Skyhook and groundhook blended by ``alpha``."""

    def desired(self, vs: float, vu: float, c_sky: float, c_ground: float, alpha: float) -> float:
        sky, gnd = hooks(vs, vu, c_sky, c_ground)
        return alpha * sky + (1.0 - alpha) * gnd

    def sweep(self, gain: float, alphas: tuple[float, ...]) -> list[dict[str, float]]:
        return [{"c_sky": gain, "c_ground": gain, "alpha": a} for a in alphas]


HYBRID = Hybrid(
    "hybrid",
    CTRL_HYBRID,
    "semi-active, skyhook and groundhook blended by alpha",
    gains=("c_sky", "c_ground", "alpha"),
    objectives=("a_w", "rms_tyre_load"),
    front_gains=(1000.0, 3000.0, 8000.0, 20000.0),
    colour="C3",
)
