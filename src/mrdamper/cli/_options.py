"""Command-line options that several commands declare the same way (one definition each)."""

from __future__ import annotations

from typing import Annotated

import typer

__all__ = ["ForceOut", "InputChannel", "Pattern"]

#: ``--pattern``: the file-name regex that selects records in the folders given.
Pattern = Annotated[str | None, typer.Option("--pattern", help="File-name regex for folders.")]

#: ``--input``: the electrical input channel a model reads.
InputChannel = Annotated[
    str | None,
    typer.Option(
        "--input", help="Electrical input: i | voltage (default: the channel every record has)."
    ),
]

#: ``--force``: replace the ``--out`` file.
ForceOut = Annotated[bool, typer.Option("--force", help="Overwrite --out if it exists.")]
