"""The names of the built-in controllers, in the order of the default comparison.

Plain data (no imports), so that what only needs the names reads them without loading the
compiled loops: the command line's ``quartercar --controllers`` help and default, and the rig's
closed-loop DoE extension (:mod:`mrdamper.rig.doe_control`, a layer below :mod:`mrdamper.control`).
The controllers themselves are the registry :mod:`mrdamper.control.loop.controllers`, which
registers exactly these, in this order (``tests/control/test_controllers.py`` checks it); a
controller added to the package is its module, its ``register`` line there and its name here.
"""

from __future__ import annotations

__all__ = ["BUILTIN_CONTROLLERS"]

#: The built-in controllers' names (:attr:`ControllerLaw.name
#: <mrdamper.control.loop.controllers.law.ControllerLaw.name>`), in the registry's order.
BUILTIN_CONTROLLERS: tuple[str, ...] = ("soft", "hard", "skyhook", "groundhook", "hybrid")
