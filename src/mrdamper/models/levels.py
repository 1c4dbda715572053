"""Whether an electrical input takes one level (shared by the fit template and the lag choice),
and whether it switches within a record."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mrdamper.errors import DataValidationError

__all__ = ["check_levels", "held_within_records", "single_level"]


def single_level(values: np.ndarray, rel_tol: float = 1e-9) -> float | None:
    """The one level of a constant electrical input, or None when it takes more than one value.

    ``values`` is constant when its spread is at most ``rel_tol * max(1, max |values|)``.

    Parameters
    ----------
    values : ndarray
        Electrical input [A] or [V] (or its extremes).
    rel_tol : float
        Relative spread below which the input is one level [-].
    """
    lo, hi = float(np.min(values)), float(np.max(values))
    if hi - lo <= rel_tol * max(1.0, abs(lo), abs(hi)):
        return 0.5 * (lo + hi)
    return None


def check_levels(model: Any, consequence: str, field: str = "model") -> None:
    """Refuse, in one line, a model identified at one electrical level for a use that needs its
    force to depend on the input (a controller, an inverse, a loop that switches the input).

    Parameters
    ----------
    model : FittedModel
        The model (one without an ``input_range`` passes).
    consequence : str
        What goes wrong, ending the message (``"every controller gives the same numbers"``).
    field : str
        Name of the model in the message (``"model"``, ``"plant"``, ``"--loop-model"``).

    Raises
    ------
    DataValidationError
        The model's identified input range is one level.
    """
    bounds = getattr(model, "input_range", None)
    level = None if bounds is None else single_level(np.asarray(bounds, dtype=float))
    if level is None:
        return
    source = getattr(model, "input", "i")
    unit = "A" if source == "i" else "V"
    raise DataValidationError(
        field,
        f"the {getattr(model, 'kind', 'damper')} model was identified at one {source} level "
        f"({level:g} {unit}): its force does not depend on {source}, so {consequence}; identify "
        "it on records at two or more levels",
    )


def held_within_records(extremes: Sequence[tuple[float, float]], fraction: float) -> bool:
    """True when the electrical input does not switch within any record: each record's span is
    at most ``fraction`` of the training input range (of its largest magnitude, for one level),
    so sensor noise on a held current or voltage does not count as a switch.

    Parameters
    ----------
    extremes : sequence of (float, float)
        ``(min, max)`` of each record's electrical input [A] or [V].
    fraction : float
        Largest span of a held input, as a fraction of the training range [-].
    """
    lo = min(e[0] for e in extremes)
    hi = max(e[1] for e in extremes)
    scale = (hi - lo) if hi - lo > 1e-12 * max(1.0, abs(hi)) else max(abs(lo), abs(hi), 1e-300)
    return all(e[1] - e[0] <= fraction * scale for e in extremes)
