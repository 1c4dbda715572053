"""``mrdamper rig``: the virtual test rig from the command line.

``mrdamper rig doe --out DIR [--seed N] [--scale S] [--fs HZ] [--damper NAME|FILE] [--workers W]
[--format csv|parquet] [--extension none|control] [--loop-model FILE|KIND|rig] [--plan-only]
[--stroke M] [--max-velocity M/S] [--no-progress] [--force]`` generates the paper's Table II
design of experiments (with ``--extension control`` also the control-oriented extension,
:mod:`mrdamper.control.loop.doe_extension`: the quarter-car loop's damper motions and currents
replayed on the rig, the loop run with a first model: by default SP-1 fitted on the Table II
records just generated) and writes one file per record (CSV or Parquet) plus ``manifest.csv``;
with ``--plan-only`` it writes the commands of every record for a physical rig and their check
against the rig's limits (:mod:`mrdamper.rig.plan`) instead. On a terminal it shows a progress
bar, and it says how much it wrote.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, cast

import typer

from mrdamper.cli._modes import refuse_unused
from mrdamper.errors import DataValidationError, SimulationDivergedError

if TYPE_CHECKING:
    import pandas as pd
    from rich.progress import Progress, TaskID

    from mrdamper.models.base import FittedModel
    from mrdamper.rig.virtual_rig import VirtualRig

__all__ = ["register", "rig_app"]

rig_app = typer.Typer(
    help="Virtual test rig: generate the paper's design of experiments.", no_args_is_help=True
)


def _damper(spec: str | None) -> FittedModel | None:
    from mrdamper.rig.reference import resolve_damper

    return resolve_damper(spec)


@rig_app.command("doe")
def doe(
    ctx: typer.Context,
    out: Annotated[
        Path, typer.Option("--out", help="Output folder (must be absent or empty unless --force).")
    ],
    seed: Annotated[
        int,
        typer.Option("--seed", min=0, help="Root seed; the same seed gives byte-identical files."),
    ] = 0,
    scale: Annotated[
        float, typer.Option("--scale", help="Duration factor (0.1: 3 s and 60 s records).")
    ] = 1.0,
    fs: Annotated[float, typer.Option("--fs", help="Sampling rate [Hz].")] = 1000.0,
    damper: Annotated[
        str | None,
        typer.Option(
            "--damper", help="Reference damper name (quiroz2022, spencer1997) or a model JSON file."
        ),
    ] = None,
    workers: Annotated[
        int, typer.Option("--workers", min=1, help="Worker processes (same files for any number).")
    ] = 1,
    force: Annotated[
        bool, typer.Option("--force", help="Write into a non-empty folder, overwriting.")
    ] = False,
    format: Annotated[
        str, typer.Option("--format", help="Record files: csv or parquet (needs pyarrow).")
    ] = "csv",
    no_progress: Annotated[
        bool, typer.Option("--no-progress", help="No progress bar (shown only on a terminal).")
    ] = False,
    extension: Annotated[
        str,
        typer.Option(
            "--extension",
            help="none (Table II only) or control: add the control-oriented extension "
            "(the quarter-car loop's damper motions, replayed with the loop's current and with "
            "a fast APRBS current; root seed SEED + 1).",
        ),
    ] = "none",
    loop_model: Annotated[
        str | None,
        typer.Option(
            "--loop-model",
            help="First model whose quarter-car loop gives the extension's motions: a saved "
            "model (JSON), a kind name fitted with its defaults on the Table II records just "
            "generated, or 'rig' (the virtual rig's own damper, which a physical rig does not "
            "have). Default: sp1 fitted on Table II (with --plan-only: a model file of your "
            "damper).",
        ),
    ] = None,
    plan_only: Annotated[
        bool,
        typer.Option(
            "--plan-only",
            help="Write the rig test plan (displacement and current commands per record, and "
            "plan.csv: each record against the rig's stroke, velocity, current and load-cell "
            "limits) instead of running the virtual rig.",
        ),
    ] = False,
    stroke: Annotated[
        float | None,
        typer.Option("--stroke", help="Total actuator stroke [m] (default 0.04)."),
    ] = None,
    max_velocity: Annotated[
        float | None,
        typer.Option(
            "--max-velocity",
            help="Largest actuator velocity [m/s], checked by --plan-only (default: reported, "
            "not checked).",
        ),
    ] = None,
) -> None:
    """Generate the paper's Table II DoE on the virtual rig.

    Writes the record files + manifest.csv.
    """
    from mrdamper._io import check_output
    from mrdamper.rig.doe import TABLE_II, table_ii
    from mrdamper.rig.doe_io import RECORD_FORMATS, write_records

    if extension not in ("none", "control"):
        raise DataValidationError("--extension", f"expected none or control, got {extension!r}")
    if format not in RECORD_FORMATS:
        raise DataValidationError(
            "--format", f"expected one of {list(RECORD_FORMATS)}, got {format!r}"
        )
    refuse_unused(
        ctx, "rig doe", {f"--extension {extension}", *(["--plan-only"] if plan_only else [])}
    )
    if max_velocity is not None and not plan_only:
        raise DataValidationError("--max-velocity", "expected only with --plan-only")
    loop_file = _loop_model_file(loop_model)
    if plan_only and extension == "control" and loop_file is None:
        raise DataValidationError(
            "--loop-model",
            "expected a model file of your damper (fitted on its Table II records) with "
            "--plan-only --extension control: the loop's motions depend on the damper",
        )
    inputs = [Path(damper)] if damper and Path(damper).exists() else []
    check_output(
        out, force=force, folder=True, inputs=[*inputs, *([loop_file] if loop_file else [])]
    )
    from mrdamper.control.loop.doe_extension import FIRST_KIND, control_extension, first_model
    from mrdamper.data import ExperimentSet
    from mrdamper.rig.doe_control import CONTROL_EXTENSION, STROKE_TEST

    first = None if loop_file is None else _loop_model(loop_file)
    rig = _rig(damper, fs, stroke, plan_only, first)
    n_ext = 2 * len(CONTROL_EXTENSION) + len(STROKE_TEST) if extension == "control" else 0
    n_rec = sum(s.replicates for s in TABLE_II) + n_ext
    written: list[int] = []
    loop_note = ""
    with _bar(not no_progress) as bar:
        gen = bar.add_task("generating" if not plan_only else "planning", total=n_rec)
        t0 = time.perf_counter()
        records = table_ii(
            seed=seed,
            scale=scale,
            rig=rig,
            workers=workers,
            progress=lambda _rec: bar.advance(gen),
        )
        if n_ext:
            if loop_model == "rig":
                first, loop_note = rig.model, "the rig's own damper"
            elif first is None:
                kind = loop_model or FIRST_KIND
                first = first_model(records, kind, input=rig.model.input)
                loop_note = f"{kind} fitted on the {len(records)} Table II records"
            else:
                loop_note = f"{first.kind} from {loop_file}"
            try:
                ext = control_extension(seed=seed + 1, scale=scale, rig=rig, model=first)
            except (DataValidationError, SimulationDivergedError) as exc:
                _loop_model_failed(exc, loop_file)
            for _ in range(n_ext):
                bar.advance(gen)
            records = ExperimentSet([*records, *ext], name=records.name + "+control")
        t1 = time.perf_counter()
        wri = bar.add_task(f"writing {format}", total=len(records))

        def wrote(path: Path) -> None:
            written.append(path.stat().st_size)
            bar.advance(wri)

        if plan_only:
            from mrdamper.rig.plan import RigLimits, plan_limits, write_plan

            table = plan_limits(records, RigLimits.of(rig, max_velocity))
            manifest = write_plan(records, table, out, force=force, progress=wrote)
        else:
            manifest = write_records(records, out, force=force, format=format, progress=wrote)  # type: ignore[arg-type]
        t2 = time.perf_counter()
    samples = sum(r.n for r in records)
    what = "planned" if plan_only else "generated"
    typer.echo(
        f"{len(records)} records, {samples} samples ({samples / fs:g} s at {fs:g} Hz), "
        f"seed {seed}, scale {scale:g}: {what} in {t1 - t0:.1f} s, written in {t2 - t1:.1f} s"
    )
    if loop_note:
        typer.echo(f"extension loops run with {loop_note}")
    typer.echo(
        f"wrote {len(written)} {'csv' if plan_only else format} files, "
        f"{sum(written) / 1e6:.1f} MB, to {out}"
    )
    if plan_only:
        over = table[table["exceeds"] != ""]
        typer.echo(f"plan: {manifest} ({len(over)} of {len(table)} records exceed a rig limit)")
        for limit, names in _exceeding(over).items():
            shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
            typer.echo(
                f"warning: {len(names)} of {len(table)} records exceed the rig's {limit} limit "
                f"({shown}; see {manifest.name})",
                err=True,
            )
    else:
        typer.echo(f"manifest: {manifest}")


def _exceeding(table: pd.DataFrame) -> dict[str, list[str]]:
    """``{limit: [record, ...]}`` of a plan table's ``exceeds`` column."""
    out: dict[str, list[str]] = {}
    for record, exceeds in zip(table["record"], table["exceeds"], strict=True):
        for limit in filter(None, str(exceeds).split(", ")):
            out.setdefault(limit, []).append(str(record))
    return out


def _loop_model_file(spec: str | None) -> Path | None:
    """The ``--loop-model`` file, or None for a kind name, ``rig`` or no value."""
    from mrdamper.kinds import rows
    from mrdamper.kinds import spec as kind_spec

    if spec is None or spec == "rig" or kind_spec(spec) is not None:
        return None
    path = Path(spec)
    if not path.is_file():
        kinds = ", ".join(row.kind for row in rows())
        raise DataValidationError(
            "--loop-model", f"expected a model file, a kind ({kinds}) or 'rig', got {spec!r}"
        )
    return path


def _rig(
    damper: str | None, fs: float, stroke: float | None, plan: bool, first: FittedModel | None
) -> VirtualRig:
    """The rig of ``rig doe``: the virtual rig, or with ``plan`` the plan rig whose damper
    estimate is ``--damper`` or else the loop model file's model."""
    from mrdamper.rig.actuator import ServoActuator
    from mrdamper.rig.plan import PlanRig
    from mrdamper.rig.virtual_rig import VirtualRig

    model = first if plan and first is not None and not damper else _damper(damper)
    actuator = ServoActuator() if stroke is None else ServoActuator(stroke=stroke)
    cls = PlanRig if plan else VirtualRig
    return cls(damper=model, fs=fs, actuator=actuator)


def _loop_model(path: Path) -> FittedModel:
    """The ``--loop-model``, refused at once when trained at one level (its loop never switches
    the current)."""
    from mrdamper.models.levels import check_levels
    from mrdamper.models.registry import load_model

    model = load_model(path)
    check_levels(model, "its loop never switches the current", field="--loop-model")
    return model


def _loop_model_failed(exc: Exception, path: Path | None) -> None:
    """Re-raise a failure of the control extension, naming ``--loop-model`` when its loop (the
    model given) failed rather than another setting."""
    if path is None or getattr(exc, "field", "model") not in ("model", "MODEL"):
        raise exc
    text = str(exc).split(": ", 1)[1] if isinstance(exc, DataValidationError) else str(exc)
    raise DataValidationError(
        "--loop-model", f"the quarter-car loop of {path.name} failed: {text}"
    ) from None


class _NoBar:
    """Stand-in for a rich Progress when no bar is shown."""

    def __enter__(self) -> _NoBar:  # noqa: PYI034
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def add_task(self, description: str, total: int) -> TaskID:
        return cast("TaskID", 0)

    def advance(self, task: TaskID) -> None:
        return None


def _bar(enabled: bool) -> Progress | _NoBar:
    """A rich progress bar on standard error when it is a terminal (else a silent stand-in)."""
    import sys

    if not enabled or not sys.stderr.isatty():
        return _NoBar()
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=False,
    )


def register(app: typer.Typer) -> None:
    """Add the ``rig`` command group to ``app``."""
    app.add_typer(rig_app, name="rig")
