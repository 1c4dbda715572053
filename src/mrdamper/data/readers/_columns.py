"""Map source column names to standard channels and find each column's unit.

A source column reaches a standard channel (``t, x, v, F, i, voltage``) either through the
user's ``columns={"source name": "channel"}`` mapping or through :data:`COLUMN_ALIASES`. A column
header may carry its unit in brackets or parentheses (``"x [mm]"``, ``"F (kN)"``); a unit declared
with ``units=`` must agree with it. Columns without any unit are taken as SI.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mrdamper.data.units import CHANNEL_QUANTITY, SI_UNIT, canonical_unit, si_factor
from mrdamper.errors import DataValidationError, UnitError

__all__ = ["COLUMN_ALIASES", "ColumnSpec", "resolve_columns", "split_header"]

#: Standard channel -> accepted header names (the bracketed unit, if any, is removed first).
#: One-letter names match with their exact case (``v`` is velocity, ``V`` is voltage;
#: ``i`` and ``I`` are current); longer names match in any case (``Time``, ``FORCE``).
COLUMN_ALIASES: dict[str, tuple[str, ...]] = {
    "t": ("t", "time", "t_s", "time_s"),
    "x": ("x", "disp", "displacement", "position", "pos"),
    "v": ("v", "vel", "velocity"),
    "F": ("F", "force", "load"),
    "i": ("i", "I", "current", "curr"),
    "voltage": ("V", "voltage", "volt", "volts"),
}

_UNIT_IN_HEADER = re.compile(r"^\s*(?P<base>.*?)\s*[\[(]\s*(?P<unit>[^\])]*?)\s*[\])]\s*$")


@dataclass(frozen=True)
class ColumnSpec:
    """Where a standard channel comes from.

    Attributes
    ----------
    channel : str
        Standard channel name.
    source : str
        Column (or variable) name in the source file.
    unit : str
        Unit of the source values (table spelling).
    """

    channel: str
    source: str
    unit: str

    @property
    def factor(self) -> float:
        """Factor to SI: ``value_SI = value * factor``."""
        return si_factor(self.channel, self.unit, column=self.source)


def split_header(header: str) -> tuple[str, str | None]:
    """Split ``"x [mm]"`` into ``("x", "mm")``; a header without brackets has no unit."""
    m = _UNIT_IN_HEADER.match(header)
    if m and m.group("base"):
        return m.group("base"), m.group("unit")
    return header.strip(), None


def _alias_matches(base: str, channel: str) -> bool:
    for alias in COLUMN_ALIASES[channel]:
        if len(alias) == 1:
            if base == alias:
                return True
        elif base.lower() == alias.lower():
            return True
    return False


def resolve_columns(
    headers: Sequence[str],
    *,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    source: str = "file",
) -> dict[str, ColumnSpec]:
    """Decide which source column feeds each standard channel, and in which unit.

    Parameters
    ----------
    headers : sequence of str
        Column (or variable) names found in the source.
    columns : mapping, optional
        ``{source name: channel}``; overrides the alias table for those channels.
    units : mapping, optional
        ``{channel or source name: unit}``. Channels without a declared unit use the unit in
        their header, or SI.
    source : str
        Source description used in messages (file path).

    Returns
    -------
    dict
        ``channel -> ColumnSpec`` for every channel found (required channels are checked by
        the caller, which knows what can be derived).

    Raises
    ------
    DataValidationError
        A duplicated header, a mapping to an unknown channel or from a missing column, two
        columns for one channel.
    UnitError
        An unknown unit, a unit of the wrong quantity, a unit given for a column that is not
        read, or a declared unit contradicting the header.
    """
    headers = [str(h) for h in headers]
    seen: set[str] = set()
    for h in headers:
        if h in seen:
            raise DataValidationError(h, f"column name appears more than once in {source}")
        seen.add(h)

    chosen: dict[str, str] = {}
    for src, ch in (columns or {}).items():
        if ch not in CHANNEL_QUANTITY:
            raise DataValidationError(
                "columns", f"{src!r} is mapped to {ch!r}; expected one of {list(CHANNEL_QUANTITY)}"
            )
        if src not in headers:
            raise DataValidationError(
                "columns",
                f"column {src!r} (mapped to {ch!r}) not found in {source}; found {headers}",
            )
        if ch in chosen:
            raise DataValidationError(
                "columns", f"both {chosen[ch]!r} and {src!r} are mapped to {ch!r}; map only one"
            )
        chosen[ch] = src

    taken = set(chosen.values())
    for ch in CHANNEL_QUANTITY:
        if ch in chosen:
            continue
        hits = [h for h in headers if h not in taken and _alias_matches(split_header(h)[0], ch)]
        if len(hits) > 1:
            raise DataValidationError(
                ch,
                f"columns {hits} in {source} all look like {ch!r}; choose one with "
                f"columns={{{hits[0]!r}: {ch!r}}}",
            )
        if hits:
            chosen[ch] = hits[0]
            taken.add(hits[0])

    declared = _declared_units(units or {}, chosen, headers, source)
    specs: dict[str, ColumnSpec] = {}
    for ch, src in chosen.items():
        header_unit = split_header(src)[1]
        unit = declared.get(ch)
        if header_unit is not None:
            hu = canonical_unit(header_unit, column=src)
            if unit is not None and unit != hu:
                raise UnitError(
                    src, f"header says {header_unit!r} but units= declares {unit!r} for {ch!r}"
                )
            unit = hu
        unit = unit or SI_UNIT[CHANNEL_QUANTITY[ch]]
        spec = ColumnSpec(ch, src, unit)
        spec.factor  # noqa: B018  (checks that the unit fits the channel's quantity)
        specs[ch] = spec
    return specs


def _declared_units(
    units: Mapping[str, Any], chosen: Mapping[str, str], headers: Sequence[str], source: str
) -> dict[str, str]:
    by_source = {src: ch for ch, src in chosen.items()}
    out: dict[str, str] = {}
    for key, unit in units.items():
        if key in chosen:
            ch = key
        elif key in by_source:
            ch = by_source[key]
        elif key in headers:
            raise UnitError(
                key, f"a unit is declared for column {key!r}, which is not read as a channel"
            )
        else:
            raise UnitError(
                key,
                f"a unit is declared for {key!r}, but {source} has no such channel or column "
                f"(channels found: {sorted(chosen)})",
            )
        u = canonical_unit(unit, column=key)
        if ch in out and out[ch] != u:
            raise UnitError(key, f"two different units declared for {ch!r}: {out[ch]!r} and {u!r}")
        out[ch] = u
    return out
