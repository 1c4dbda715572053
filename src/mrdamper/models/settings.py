"""Settings checks shared by every estimator: one message style, one place.

:meth:`mrdamper.models.Estimator._validate` checks every ``Literal`` field of an estimator against
its choices and every ``bool`` field with these functions; families add their number checks with
:func:`check_int` and :func:`check_number`. Each raises
:class:`~mrdamper.errors.DataValidationError` naming the setting, what was expected and the value.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Hashable, Sequence
from typing import Any, Literal

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = [
    "check_bool",
    "check_choice",
    "check_int",
    "check_number",
    "literal_choices",
    "type_hints",
]


def check_choice(
    name: str, value: Any, choices: Sequence[Any], *, allow_none: bool = False
) -> None:
    """Refuse ``value`` unless it is one of ``choices`` (or None with ``allow_none``).

    Parameters
    ----------
    name : str
        Setting name (in the message).
    value : object
        The value given.
    choices : sequence
        Accepted values.
    allow_none : bool
        Also accept None.

    Raises
    ------
    DataValidationError
        Naming the setting, the accepted values and the value given.
    """
    if value is None and allow_none:
        return
    if isinstance(value, Hashable) and value in choices and not isinstance(value, bool):
        return
    expected = ", ".join(repr(c) for c in choices) + (" or None" if allow_none else "")
    raise DataValidationError(name, f"expected one of {expected}, got {value!r}")


def check_bool(name: str, value: Any) -> None:
    """Refuse anything but True / False.

    Parameters
    ----------
    name : str
        Setting name (in the message).
    value : object
        The value given.
    """
    if not isinstance(value, (bool, np.bool_)):
        raise DataValidationError(name, f"expected True or False, got {value!r}")


def check_int(
    name: str,
    value: Any,
    low: int | None = 0,
    high: int | None = None,
    *,
    allow_none: bool = False,
) -> None:
    """Refuse anything but an integer in ``[low, high]``.

    Parameters
    ----------
    name : str
        Setting name (in the message).
    value : object
        The value given.
    low, high : int or None
        Inclusive bounds; None: unbounded on that side.
    allow_none : bool
        Also accept None.
    """
    if value is None and allow_none:
        return
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if ok and (low is None or value >= low) and (high is None or value <= high):
        return
    if low is None:
        rng = "" if high is None else f" <= {high}"
    else:
        rng = f" >= {low}" if high is None else f" in {low}..{high}"
    raise DataValidationError(name, f"expected an integer{rng}, got {value!r}")


def check_number(
    name: str,
    value: Any,
    *,
    low: float = 0.0,
    high: float = math.inf,
    strict: bool = True,
    allow_none: bool = False,
    what: str = "a positive finite number",
) -> None:
    """Refuse anything but a finite real number above ``low`` and below ``high``.

    Parameters
    ----------
    name : str
        Setting name (in the message).
    value : object
        The value given.
    low, high : float
        Bounds: ``value > low`` (``>=`` unless ``strict``) and ``value < high``.
    strict : bool
        Exclude ``low`` itself.
    allow_none : bool
        Also accept None.
    what : str
        What was expected, in words (in the message).
    """
    if value is None and allow_none:
        return
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if ok:
        v = float(value)
        above = v > low if strict else v >= low
        if math.isfinite(v) and above and v < high:
            return
    raise DataValidationError(name, f"expected {what}, got {value!r}")


def type_hints(cls: type) -> dict[str, Any]:
    """Resolved annotations of ``cls`` (empty when one does not resolve: no literal checks).

    Parameters
    ----------
    cls : type
        An estimator class.
    """
    try:
        return typing.get_type_hints(cls)
    except (NameError, TypeError):  # an annotation that does not resolve: no literal checks
        return {}


def literal_choices(hint: Any) -> tuple[tuple[Any, ...], bool] | None:
    """``(choices, allows None)`` of a ``Literal[...]`` or ``Literal[...] | None`` hint.

    Parameters
    ----------
    hint : object
        A resolved type annotation.
    """
    if typing.get_origin(hint) is Literal:
        return typing.get_args(hint), False
    args = typing.get_args(hint)
    if args and type(None) in args:
        rest = [a for a in args if a is not type(None)]
        if len(rest) == 1 and typing.get_origin(rest[0]) is Literal:
            return typing.get_args(rest[0]), True
    return None
