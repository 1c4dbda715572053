"""The electrical input's range: the policy when a record leaves the identified range, and the
note of a model identified at a single level (re-exported by :mod:`mrdamper.models.base`)."""

from __future__ import annotations

from typing import Literal

import numpy as np

from mrdamper._warn import warn_user
from mrdamper.errors import OutOfRangeError

__all__ = ["RangePolicy", "check_input_range", "single_level_note"]

#: What a fitted model does when a record's electrical input leaves its identified range.
RangePolicy = Literal["error", "warn", "clip", "ignore"]


def check_input_range(
    values: np.ndarray,
    bounds: tuple[float, float],
    policy: RangePolicy,
    *,
    field_name: str = "i",
    model: str = "model",
    tolerance: float = 1e-9,
) -> np.ndarray:
    """Apply an out-of-range policy to a scheduling / electrical input signal.

    Parameters
    ----------
    values : ndarray
        The signal (e.g. coil current [A]).
    bounds : (float, float)
        Range the model was identified on.
    policy : {"error", "warn", "clip", "ignore"}
        What to do when values leave ``bounds`` by more than ``tolerance`` times the range width.
    field_name, model : str
        Used in the message.
    tolerance : float
        Relative slack on the bounds, as a fraction of the range width (at least 1) [-].

    Returns
    -------
    ndarray
        ``values`` (clipped under ``"clip"``).
    """
    lo, hi = float(bounds[0]), float(bounds[1])
    slack = tolerance * max(hi - lo, 1.0)
    vmin, vmax = float(np.min(values)), float(np.max(values))
    if vmin >= lo - slack and vmax <= hi + slack:
        return values
    msg = (
        f"{field_name}: {model} was identified on [{lo:g}, {hi:g}] but the record spans "
        f"[{vmin:g}, {vmax:g}]"
    )
    if policy == "error":
        raise OutOfRangeError(msg + "; pass range_policy='clip', 'warn' or 'ignore' to proceed")
    if policy == "warn":
        warn_user(msg + " (extrapolating)", RuntimeWarning)
        return values
    if policy == "clip":
        return np.asarray(np.clip(values, lo, hi))
    if policy == "ignore":
        return values
    raise OutOfRangeError(f"range_policy: expected error/warn/clip/ignore, got {policy!r}")


def single_level_note(kind: str, source: str, level: float) -> str:
    """One-line note for a model identified at a single electrical level.

    The note is also emitted as a warning.

    Parameters
    ----------
    kind : str
        Model kind.
    source : {"i", "voltage"}
        Electrical input channel.
    level : float
        The level [A] or [V].
    """
    unit = "A" if source == "i" else "V"
    return (
        f"{kind}: trained at one {source} level ({level:g} {unit}): its {source}-dependent laws "
        f"are constants and its identified range is [{level:g}, {level:g}] {unit}; other levels "
        "follow range_policy"
    )
