"""What :mod:`mrdamper.control` reads of a damper model: :class:`DamperModel`.

Every tool of ``control/`` (the inverse, the loop, the exports) takes a damper model: a fitted
model of :mod:`mrdamper.models` (its capabilities, such as an inverse form or a per-sample step,
are the protocols of :mod:`mrdamper.models.protocols`), the reference
:class:`~mrdamper.control.loop.car.LinearDamper`, or a plug-in family's model. This protocol is
what they all have; a tool that needs more asks the model for its capability (``isinstance``
with a protocol of :mod:`mrdamper.models.protocols`, or the model's ``step()``).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

__all__ = ["DamperModel", "SampledModel", "StaticMapModel"]


@runtime_checkable
class DamperModel(Protocol):
    """A damper model as :mod:`mrdamper.control` reads it.

    Attributes
    ----------
    kind : str
        The model kind (a name of the kind table, ``"linear"`` for the reference damper).
    input : str
        Electrical input: ``"i"`` (current [A]) or ``"v"`` (voltage [V]).
    input_range : (float, float)
        Identified input range [input unit].
    """

    @property
    def kind(self) -> str: ...

    @property
    def input(self) -> str: ...

    @property
    def input_range(self) -> tuple[float, float]: ...


class StaticMapModel(DamperModel, Protocol):
    """A static map (SP family, Bingham): its force as a function of the motion and the input."""

    def force(self, x: Any, v: Any, i: Any) -> Any:
        """Force [N] at travel ``x`` [m], velocity ``v`` [m/s] and input ``i`` (arrays)."""
        ...


class SampledModel(DamperModel, Protocol):
    """A discrete-time model (LPV, LTI, NARX): it runs at its own rate."""

    @property
    def fs(self) -> float:
        """The model's sampling rate [Hz]."""
        ...
