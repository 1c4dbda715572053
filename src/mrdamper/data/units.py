"""The unit table and conversions to and from SI: the only place where units are converted.

Every channel of an :class:`~mrdamper.data.Experiment` has one physical quantity and is stored in
its SI unit (see :data:`CHANNEL_QUANTITY`). Readers convert each column once, from the unit the
user declares, with :func:`to_si`; writers convert back with :func:`from_si`. A unit string that is
not in :data:`UNITS`, or that belongs to another quantity than the channel's, raises
:class:`~mrdamper.errors.UnitError` naming the column.

Examples
--------
>>> import numpy as np
>>> to_si(np.array([1.0, 2.5]), "mm", channel="x")
array([0.001 , 0.0025])
>>> si_factor("F", "kN")
1000.0
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from mrdamper.errors import UnitError

__all__ = [
    "CHANNEL_QUANTITY",
    "SI_UNIT",
    "UNITS",
    "UNIT_ALIASES",
    "canonical_unit",
    "from_si",
    "parse_unit_assignments",
    "si_factor",
    "to_si",
]

#: Physical quantity of each standard channel.
CHANNEL_QUANTITY: dict[str, str] = {
    "t": "time",
    "x": "length",
    "v": "velocity",
    "F": "force",
    "i": "current",
    "voltage": "voltage",
}

#: SI unit of each quantity (the unit channels are stored in).
SI_UNIT: dict[str, str] = {
    "time": "s",
    "length": "m",
    "velocity": "m/s",
    "force": "N",
    "current": "A",
    "voltage": "V",
}

_INCH = 0.0254  # [m], exact by definition
_POUND_FORCE = 4.4482216152605  # [N], exact: 0.45359237 kg * 9.80665 m/s^2

#: The unit table: quantity -> {unit: factor}, where ``value_SI = value * factor``.
UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": _INCH},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "in/s": _INCH},
    "force": {"N": 1.0, "kN": 1e3, "lbf": _POUND_FORCE},
    "current": {"A": 1.0, "mA": 1e-3},
    "voltage": {"V": 1.0},
}

#: Accepted spellings of units in the table (e.g. the paper's ``in/sec`` and ``lb_F``).
UNIT_ALIASES: dict[str, str] = {
    "sec": "s",
    "inch": "in",
    "in/sec": "in/s",
    "ips": "in/s",
    "lb_F": "lbf",
    "lbF": "lbf",
}


def canonical_unit(unit: Any, *, column: str = "unit") -> str:
    """Return the table spelling of ``unit`` (surrounding blanks removed, aliases resolved).

    Unit strings are case sensitive (``mA`` is not ``MA``).

    Parameters
    ----------
    unit : str
        Unit as written by the user or in a file header.
    column : str
        Column name used in error messages.

    Raises
    ------
    UnitError
        If ``unit`` is not a string or is not in :data:`UNITS` or :data:`UNIT_ALIASES`.
    """
    if not isinstance(unit, str):
        raise UnitError(column, f"unit must be a string, got {unit!r}")
    u = unit.strip()
    u = UNIT_ALIASES.get(u, u)
    for table in UNITS.values():
        if u in table:
            return u
    known = ", ".join(u for table in UNITS.values() for u in table)
    raise UnitError(column, f"unknown unit {unit!r}; expected one of: {known}")


def si_factor(channel: str, unit: Any, *, column: str | None = None) -> float:
    """Return the factor that converts ``unit`` to the SI unit of ``channel``.

    Parameters
    ----------
    channel : str
        Standard channel name (``"t"``, ``"x"``, ``"v"``, ``"F"``, ``"i"``, ``"voltage"``).
    unit : str
        Unit of the values, e.g. ``"mm"``.
    column : str, optional
        Name of the source column, used in error messages (defaults to ``channel``).

    Returns
    -------
    float
        ``value_SI = value * factor``.

    Raises
    ------
    UnitError
        If the unit is unknown or measures another quantity than the channel.
    """
    col = column or channel
    if channel not in CHANNEL_QUANTITY:
        raise UnitError(
            col, f"unknown channel {channel!r}; expected one of {list(CHANNEL_QUANTITY)}"
        )
    quantity = CHANNEL_QUANTITY[channel]
    u = canonical_unit(unit, column=col)
    table = UNITS[quantity]
    if u not in table:
        other = next(q for q, tab in UNITS.items() if u in tab)
        raise UnitError(
            col,
            f"unit {unit!r} measures {other}, but channel {channel!r} is a {quantity}; "
            f"expected one of {list(table)}",
        )
    return table[u]


def to_si(values: Any, unit: Any, *, channel: str, column: str | None = None) -> np.ndarray:
    """Convert ``values`` given in ``unit`` to the SI unit of ``channel``.

    Parameters
    ----------
    values : array_like
        Values in ``unit``.
    unit : str
        Their unit.
    channel : str
        Standard channel the values belong to (fixes the quantity).
    column : str, optional
        Source column name for error messages.

    Returns
    -------
    ndarray
        float64 values in SI units (a new array; SI input is copied unchanged).
    """
    f = si_factor(channel, unit, column=column)
    arr = np.array(values, dtype=np.float64, copy=True)
    if f != 1.0:
        arr *= f
    return arr


def from_si(values: Any, unit: Any, *, channel: str, column: str | None = None) -> np.ndarray:
    """Convert SI ``values`` of ``channel`` to ``unit`` (inverse of :func:`to_si`).

    Parameters
    ----------
    values : array_like
        Values in the SI unit of ``channel``.
    unit : str
        Target unit.
    channel : str
        Standard channel the values belong to.
    column : str, optional
        Column name for error messages.

    Returns
    -------
    ndarray
        float64 values in ``unit`` (a new array).
    """
    f = si_factor(channel, unit, column=column)
    arr = np.array(values, dtype=np.float64, copy=True)
    if f != 1.0:
        arr /= f
    return arr


def parse_unit_assignments(items: Any) -> dict[str, str]:
    """Parse ``["x=mm", "F=kN"]`` (or a mapping) into ``{"x": "mm", "F": "kN"}``.

    Units are checked against the table; keys are not (they may be channel or source column
    names; the reader checks them).

    Parameters
    ----------
    items : iterable of str, mapping or None
        ``"column=unit"`` strings (as given on the command line) or a mapping.

    Raises
    ------
    UnitError
        If an item has no ``=``, an empty side, or an unknown unit.
    """
    if items is None:
        return {}
    if isinstance(items, Mapping):
        pairs = list(items.items())
    else:
        pairs = []
        for item in items:
            if not isinstance(item, str) or "=" not in item:
                raise UnitError("units", f"expected 'column=unit' (e.g. 'x=mm'), got {item!r}")
            key, _, unit = item.partition("=")
            pairs.append((key.strip(), unit.strip()))
    out: dict[str, str] = {}
    for key, unit in pairs:
        if not isinstance(key, str) or not key:
            raise UnitError("units", f"expected a column name before '=', got {key!r}")
        out[key] = canonical_unit(unit, column=key)
    return out
