"""The ``mrdamper`` command: builds the Typer app from per-group modules and maps errors to exits.

Each command module exposes ``register(app)``. Exits, for every command:

* usage errors (missing argument, unknown option or command, a value of the wrong type): one
  line on standard error, status 2;
* errors raised on purpose by the library (:class:`~mrdamper.errors.MrDamperError`, missing
  files, permission denied, a symbolic link loop): one line, status 2; other operating-system
  errors while reading or writing (disk full, an input error of the device): one line,
  status 1;
* Ctrl-C: one line ``interrupted``, status 130 (also when a compiled kernel turned the
  interrupt into another exception);
* SIGTERM (``kill``, a batch system ending the job): handled like Ctrl-C (temporary files and
  partial folders removed, worker processes stopped), one line ``terminated``, status 143;
* warnings print as one ``warning: ...`` line, notes (:class:`~mrdamper.errors.Note`) as
  ``note: ...``, on standard error; each text once per command, however often it is raised, and
  of several that differ only in a quoted name and figures (one note per record) the first,
  then at the end one line counting the others.

``--debug`` shows tracebacks instead of the one-line messages.
"""

from __future__ import annotations

import errno
import importlib
import re
import signal
import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import typer

from mrdamper.cli._help import readable_help
from mrdamper.cli._status import SHOWN
from mrdamper.errors import MrDamperError, Note, interrupt_in_chain

__all__ = ["app", "main"]

#: Command modules, each with ``register(app: typer.Typer) -> None``.
COMMAND_MODULES: tuple[str, ...] = (
    "mrdamper.cli.info",
    "mrdamper.cli.models",
    "mrdamper.cli.rig",
    "mrdamper.cli.study",
    "mrdamper.cli.export",
    "mrdamper.cli.control",
    "mrdamper.cli.select",
)

#: Exit status of a usage error (as click's own).
USAGE_EXIT = 2
#: Exit status after Ctrl-C (128 + SIGINT).
INTERRUPT_EXIT = 130
#: Exit status after SIGTERM (128 + SIGTERM).
TERMINATE_EXIT = 143
#: Exit status of a failure while running (an operating-system error such as a full disk).
FAILURE_EXIT = 1
#: Operating-system errors that mean a bad path was given (exit 2), not a failure while running.
_PATH_ERRNOS = frozenset({errno.ELOOP, errno.ENAMETOOLONG, errno.EACCES, errno.EPERM})

_terminated: list[int] = []

app = typer.Typer(
    name="mrdamper",
    help="Identify, compare and export control-oriented models of MR dampers.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        from mrdamper.version import version_text

        typer.echo(version_text())
        raise typer.Exit()


@app.callback()
def _root(
    debug: bool = typer.Option(False, "--debug", help="Show full tracebacks on errors."),
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and commit."
    ),
) -> None:
    """Identify, compare and export control-oriented models of MR dampers."""


def _build() -> None:
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # command group not built yet on this installation
                continue
            raise
        module.register(app)


with warnings.catch_warnings(record=True) as _EARLY:  # a broken plug-in's line, read while the
    warnings.simplefilter("always")  # help texts list the kinds: shown by every command
    _build()


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


@dataclass
class _Held:
    """Notes of one kind (:func:`_template`): the label, the words of the one shown, which of
    its words the others change and the first changed word of each other one."""

    label: str
    words: list[str]
    changed: set[int] = field(default_factory=set)
    names: list[str] = field(default_factory=list)

    def add(self, text: str) -> None:
        words = text.split()
        diff = [k for k, (a, b) in enumerate(zip(self.words, words)) if a != b]
        self.changed.update(diff)
        self.names.append(words[diff[0]].strip("'\",;:()") if diff else "")

    def line(self) -> str:
        """``note: 4 more like 'lpv: record ... leaves ...', with other figures: a, b, ...``."""
        words = ["..." if k in self.changed else w for k, w in enumerate(self.words)]
        head = " ".join(w for k, w in enumerate(words) if w != "..." or words[k - 1] != "...")
        head = head if len(head) <= _HEAD else head[:_HEAD].rsplit(" ", 1)[0] + " ..."
        named = [n for n in self.names if n]
        which = ", ".join(named[:_NAMES_SHOWN]) + (", ..." if len(named) > _NAMES_SHOWN else "")
        return f"{self.label}: {len(self.names)} more like '{head}', with other figures" + (
            f": {which}" if which else ""
        )


#: Notes of one kind (:func:`_template`) -> the one shown and the others held back (a note about
#: each of 30 records prints once, then one line counts and names the others).
_LIKE: dict[str, _Held] = {}
#: Names listed in the line that counts the held-back notes.
_NAMES_SHOWN = 4
#: Characters of the shown text that line repeats (changed words as ``...``).
_HEAD = 90


def _template(text: str) -> str:
    """``text`` with quoted names and figures left out: the notes of one kind about different
    records (``record 'a' ... 1.38 x``, ``record 'b' ... 1.37 x``) share it."""
    return re.sub(r"\d+(?:\.\d+)?", "#", re.sub(r"'[^']*'", "''", text))


def _show_warning(message: Any, category: type[Warning], *_: Any, **__: Any) -> None:
    label = "note" if issubclass(category, Note) else "warning"
    text = _one_line(str(message))
    if text in SHOWN:
        return
    SHOWN.add(text)
    key = f"{label}: {_template(text)}"
    if key in _LIKE:
        _LIKE[key].add(text)
        return
    _LIKE[key] = _Held(label, text.split())
    typer.echo(f"{label}: {text}", err=True)


def _show_held_back() -> None:
    """One line per kind of note held back by :func:`_show_warning`: how many, and which."""
    for held in _LIKE.values():
        if held.names:
            typer.echo(held.line(), err=True)
    _LIKE.clear()


def _usage_error(exc: BaseException) -> str | None:
    """One-line text of a command-line parser error, or None if ``exc`` is not one.

    Recognised by its interface (``format_message`` and ``exit_code``), so it works whichever
    copy of click raised it (Typer bundles its own).
    """
    if not (hasattr(exc, "format_message") and hasattr(exc, "exit_code")):
        return None
    ctx = getattr(exc, "ctx", None)
    where = getattr(ctx, "command_path", "") or "mrdamper"
    return f"error: {where}: {_one_line(exc.format_message())} (see '{where} --help')"


def _help_text(exc: BaseException) -> str | None:
    """Help of the group or command whose arguments were missing (``no_args_is_help``)."""
    if type(exc).__name__ != "NoArgsIsHelpError":
        return None
    ctx = getattr(exc, "ctx", None)
    return ctx.get_help() if ctx is not None else None


def _on_sigterm(signum: int, _frame: Any) -> None:
    """SIGTERM: unwind like Ctrl-C (every ``finally`` and cleanup runs), remembered for the
    exit status."""
    _terminated.append(signum)
    raise KeyboardInterrupt


def _interrupted() -> None:
    """Print the one line of an interruption and exit with its status (130, or 143)."""
    if _terminated:
        typer.echo("terminated", err=True)
        sys.exit(TERMINATE_EXIT)
    typer.echo("interrupted", err=True)
    sys.exit(INTERRUPT_EXIT)


def _handle_sigterm() -> Any:
    """Install :func:`_on_sigterm` (main thread only); return the previous handler."""
    try:
        return signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:  # not the main thread: leave signals alone
        return None


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``mrdamper`` console script."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    saved_show = warnings.showwarning
    SHOWN.clear()
    _LIKE.clear()
    if not debug:
        warnings.showwarning = _show_warning
    for early in _EARLY:
        warnings.showwarning(early.message, early.category, early.filename, early.lineno)
    _terminated.clear()
    saved_term = _handle_sigterm()
    try:
        command = readable_help(typer.main.get_command(app), app.rich_markup_mode)
        rc = command.main(args=args, prog_name="mrdamper", standalone_mode=False)
        if rc == INTERRUPT_EXIT:  # Typer turns KeyboardInterrupt into this exit status
            _interrupted()
        if isinstance(rc, int) and rc:
            sys.exit(rc)
    except SystemExit:
        raise
    except KeyboardInterrupt:
        _interrupted()
    except (MrDamperError, FileNotFoundError, NotADirectoryError, PermissionError) as exc:
        if interrupt_in_chain(exc):
            _interrupted()
        if debug:
            raise
        typer.echo(f"error: {_one_line(str(exc))}", err=True)
        sys.exit(USAGE_EXIT)
    except Exception as exc:
        if interrupt_in_chain(exc):
            _interrupted()
        help_text = _help_text(exc)
        if help_text is not None:
            typer.echo(help_text)
            sys.exit(0)
        usage = _usage_error(exc)
        if usage is not None:
            typer.echo(usage, err=True)
            code = getattr(exc, "exit_code", USAGE_EXIT)
            sys.exit(code if isinstance(code, int) and code else USAGE_EXIT)
        if type(exc).__name__ == "Abort":
            typer.echo("aborted", err=True)
            sys.exit(1)
        if isinstance(exc, OSError) and not debug:
            where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
            typer.echo(f"error: {where}{exc.strerror or _one_line(str(exc))}", err=True)
            sys.exit(USAGE_EXIT if exc.errno in _PATH_ERRNOS else FAILURE_EXIT)
        raise
    finally:
        _show_held_back()
        warnings.showwarning = saved_show
        if saved_term is not None:
            signal.signal(signal.SIGTERM, saved_term)


if __name__ == "__main__":  # pragma: no cover
    main()
