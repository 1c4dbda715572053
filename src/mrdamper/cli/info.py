"""``mrdamper info``: what is in a data file or folder, and what looks wrong with it.

For each record it shows samples, rate, duration, ranges of x, v and F, the current (or voltage)
levels and detected problems: repaired NaN samples, regenerated time, force plateaus at the
extremes (clipping or saturation), nearly constant force, current outside 0..4 A.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from mrdamper.cli._modes import refuse_unused
from mrdamper.cli._records import read_paths, reader_options
from mrdamper.data.experiment import Experiment
from mrdamper.data.inspection import record_summary
from mrdamper.errors import DataValidationError, MrDamperError

if TYPE_CHECKING:
    from rich.console import JustifyMethod

__all__ = ["register"]


def _example() -> list[Experiment]:
    try:
        from mrdamper.rig.doe import table_ii
    except ImportError as exc:
        raise MrDamperError(
            f"example: the built-in example needs mrdamper.rig.doe ({exc})"
        ) from None
    return list(table_ii(seed=0, scale=0.1))


def _fmt_range(r: list[float], digits: int = 4) -> str:
    return f"{r[0]:.{digits}g} .. {r[1]:.{digits}g}"


def _unless_shown(problem: str) -> str:
    """``problem``, or a pointer to the note above when its text was printed as one already."""
    from mrdamper.cli._status import SHOWN

    what, _, text = problem.partition(": ")
    return f"{what}: see the note above" if text and " ".join(text.split()) in SHOWN else problem


def _print_table(rows: list[dict[str, Any]], title: str) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(title), show_lines=False)
    columns: tuple[tuple[str, JustifyMethod], ...] = (
        ("name", "left"),
        ("samples", "right"),
        ("rate [Hz]", "right"),
        ("duration [s]", "right"),
        ("x [mm]", "right"),
        ("v [m/s]", "right"),
        ("F [N]", "right"),
        ("input levels", "left"),
        ("problems", "left"),
    )
    for col, justify in columns:
        table.add_column(escape(col), justify=justify, overflow="fold")
    for r in rows:
        unit = "A" if r["input"] == "i" else "V"
        if r["levels"] is not None:
            levels = f"{r['input']}: " + ", ".join(f"{v:g}" for v in r["levels"]) + f" {unit}"
        else:
            levels = f"{r['input']}: {_fmt_range(r['input_range'])} {unit} (varying)"
        cells = (
            r["name"],
            str(r["samples"]),
            f"{r['rate_hz']:g}",
            f"{r['duration_s']:.4g}",
            _fmt_range(r["x_mm"]),
            _fmt_range(r["v_m_s"], 3),
            _fmt_range(r["F_n"]),
            levels,
            "; ".join(_unless_shown(p) for p in r["problems"]) or "-",
        )
        table.add_row(*(escape(c) for c in cells))
    Console(width=200).print(table)


def info(
    ctx: typer.Context,
    paths: Annotated[
        list[Path] | None, typer.Argument(help="Data files or folders (CSV, Parquet, MAT).")
    ] = None,
    pattern: Annotated[
        str | None,
        typer.Option(
            "--pattern",
            help="Regex for file names in folders; named groups become metadata. Default: the "
            "sine-record pattern if any file matches it, else every CSV/Parquet/MAT file.",
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
    example: Annotated[
        bool,
        typer.Option("--example", help="Describe the built-in example (virtual rig, Table II)."),
    ] = False,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Describe records: size, rate, ranges, current levels and detected problems."""
    if example:
        refuse_unused(ctx, "info", {"--example"})
        if paths:
            raise DataValidationError("PATH", "not with --example: the example is not read")
        records = _example()
        title = "built-in example: virtual rig, Table II design (scale 0.1, seed 0)"
    else:
        if not paths:
            raise DataValidationError("PATH", "give at least one file or folder, or --example")
        records = read_paths(list(paths), pattern, read_kw or {})
        title = ", ".join(str(p) for p in paths)
    rows = [record_summary(e) for e in records]
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
    else:
        _print_table(rows, title)


def register(app: typer.Typer) -> None:
    """Add the ``info`` command to ``app``."""
    app.command("info")(reader_options(default_nan_policy="interpolate")(info))
