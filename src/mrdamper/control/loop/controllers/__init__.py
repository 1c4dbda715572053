"""The controllers, one module each, and their registry.

A controller is a :class:`~mrdamper.control.loop.controllers.law.ControllerLaw`: its name, its
law of desired force (or constant input), the gains it reads and how the gain fronts sweep it.
:data:`LAWS` is the registry, in the order of the default comparison; adding a controller is a
module beside these and one line here (``docs/architecture.md`` shows one).
"""

from __future__ import annotations

from mrdamper.control.loop.controllers.groundhook import GROUNDHOOK
from mrdamper.control.loop.controllers.hard import HARD
from mrdamper.control.loop.controllers.hybrid import HYBRID
from mrdamper.control.loop.controllers.law import ControllerLaw
from mrdamper.control.loop.controllers.skyhook import SKYHOOK
from mrdamper.control.loop.controllers.soft import SOFT
from mrdamper.errors import DataValidationError

__all__ = ["LAWS", "ControllerLaw", "law_of", "register"]

#: Name -> controller, in the order of the default comparison.
LAWS: dict[str, ControllerLaw] = {}


def register(law: ControllerLaw) -> ControllerLaw:
    """Add ``law`` to :data:`LAWS` (a name already taken is refused) and return it."""
    if not isinstance(law, ControllerLaw):
        raise DataValidationError("law", f"expected a ControllerLaw, got {type(law).__name__}")
    if law.name in LAWS:
        raise DataValidationError("law", f"a controller named {law.name!r} is registered")
    LAWS[law.name] = law
    return law


def law_of(name: str) -> ControllerLaw:
    """The registered controller ``name`` (one line naming the known ones otherwise)."""
    try:
        return LAWS[name]
    except (KeyError, TypeError):
        raise DataValidationError(
            "controller", f"expected one of {tuple(LAWS)}, got {name!r}"
        ) from None


register(SOFT)
register(HARD)
register(SKYHOOK)
register(GROUNDHOOK)
register(HYBRID)
