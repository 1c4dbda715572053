"""What a controller is: a strategy object the loop asks for its facts (see :mod:`.` for the
registry).

A :class:`ControllerLaw` says how a controller chooses the damper's input: passive (a constant
input, :meth:`ControllerLaw.constant_input`) or semi-active (a desired force,
:meth:`ControllerLaw.desired`, realised through the damper model's inverse). The compiled loops
(:mod:`mrdamper.control.loop._quarter_car_kernels`) compute the desired force by the law's
``code``; :meth:`ControllerLaw.desired` is the same law in Python, checked against the kernel by
the tests. The gains a law reads are attributes of :class:`~mrdamper.control.loop.car.Controller`
(``c_sky``, ``c_ground``, ``alpha``); the gain fronts (:mod:`mrdamper.control.loop.fronts`) sweep
:attr:`ControllerLaw.front_gains` and tune for :attr:`ControllerLaw.objectives`.
"""

from __future__ import annotations

from dataclasses import dataclass

from mrdamper.control.loop._quarter_car_kernels import (
    CTRL_GROUNDHOOK,
    CTRL_HYBRID,
    CTRL_PASSIVE,
    CTRL_SKYHOOK,
)

__all__ = [
    "CTRL_GROUNDHOOK",
    "CTRL_HYBRID",
    "CTRL_PASSIVE",
    "CTRL_SKYHOOK",
    "ControllerLaw",
    "hooks",
]


def hooks(vs: float, vu: float, c_sky: float, c_ground: float) -> tuple[float, float]:
    """The skyhook and groundhook desired forces [N] of body velocity ``vs`` and wheel velocity
    ``vu`` [m/s] (damper velocity ``vs - vu``; each is 0 where the damper cannot give it)."""
    vrel = vs - vu
    sky = c_sky * vs if vs * vrel > 0.0 else 0.0
    gnd = -c_ground * vu if -vu * vrel > 0.0 else 0.0
    return sky, gnd


@dataclass(frozen=True)
class ControllerLaw:
    """A controller as the loop reads it (subclass and override :meth:`desired` or
    :meth:`constant_input`).

    Attributes
    ----------
    name : str
        The name users pass (``--controllers``, ``Controller(kind=...)``).
    code : int
        The law's code in the compiled loops (``CTRL_*`` of
        :mod:`mrdamper.control.loop._quarter_car_kernels`).
    summary : str
        One line for tables and help.
    gains : tuple of str
        The :class:`~mrdamper.control.loop.car.Controller` attributes the law reads.
    objectives : tuple of str
        Metrics the gain fronts tune it for (empty: not swept).
    front_gains : tuple of float
        Gains the fronts sweep [N s/m].
    colour : str
        Matplotlib colour of its points in the fronts figure.
    """

    name: str
    code: int
    summary: str
    gains: tuple[str, ...] = ()
    objectives: tuple[str, ...] = ()
    front_gains: tuple[float, ...] = ()
    colour: str = "0.3"

    @property
    def passive(self) -> bool:
        """A constant input (no desired force, no inverse)."""
        return not self.gains

    def constant_input(self, lo: float, hi: float) -> float:
        """The constant input of a passive run within the limits ``[lo, hi]`` [input unit]
        (unused by a semi-active controller, which starts at ``lo``)."""
        return lo

    def desired(self, vs: float, vu: float, c_sky: float, c_ground: float, alpha: float) -> float:
        """Desired damper force [N] at body / wheel velocity ``vs`` / ``vu`` [m/s] (NaN:
        passive)."""
        return float("nan")

    def sweep(self, gain: float, alphas: tuple[float, ...]) -> list[dict[str, float]]:
        """The gains (keyword arguments of :class:`~mrdamper.control.loop.car.Controller`) of one
        gain of the fronts' sweep [N s/m]; ``alphas`` are the hybrid weights swept [-]."""
        return [{g: gain for g in self.gains if g != "alpha"}]
