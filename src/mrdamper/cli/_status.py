"""A live status line (spinner and elapsed time) for long commands, shown only on a terminal."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator

__all__ = ["working"]


@contextlib.contextmanager
def working(message: str) -> Iterator[None]:
    """Show ``message`` with a spinner and the elapsed time on standard error while the block runs.

    Nothing is printed when standard error is not a terminal (pipes, files, tests), so output
    that is captured stays the same.
    """
    if not sys.stderr.isatty():
        yield
        return
    import time

    from rich.console import Console

    t0 = time.perf_counter()
    console = Console(stderr=True)
    with console.status(message):
        yield
    console.print(f"{message}: done in {time.perf_counter() - t0:.1f} s")
