"""``mrdamper info``: what is in a data file or folder, and what looks wrong with it.

For each record it shows samples, rate, duration, ranges of x, v and F, the current (or voltage)
levels and detected problems: repaired NaN samples, regenerated time, force plateaus at the
extremes (clipping or saturation), nearly constant force, current outside 0..4 A.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from mrdamper.cli._records import read_paths, reader_options
from mrdamper.data.experiment import Experiment
from mrdamper.errors import DataValidationError, MrDamperError

__all__ = ["CURRENT_RANGE", "detect_problems", "register", "summarize"]

#: Coil current range of the rig [A] (paper Section IV); values outside are flagged.
CURRENT_RANGE = (0.0, 4.0)
#: Standard deviation of the force [N] below which the force is reported as nearly constant.
MIN_FORCE_STD = 1.0
#: Most distinct values for an electrical input to be shown as levels rather than a range.
MAX_LEVELS = 8


def _longest_run(mask: np.ndarray) -> int:
    if not mask.any():
        return 0
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return int((np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)).max())


def _levels(values: np.ndarray) -> list[float] | None:
    levels = np.unique(np.round(values, 9))
    return [float(v) for v in levels] if levels.size <= MAX_LEVELS else None


def detect_problems(exp: Experiment) -> list[str]:
    """Return human-readable warnings about a record (empty if nothing was found).

    Checks
    ------
    * repairs made while reading (``metadata["repairs"]``: NaN samples, regenerated time, ...);
    * values beyond the plausibility bounds (``metadata["implausible"]``, see
      :mod:`mrdamper.data.plausibility`: usually wrong declared units);
    * a force plateau at its maximum or minimum: the extreme value held for at least
      ``max(10, n / 500)`` consecutive samples (clipping or sensor saturation);
    * force standard deviation below :data:`MIN_FORCE_STD` [N];
    * coil current outside :data:`CURRENT_RANGE` [A].
    """
    problems = [f"repaired: {r}" for r in exp.metadata.get("repairs", ())]
    problems += [f"implausible: {r}" for r in exp.metadata.get("implausible", ())]
    F = exp.F
    min_run = max(10, exp.n // 500)
    for label, extreme in (("maximum", F.max()), ("minimum", F.min())):
        run = _longest_run(F == extreme)
        if run >= min_run:
            problems.append(
                f"F held at its {label} {extreme:.6g} N for {run} consecutive samples "
                "(clipping or saturation?)"
            )
    std = float(np.std(F))
    if std < MIN_FORCE_STD:
        problems.append(f"force nearly constant (standard deviation {std:.3g} N)")
    if exp.i is not None:
        lo, hi = float(exp.i.min()), float(exp.i.max())
        if lo < CURRENT_RANGE[0] - 1e-9 or hi > CURRENT_RANGE[1] + 1e-9:
            problems.append(
                f"current spans [{lo:.4g}, {hi:.4g}] A, outside {CURRENT_RANGE[0]:g}..{CURRENT_RANGE[1]:g} A"
            )
    return problems


def summarize(exp: Experiment) -> dict[str, Any]:
    """Return one record's summary as JSON-safe data (the rows of ``mrdamper info``).

    Keys: ``name, samples, rate_hz, duration_s, x_mm, v_m_s, F_n`` (each range a ``[min, max]``
    pair), ``input`` (``"i"`` or ``"voltage"``), ``levels`` (distinct values, or None if more
    than :data:`MAX_LEVELS`), ``input_range``, ``problems`` and ``source``.
    """
    source = "i" if exp.i is not None else "voltage"
    el = exp.electrical(source)  # type: ignore[arg-type]
    return {
        "name": exp.name,
        "samples": exp.n,
        "rate_hz": exp.fs,
        "duration_s": exp.duration,
        "x_mm": [float(exp.x.min() * 1e3), float(exp.x.max() * 1e3)],
        "v_m_s": [float(exp.v.min()), float(exp.v.max())],
        "F_n": [float(exp.F.min()), float(exp.F.max())],
        "input": source,
        "levels": _levels(el),
        "input_range": [float(el.min()), float(el.max())],
        "problems": detect_problems(exp),
        "source": str(exp.metadata.get("source", "")),
    }


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


def _print_table(rows: list[dict[str, Any]], title: str) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(title), show_lines=False)
    for col, justify in (
        ("name", "left"),
        ("samples", "right"),
        ("rate [Hz]", "right"),
        ("duration [s]", "right"),
        ("x [mm]", "right"),
        ("v [m/s]", "right"),
        ("F [N]", "right"),
        ("input levels", "left"),
        ("problems", "left"),
    ):
        table.add_column(escape(col), justify=justify, overflow="fold")  # type: ignore[arg-type]
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
            "; ".join(r["problems"]) or "-",
        )
        table.add_row(*(escape(c) for c in cells))
    Console(width=200).print(table)


def info(
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
        records = _example()
        title = "built-in example: virtual rig, Table II design (scale 0.1, seed 0)"
    else:
        if not paths:
            raise DataValidationError("PATH", "give at least one file or folder, or --example")
        if pattern is not None:
            try:
                re.compile(pattern)
            except re.error as exc:
                raise DataValidationError(
                    "pattern", f"{pattern!r} is not a valid regular expression ({exc})"
                ) from None
        records = read_paths(list(paths), pattern, read_kw or {})
        title = ", ".join(str(p) for p in paths)
    rows = [summarize(e) for e in records]
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
    else:
        _print_table(rows, title)


def register(app: typer.Typer) -> None:
    """Add the ``info`` command to ``app``."""
    app.command("info")(reader_options(default_nan_policy="interpolate")(info))
