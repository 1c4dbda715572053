"""Warnings and notes attributed to the user's code.

Python prints a warning with the source line of the frame it is attributed to; a warning raised
deep inside mrdamper with a fixed ``stacklevel`` shows a line of mrdamper's own source (``result =
self._identify(...)``), which tells the user nothing. :func:`warn_user` attributes it to the first
frame outside the package: the user's call.
"""

from __future__ import annotations

import sys
import warnings

__all__ = ["warn_user"]


def warn_user(message: str, category: type[Warning] = UserWarning) -> None:
    """Issue ``message`` as a warning of ``category`` from the first caller outside mrdamper.

    Parameters
    ----------
    message : str
        One-line text.
    category : type of Warning
        E.g. :class:`RuntimeWarning` or :class:`~mrdamper.errors.Note`.
    """
    level = 1
    frame = sys._getframe(0)
    while (
        frame is not None and str(frame.f_globals.get("__name__", "")).split(".")[0] == "mrdamper"
    ):
        frame = frame.f_back  # type: ignore[assignment]
        level += 1
    warnings.warn(message, category, stacklevel=level)


def _ours(module: object) -> bool:
    return str(module or "").split(".")[0] == "mrdamper"
