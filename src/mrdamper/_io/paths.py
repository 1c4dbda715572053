"""Paths as the output checks compare them: absolute, resolved, a link loop a one-line error."""

from __future__ import annotations

import os
from pathlib import Path

from mrdamper.errors import OutputError

__all__ = ["resolved"]


def resolved(p: str | os.PathLike[str], option: str = "path") -> Path:
    """Absolute, resolved form of ``p`` (``~`` expanded); one-line error for a link loop.

    Raises
    ------
    OutputError
        ``p`` is, or goes through, a symbolic link loop.
    """
    try:
        return Path(os.path.abspath(Path(p).expanduser())).resolve(strict=False)
    except (RuntimeError, OSError):  # Python < 3.13: RuntimeError("Symlink loop from ...")
        raise OutputError(
            f"{option}: {p} is a symbolic link loop (or goes through one); choose another path"
        ) from None
