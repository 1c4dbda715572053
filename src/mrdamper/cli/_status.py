"""What a long command shows on standard error while it works.

On a terminal, a live line: the command's message, the stage the library reports through
:mod:`mrdamper.progress` (with ``k/N`` when the stage counts), a spinner, the elapsed time and,
once steps are counted, an estimate of the time left; every finished step
(:func:`mrdamper.progress.finished`) is printed above it, and when the block ends the line is
replaced by one line ``<message>: done in X s``.

Off a terminal (a log, CI, a notebook), the same finished steps and the final line, each as one
plain line (no carriage returns, no bars), printed when it happens.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:  # pragma: no cover
    from rich.console import Console

__all__ = ["SHOWN", "NoProgress", "Status", "finished_lines", "time_left", "working"]

#: The ``--no-progress`` option of the commands that show :func:`working`'s line.
NoProgress = Annotated[
    bool,
    typer.Option(
        "--no-progress",
        help="No live status line (shown on standard error only when that is a terminal).",
    ),
]


class Status:
    """Handle of a :func:`working` block: its ``message`` may change while the block runs.

    Attributes
    ----------
    message : str
        What the command does (shown before the stage, and in the final line).
    """

    def __init__(self, message: str) -> None:
        self.message = message


def _terminal_console() -> Console | None:
    """A rich console on standard error when it is a terminal, else None (nothing is shown)."""
    if not sys.stderr.isatty():
        return None
    from rich.console import Console

    return Console(stderr=True)


def _count(done: int | None, total: int | None) -> str:
    if done is None:
        return ""
    return f"{done}/{total}" if total is not None else str(done)


def time_left(elapsed: float, done: int | None, total: int | None) -> str:
    """Estimate of the time left, ``"about 3 min left"``, from ``done`` of ``total`` steps in
    ``elapsed`` seconds (steps taken as alike); empty before the first step or without a total.

    Parameters
    ----------
    elapsed : float
        Time since the first step started [s].
    done, total : int or None
        Steps over and steps in all.
    """
    if not done or total is None or done >= total:
        return ""
    left = elapsed / done * (total - done)
    if left < 90:
        return f"about {max(left, 1.0):.0f} s left"
    return f"about {left / 60:.0f} min left"


def _plain(message: str, text: str, done: int | None, total: int | None) -> str:
    count = f" ({done} of {total})" if done is not None and total is not None else ""
    return f"{message}: {text}{count}"


@contextlib.contextmanager
def working(message: str, *, show: bool = True) -> Iterator[Status]:
    """Show ``message``, the reported stage and the elapsed time on standard error during the block.

    The stage comes from the reports of :mod:`mrdamper.progress` made in the block, and the
    finished steps (:func:`mrdamper.progress.finished`) are printed above the line. When standard
    error is not a terminal (pipes, files, tests) only the finished steps and, when the block ends
    without an error, ``<message>: done in X s`` are printed, each as one plain line. Nothing is
    printed when ``show`` is false.

    Parameters
    ----------
    message : str
        What the command does; the yielded :class:`Status` may change it.
    show : bool
        False for ``--no-progress``.

    Yields
    ------
    Status
        Set its ``message`` when more is known (e.g. the number of records read).
    """
    import time

    from mrdamper.progress import listening

    status = Status(message)
    t0 = time.perf_counter()
    console = _terminal_console() if show else None
    if console is None:
        if not show:
            yield status
            return

        def print_line(text: str, done: int | None, total: int | None) -> None:
            print(_plain(status.message, text, done, total), file=sys.stderr, flush=True)

        with listening(None, finished=print_line):  # not finished_lines: the message may change
            yield status
        print(f"{status.message}: done in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        return
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
    from rich.table import Column

    bar = Progress(
        SpinnerColumn(),
        # a long stage wraps onto a second line instead of being cut off
        TextColumn("{task.description}", markup=False, table_column=Column(overflow="fold")),
        TextColumn("{task.fields[count]}", markup=False),
        TimeElapsedColumn(),
        TextColumn("{task.fields[left]}", markup=False),
        console=console,
        transient=True,
    )
    task = bar.add_task(message, count="", left="")
    last = [""]

    def show_stage(stage: str, done: int | None, total: int | None) -> None:
        bar.update(task, description=f"{status.message}: {stage}", count=_count(done, total))
        if stage != last[0]:  # a new stage is drawn at once, counts at the refresh rate
            last[0] = stage
            bar.refresh()

    def show_finished(text: str, done: int | None, total: int | None) -> None:
        bar.console.print(_plain(status.message, text, done, total), highlight=False, markup=False)
        bar.update(task, left=time_left(time.perf_counter() - t0, done, total))
        bar.refresh()

    with bar, listening(show_stage, finished=show_finished):
        yield status
    console.print(f"{status.message}: done in {time.perf_counter() - t0:.1f} s")


@contextlib.contextmanager
def finished_lines(message: str, *, show: bool = True) -> Iterator[None]:
    """Off a terminal, print every finished step of the block as one plain line on standard
    error (``<message>: <step> (k of N)``); on a terminal nothing (the command draws its own bars).

    Parameters
    ----------
    message : str
        What the command does.
    show : bool
        False for ``--no-progress``.
    """
    from mrdamper.progress import listening

    if not show or sys.stderr.isatty():
        yield
        return

    def print_line(text: str, done: int | None, total: int | None) -> None:
        print(_plain(message, text, done, total), file=sys.stderr, flush=True)

    with listening(None, finished=print_line):
        yield


#: Text of every warning and note printed by this process: each is printed once, however often
#: it is raised (a record read by several steps gives its reading note once).
SHOWN: set[str] = set()
