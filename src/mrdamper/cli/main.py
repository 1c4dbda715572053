"""The ``mrdamper`` command: builds the Typer app from per-group modules and maps errors to exits.

Each command module exposes ``register(app)``. Errors raised on purpose by the library
(:class:`~mrdamper.errors.MrDamperError`, missing files) print one line to standard error and exit
with status 2; ``--debug`` shows the traceback instead.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

import typer

from mrdamper.errors import MrDamperError

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

app = typer.Typer(
    name="mrdamper",
    help="Identify, compare and export control-oriented models of MR dampers.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _root(
    debug: bool = typer.Option(False, "--debug", help="Show full tracebacks on errors."),
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


_build()


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``mrdamper`` console script."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    try:
        rc = app(args=args, prog_name="mrdamper", standalone_mode=False)
        if isinstance(rc, int) and rc:
            sys.exit(rc)
    except (MrDamperError, FileNotFoundError, NotADirectoryError, PermissionError) as exc:
        if debug:
            raise
        typer.echo(f"error: {exc}", err=True)
        sys.exit(2)
    except KeyboardInterrupt:
        typer.echo("interrupted", err=True)
        sys.exit(130)
    except SystemExit:
        raise
    except Exception as exc:  # click usage errors and friends
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show()
            sys.exit(exc.exit_code)
        if isinstance(exc, click.exceptions.Abort):
            typer.echo("aborted", err=True)
            sys.exit(1)
        raise


if __name__ == "__main__":  # pragma: no cover
    main()
