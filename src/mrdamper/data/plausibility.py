"""Plausibility bounds of damper records: values a real MR damper test cannot produce.

A record whose values exceed these bounds was almost always read in the wrong units (millimetres
declared as metres: a 4.6 m stroke at 88 m/s; a current in mA read as A: 1000 A). Readers check
every record and warn, one line per channel, naming the channel, the value and the bound; the
record is still returned (nothing is changed). A value beyond a bound by more than
:data:`ABSURD_FACTOR` is no unit mistake but a corrupt sample (``x = 1e300`` m): the record is
refused in one line naming the channel and the sample. Override a bound with ``plausible_max=``
of any reader (command line: ``--plausible-max KEY=VALUE``), e.g. for a large seismic damper.

=========  ==========================================  ========
key        quantity                                    default
=========  ==========================================  ========
stroke     peak-to-peak displacement ``max x - min x``  1 m
v          largest ``|v|``                              10 m/s
F          largest ``|F|``                              2 MN
i          largest ``|i|``                              20 A
voltage    largest ``|voltage|``                        100 V
=========  ==========================================  ========
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.errors import DataValidationError, PlausibilityWarning

__all__ = ["ABSURD_FACTOR", "PLAUSIBLE_MAX", "check_plausibility", "plausibility_bounds"]

#: Default plausibility bounds, SI units: stroke [m], v [m/s], F [N], i [A], voltage [V].
PLAUSIBLE_MAX: Mapping[str, float] = MappingProxyType(
    {"stroke": 1.0, "v": 10.0, "F": 2.0e6, "i": 20.0, "voltage": 100.0}
)
#: Factor beyond a bound from which a value cannot be a unit mistake (nanometres read as metres
#: are 1e9): the record is refused, not warned about.
ABSURD_FACTOR = 1e12
_UNITS = {"stroke": "m", "v": "m/s", "F": "N", "i": "A", "voltage": "V"}


def plausibility_bounds(overrides: Mapping[str, Any] | None = None) -> dict[str, float]:
    """The bounds in force: :data:`PLAUSIBLE_MAX` with ``overrides`` applied (checked)."""
    out = dict(PLAUSIBLE_MAX)
    for key, value in (overrides or {}).items():
        if key not in out:
            raise DataValidationError(
                "plausible_max", f"unknown key {key!r}; expected some of {sorted(out)}"
            )
        try:
            val = float(value)
        except (TypeError, ValueError):
            raise DataValidationError(
                "plausible_max", f"{key}: expected a positive number, got {value!r}"
            ) from None
        if not (np.isfinite(val) and val > 0):
            raise DataValidationError(
                "plausible_max", f"{key}: expected a positive number, got {value!r}"
            )
        out[key] = val
    return out


def check_plausibility(
    channels: Mapping[str, np.ndarray | None],
    source: str,
    overrides: Mapping[str, Any] | None = None,
) -> list[str]:
    """Warn (:class:`~mrdamper.errors.PlausibilityWarning`) for every bound a record exceeds.

    Parameters
    ----------
    channels : mapping
        SI channels ``x, v, F, i, voltage`` (missing or None ones are skipped).
    source : str
        Record or file name used in the messages.
    overrides : mapping, optional
        Bounds replacing :data:`PLAUSIBLE_MAX` entries.

    Returns
    -------
    list of str
        The messages (also issued as warnings).
    """
    bounds = plausibility_bounds(overrides)
    values: dict[str, float] = {}
    x = channels.get("x")
    if x is not None and np.size(x):
        values["stroke"] = float(np.nanmax(x)) - float(np.nanmin(x))  # Python floats: no overflow
    for ch in ("v", "F", "i", "voltage"):
        a = channels.get(ch)
        if a is not None and np.size(a):
            values[ch] = max(abs(float(np.nanmax(a))), abs(float(np.nanmin(a))))  # no |a| copy
    for key, val in values.items():
        if val > bounds[key] * ABSURD_FACTOR:
            ch = "x" if key == "stroke" else key
            a = np.asarray(channels[ch], dtype=np.float64)
            k = int(np.nanargmax(np.abs(a)))
            raise DataValidationError(
                ch,
                f"sample {k} of {source} is {float(a[k]):.3g} {_UNITS[key]}, beyond any damper "
                f"(more than {ABSURD_FACTOR:g} times the plausible {bounds[key]:g} {_UNITS[key]}: "
                "not a unit mistake but a corrupt value); fix or remove that sample",
            )
    msgs = []
    for key, val in values.items():
        if val > bounds[key]:
            what = "x: stroke (peak-to-peak)" if key == "stroke" else f"{key}: largest magnitude"
            msgs.append(
                f"{what} {val:.4g} {_UNITS[key]} in {source} exceeds the plausible "
                f"{bounds[key]:g} {_UNITS[key]}; check the declared units "
                f"(override with plausible_max={{'{key}': ...}}, command line "
                f"--plausible-max {key}=...)"
            )
    for m in msgs:
        warn_user(m, PlausibilityWarning)
    return msgs
