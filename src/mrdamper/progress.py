"""Progress of long computations (reading records, fitting), for whoever listens.

Library code reports where it is with :func:`report`: a stage (a short text such as
``"output-error refinement: iteration"``) and, when it counts, how many steps of how many are done.
Nothing is shown by the library itself: a caller that wants to display progress (the command line
does, on a terminal) installs a listener for a block with :func:`listening`. With no listener
installed, :func:`report` costs one :class:`~contextvars.ContextVar` lookup, and reporting never
changes a result.

A step that is over (one model kind of a selection, one stage of a study) is announced with
:func:`finished`: one line of text and, when it counts, how many such steps of how many are over.
The command line prints each as one plain line off a terminal (a log, CI, a notebook) and above
its live line on a terminal, where the counts give the estimate of the time left. A listener for
them is installed with ``listening(callback, finished=...)``; :func:`section` leaves them as they
are (a finished step says in full what it was).

The listeners live in :class:`~contextvars.ContextVar` objects, so they follow the code that
installed them (threads and asynchronous tasks started elsewhere do not report into them; worker
processes never do: the process that collects the workers' results reports for them).

Examples
--------
>>> from mrdamper import progress
>>> events = []
>>> with progress.listening(lambda stage, done, total: events.append((stage, done, total))):
...     for k in range(2):
...         progress.report("step", k + 1, 2)
>>> events
[('step', 1, 2), ('step', 2, 2)]
>>> lines = []
>>> with progress.listening(lambda *_: None, finished=lambda text, d, t: lines.append(text)):
...     progress.finished("kind a: fitted", 1, 2)
>>> lines
['kind a: fitted']
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from typing import Any, TypeVar

__all__ = ["Listener", "counted", "finished", "listening", "report", "section"]

#: A listener: called with the stage, the steps done (or None) and the steps in all (or None).
Listener = Callable[[str, int | None, int | None], None]

_F = TypeVar("_F", bound=Callable[..., Any])

_LISTENER: ContextVar[Listener | None] = ContextVar("mrdamper_progress_listener", default=None)
_FINISHED: ContextVar[Listener | None] = ContextVar("mrdamper_progress_finished", default=None)


def report(stage: str, done: int | None = None, total: int | None = None) -> None:
    """Tell the current listener, if any, that the computation is at ``stage``.

    Parameters
    ----------
    stage : str
        What is being done, e.g. ``"reading records"``.
    done : int, optional
        Steps of the stage completed so far (never above ``total``).
    total : int, optional
        Steps of the stage in all, or at most, when known.
    """
    listener = _LISTENER.get()
    if listener is not None:
        listener(stage, done, total)


def finished(text: str, done: int | None = None, total: int | None = None) -> None:
    """Tell the current listener for finished steps, if any, that a step is over.

    Parameters
    ----------
    text : str
        What was done and its outcome, in one line, e.g. ``"sp1: 9 fits, mean ESR 0.0123"``.
    done : int, optional
        Such steps over so far, this one included (never above ``total``).
    total : int, optional
        Such steps in all, when known.
    """
    listener = _FINISHED.get()
    if listener is not None:
        listener(text, done, total)


@contextlib.contextmanager
def listening(callback: Listener | None, *, finished: Listener | None = None) -> Iterator[None]:
    """Send the reports of the block to ``callback`` (the listeners before it are restored after).

    Parameters
    ----------
    callback : callable or None
        Called as ``callback(stage, done, total)`` for every :func:`report` of the block. It
        should be quick; an exception it raises propagates into the reporting code. None: the
        listener outside the block, if any, stays in place.
    finished : callable, optional
        Called as ``finished(text, done, total)`` for every :func:`finished` of the block (None:
        the listener for finished steps outside the block, if any, stays in place).
    """
    token = _LISTENER.set(callback) if callback is not None else None
    done_token = _FINISHED.set(finished) if finished is not None else None
    try:
        yield
    finally:
        if token is not None:
            _LISTENER.reset(token)
        if done_token is not None:
            _FINISHED.reset(done_token)


@contextlib.contextmanager
def section(label: str) -> Iterator[None]:
    """Prefix the stages reported in the block with ``label`` (e.g. one candidate of a search).

    Sections nest: a stage ``s`` reported inside ``section("a")`` and ``section("b")`` reaches
    the listener as ``"a: b: s"``. Without a listener this does nothing.

    Parameters
    ----------
    label : str
        Text put before every stage of the block.
    """
    outer = _LISTENER.get()
    if outer is None:
        yield
        return

    def prefixed(stage: str, done: int | None, total: int | None) -> None:
        outer(f"{label}: {stage}", done, total)

    token = _LISTENER.set(prefixed)
    try:
        yield
    finally:
        _LISTENER.reset(token)


def counted(fun: _F, stage: str, total: int | None = None) -> _F:
    """``fun`` wrapped so that each call reports ``stage`` with the number of calls so far.

    For counting the residual evaluations of an optimiser: pass the wrapper instead of ``fun``.
    The wrapper returns exactly what ``fun`` returns. Without a listener when this is called,
    ``fun`` itself is returned (nothing is counted).

    Parameters
    ----------
    fun : callable
        The function to count.
    stage : str
        Stage reported at each call.
    total : int, optional
        Most calls expected (e.g. an optimiser's evaluation budget), when known.

    Returns
    -------
    callable
        The wrapper, or ``fun``.
    """
    listener = _LISTENER.get()
    if listener is None:
        return fun
    calls = 0

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        nonlocal calls
        calls += 1
        listener(stage, calls, total)
        return fun(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
