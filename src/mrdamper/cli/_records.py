"""Read the records named on a command line: files, and folders of record files.

:func:`reader_options` gives a command every option of the file readers (the ones their error
messages point to): ``--fs``, ``--resample-fs``, ``--nan-policy``, ``--max-gap``, ``--decimal``,
``--sep``, ``--column``, ``--units``, ``--struct``, ``--plausible-max``, ``--derive-velocity``. The
command receives them as one mapping ``read_kw`` to pass to the readers.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError

__all__ = ["READER_OPTIONS", "read_paths", "reader_kwargs", "reader_options"]

_F = TypeVar("_F", bound=Callable[..., Any])

#: Reader options added by :func:`reader_options`: parameter name -> (annotation, default).
READER_OPTIONS: dict[str, tuple[Any, Any]] = {
    "fs": (
        Annotated[
            float | None,
            typer.Option(
                "--fs",
                help="Declared record sampling rate [Hz]: regenerates a rounded time column.",
            ),
        ],
        None,
    ),
    "resample_fs": (
        Annotated[
            float | None,
            typer.Option(
                "--resample-fs",
                help="Interpolate irregular time onto a uniform grid at this rate [Hz].",
            ),
        ],
        None,
    ),
    "nan_policy": (
        Annotated[
            str | None,
            typer.Option(
                "--nan-policy",
                help="raise | drop-edges | interpolate (default: raise; info: interpolate).",
            ),
        ],
        None,
    ),
    "max_gap": (
        Annotated[
            int | None,
            typer.Option("--max-gap", help="Longest NaN gap 'interpolate' fills [samples]."),
        ],
        None,
    ),
    "decimal": (
        Annotated[
            str | None,
            typer.Option("--decimal", help="Decimal mark of text files, e.g. --decimal ,"),
        ],
        None,
    ),
    "sep": (
        Annotated[
            str | None,
            typer.Option("--sep", help="Column delimiter of text files (default: detected)."),
        ],
        None,
    ),
    "column": (
        Annotated[
            list[str] | None,
            typer.Option(
                "--column", help="Map a header to a channel, e.g. --column Force_kN=F (repeatable)."
            ),
        ],
        None,
    ),
    "units": (
        Annotated[
            list[str] | None,
            typer.Option(
                "--units", help="Unit of a channel or header, e.g. --units x=mm --units F=kN."
            ),
        ],
        None,
    ),
    "struct": (
        Annotated[
            str | None,
            typer.Option("--struct", help="MATLAB files: the struct holding the channels."),
        ],
        None,
    ),
    "plausible_max": (
        Annotated[
            list[str] | None,
            typer.Option(
                "--plausible-max",
                help="Override a plausibility bound, e.g. --plausible-max stroke=2 (m).",
            ),
        ],
        None,
    ),
    "derive_velocity": (
        Annotated[
            bool,
            typer.Option(
                "--derive-velocity", help="Compute v from x when the files have no velocity column."
            ),
        ],
        False,
    ),
}


def _pairs(items: list[str] | None, option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise DataValidationError(option, f"expected KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def reader_kwargs(options: Mapping[str, Any], default_nan_policy: str = "raise") -> dict[str, Any]:
    """Reader keyword arguments from the values of :data:`READER_OPTIONS` (unset ones left out)."""
    kw: dict[str, Any] = {}
    for name in ("fs", "resample_fs", "max_gap", "decimal", "sep", "struct"):
        if options.get(name) is not None:
            kw[name] = options[name]
    kw["nan_policy"] = options.get("nan_policy") or default_nan_policy
    if options.get("column"):
        kw["columns"] = _pairs(options["column"], "--column")
    if options.get("units"):
        kw["units"] = _pairs(options["units"], "--units")
    if options.get("plausible_max"):
        kw["plausible_max"] = _pairs(options["plausible_max"], "--plausible-max")
    if options.get("derive_velocity"):
        kw["derive_velocity"] = True
    return kw


def reader_options(default_nan_policy: str = "raise") -> Callable[[_F], _F]:
    """Decorator: add the reader options to a command; it receives them as ``read_kw``.

    The decorated function must take a keyword parameter ``read_kw: dict``.
    """

    def deco(fn: _F) -> _F:
        sig = inspect.signature(fn, eval_str=True)
        params = [p for p in sig.parameters.values() if p.name != "read_kw"]
        taken = {p.name for p in params}
        extra = [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=ann)
            for name, (ann, default) in READER_OPTIONS.items()
            if name not in taken
        ]
        added = [p.name for p in extra]

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            opts = {name: kwargs.pop(name) for name in added if name in kwargs}
            kwargs["read_kw"] = reader_kwargs(opts, default_nan_policy)
            return fn(*args, **kwargs)

        new_params = [
            p.replace(kind=inspect.Parameter.KEYWORD_ONLY) if p.kind == p.VAR_KEYWORD else p
            for p in params
        ]
        wrapper.__signature__ = sig.replace(parameters=[*new_params, *extra])  # type: ignore[attr-defined]
        wrapper.__annotations__ = {p.name: p.annotation for p in [*new_params, *extra]}
        del wrapper.__wrapped__  # type: ignore[attr-defined]  # typer must see the new signature
        return wrapper  # type: ignore[return-value]

    return deco


def read_paths(
    paths: list[Path], pattern: str | None, read_kw: Mapping[str, Any]
) -> list[Experiment]:
    """Read every file and folder of ``paths`` into one list of records, in the order given.

    Folders are resolved by :func:`mrdamper.data.readers.record_files`, the one rule every
    command and the study use (a DoE manifest, else ``pattern``, else the sine-record pattern
    when a file name matches it, else every record file).

    Parameters
    ----------
    paths : list of Path
        Record files and folders.
    pattern : str or None
        File-name regex for folders (named groups become metadata).
    read_kw : mapping
        Options of the file readers (see :func:`mrdamper.data.readers.read_csv`).

    Returns
    -------
    list of Experiment

    Raises
    ------
    FileNotFoundError
        If a path does not exist.
    """
    from mrdamper.data.readers.records import read_files, record_files

    return read_files(record_files(paths, pattern, **read_kw))
