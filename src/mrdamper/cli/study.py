"""``mrdamper study`` and ``mrdamper demo``: run the model comparison and write its report.

``study`` reads records from a file or folder and runs a protocol on them; ``demo`` generates the
paper's Table II design of experiments on the virtual rig (seeded) and runs the default protocol.
Both refuse to write into a non-empty output folder unless ``--force`` is given, and check this
before any computation starts.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from mrdamper.cli._modes import refuse_unused
from mrdamper.cli._records import reader_options
from mrdamper.cli._status import finished_lines
from mrdamper.errors import DataValidationError, SchemaError
from mrdamper.kinds import kind_list

if TYPE_CHECKING:
    from rich.console import JustifyMethod

__all__ = [
    "DEMO_OUT",
    "QUICK_SCALE",
    "demo",
    "print_summary",
    "register",
    "study",
    "write_or_fail",
]

#: Duration scale of the Table II records in ``demo --quick`` (30 s -> 3 s, 600 s -> 60 s).
QUICK_SCALE = 0.1
#: Default output folder of ``mrdamper demo``.
DEMO_OUT = Path("mrdamper-demo")


def _headless() -> None:
    """Draw figures off-screen: the commands only write files."""
    import matplotlib

    matplotlib.use("Agg")


def _check_out(out: Path, force: bool, inputs: list[Path] | None = None) -> None:
    from mrdamper._io import check_output

    check_output(out, force=force, folder=True, inputs=inputs or [])


def _models(models: str | None) -> list[str] | None:
    if models is None:
        return None
    kinds = [m.strip() for m in models.split(",") if m.strip()]
    if not kinds:
        raise SchemaError(
            f"models: expected a comma-separated list of kinds such as lpv,sp1, got {models!r}"
        )
    from mrdamper.models import known_kinds

    unknown = [k for k in kinds if k not in known_kinds()]
    if unknown:
        raise SchemaError(f"models: unknown kind(s) {unknown}; expected some of {known_kinds()}")
    return kinds


def write_or_fail(res: Any, out: Path, force: bool, show: bool = False) -> None:
    """Write the study to ``out`` and print its summary; when every fit failed, print the
    failures and one ``error:`` line instead, write nothing and exit with status 1. ``show``:
    a progress line while the figures and the report are written."""
    from mrdamper.study import write_study
    from mrdamper.study.runner import progress_bars

    ok = res.fits["status"] == "ok"
    if not ok.any():
        print_summary(res)
        typer.echo(
            f"error: every fit failed ({len(ok)} of {len(ok)}: see the lines above); nothing "
            f"written to {out}",
            err=True,
        )
        raise typer.Exit(1)
    with progress_bars(show) as bar:
        task = bar.add_task("writing", total=None)  # figures (PNG and SVG) and the report
        write_study(res, out, force=force)
        bar.update(task, total=1, completed=1)
    print_summary(res, out)


def print_summary(res: Any, out: Path | None = None) -> None:
    """Print the per-model means, failures, the headline and where the report is."""
    import math

    from rich.console import Console
    from rich.table import Table

    console = Console()
    s = res.summary
    table = Table(title=f"Model comparison ({res.protocol.name}): scored records per model")
    columns: tuple[tuple[str, JustifyMethod], ...] = (
        ("model", "left"),
        ("ok", "right"),
        ("failed", "right"),
        ("ESR mean", "right"),
        ("ESR median", "right"),
        ("SSSE mean [N]", "right"),
        ("fit time [s]", "right"),
    )
    for col, just in columns:
        table.add_column(col, justify=just)

    def f(x: float, fmt: str = "{:.4g}") -> str:
        return "-" if not math.isfinite(x) else fmt.format(x)

    for row in s.itertuples(index=False):
        table.add_row(
            row.model,
            str(row.n_ok),
            str(row.n_failed),
            f(row.esr_mean),
            f(row.esr_median),
            f(row.ssse_mean),
            f(row.fit_time_s, "{:.2f}"),
        )
    console.print(table)
    failed = res.fits[res.fits["status"] != "ok"]
    for row in failed.itertuples(index=False):
        console.print(
            f"[yellow]{row.model}[/] did not fit ({row.fold}): {row.error}",
            markup=True,
            highlight=False,
        )
    for hl in res.headlines():
        console.print(
            "[bold]Headline[/] (LPV vs the best of the paper's classical models P-15, SP-1..SP-4): "
            f"{hl['text']}",
            highlight=False,
        )
    console.print(
        "The paper reports LPV 51 % lower mean ESR and 36.8 % lower mean SSSE than its best "
        "classical model (SP-1).",
        highlight=False,
    )
    if out is not None:
        console.print(
            f"Report: [bold]{out / 'report.html'}[/] (tables in {out}/summary.csv, "
            f"{out}/results.csv)",
            highlight=False,
        )


def study(
    ctx: typer.Context,
    data: Path = typer.Argument(..., help="Data file or folder (CSV, Parquet, MAT)."),
    out: Path = typer.Option(
        ..., "--out", help="Output folder (must not exist or be empty, unless --force)."
    ),
    protocol: str = typer.Option(
        None,
        "--protocol",
        help=(
            "Protocol file (.json or .toml) or a preset: doe, quiroz, dyke. Default: chosen from "
            "the records (see docs/study.md: doe / quiroz presets by metadata, else k-fold by "
            "record or a time split)."
        ),
    ),
    models: str = typer.Option(
        None,
        "--models",
        help=f"Comma-separated model kinds among {kind_list()} (default: the protocol's).",
    ),
    workers: int = typer.Option(
        None, "--workers", help="Local worker processes (default min(2, CPUs); 1 = in-process)."
    ),
    scheduler: str = typer.Option(
        None, "--scheduler", help="Dask scheduler address (tcp://host:8786); replaces --workers."
    ),
    pattern: str = typer.Option(
        None, "--pattern", help="Regex for file names in a folder; named groups become metadata."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed given to every estimator that takes one."),
    force: bool = typer.Option(False, "--force", help="Replace a non-empty output folder."),
    no_progress: bool = typer.Option(False, "--no-progress", help="Do not show progress bars."),
    load: str = typer.Option(
        "worker",
        "--load",
        help="Where records are read: worker (by the tasks that use them; this process keeps "
        "headers only) or parent (all into memory first).",
    ),
    no_control: bool = typer.Option(
        False, "--no-control", help="Skip the control-relevance step (quarter-car loop)."
    ),
    control_roads: str = typer.Option(
        "C", "--control-roads", help="ISO 8608 classes of the control-relevance step (A..H)."
    ),
    control_duration: float = typer.Option(
        3.0, "--control-duration", help="Road length of the control-relevance step [s] (>= 2)."
    ),
    control_plant: str = typer.Option(
        None,
        "--control-plant",
        help="The damper behind virtual-rig records, as the truth of the control-relevance step: "
        "rig, rig:NAME or a model file (default: the damper the records name; unused on "
        "measured data).",
    ),
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Fit and score every model of a protocol on DATA.

    Writes tables, models, figures and report.html.
    """
    from mrdamper.study import choose_protocol, run_study, study_records

    refuse_unused(ctx, "study", _modes(no_control=no_control, scheduler=scheduler))
    if scheduler is not None:
        from mrdamper.study.executor import check_scheduler_address

        check_scheduler_address(scheduler)
    plant_inputs = [Path(control_plant)] if control_plant and Path(control_plant).exists() else []
    _check_out(out, force, [data, *plant_inputs])
    _headless()
    kinds = _models(models)
    control = control_settings(no_control, control_roads, control_duration, plant=control_plant)
    records = study_records(data, pattern, load=load, **(read_kw or {}))  # type: ignore[arg-type]
    if control is not None and control_plant is not None:
        from mrdamper.study.control_step import truth_damper

        if truth_damper(records, control_plant) is None:
            raise DataValidationError(
                "--control-plant",
                "the records are not all from the virtual rig with one damper (measured data): "
                "no loop compares a model with them, so a plant has no use here (drop it)",
            )
    proto, why = choose_protocol(records, protocol)
    typer.echo(f"{len(records)} records from {data}; {why}", err=True)
    with finished_lines("study", show=not no_progress):
        res = run_study(
            records,
            proto,
            kinds,
            workers=workers,
            scheduler=scheduler,
            seed=seed,
            progress=not no_progress,
            control=control,
        )
    write_or_fail(res, out, force, show=not no_progress)


def _modes(*, no_control: bool, scheduler: str | None = None) -> set[str]:
    """The modes of ``study`` / ``demo`` the options given select (:mod:`mrdamper.cli._modes`)."""
    return {m for m, on in (("--no-control", no_control), ("--scheduler", scheduler)) if on}


def control_settings(
    off: bool, roads: str, duration: float, quick: bool = False, plant: str | None = None
) -> Any:
    """The :class:`~mrdamper.study.control_step.ControlSettings` of the command's options (None
    with ``--no-control``; with ``quick``, the demo's ``--quick``, passive soft and skyhook only
    and no gain fronts; ``plant``, the study's ``--control-plant``, checked here)."""
    from mrdamper.rig.reference import REFERENCE_DAMPERS
    from mrdamper.study.control_step import QUICK_CONTROLLERS, ControlSettings

    if plant is not None:
        name = plant[4:] if plant.startswith("rig:") else None
        if not (plant == "rig" or name in REFERENCE_DAMPERS or Path(plant).is_file()):
            raise DataValidationError(
                "--control-plant",
                f"expected rig, rig:NAME (NAME one of {list(REFERENCE_DAMPERS)}) or a model file, "
                f"got {plant!r}",
            )
    if off:
        return None
    classes = tuple(r.strip().upper() for r in roads.split(",") if r.strip())
    bad = [c for c in classes if c not in tuple("ABCDEFGH")]
    if bad or not classes:
        raise DataValidationError(
            "--control-roads", f"expected ISO 8608 classes A..H, comma-separated, got {roads!r}"
        )
    if quick:
        return ControlSettings(
            road_classes=classes,
            duration=duration,
            controllers=QUICK_CONTROLLERS,
            fronts=False,
            plant=plant,
        )
    return ControlSettings(road_classes=classes, duration=duration, plant=plant)


def demo(
    ctx: typer.Context,
    out: Path = typer.Option(
        DEMO_OUT,
        "--out",
        help="Output folder (default ./mrdamper-demo; never replaced without --force).",
    ),
    quick: bool = typer.Option(
        False,
        "--quick",
        help=f"Shortened records (durations x {QUICK_SCALE}) for a run under a minute.",
    ),
    force: bool = typer.Option(False, "--force", help="Replace a non-empty output folder."),
    models: str = typer.Option(
        None,
        "--models",
        help=f"Comma-separated model kinds among {kind_list()} (default: all installed).",
    ),
    workers: int = typer.Option(
        None, "--workers", help="Local worker processes (default min(2, CPUs))."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the virtual rig and the estimators."),
    scale: float = typer.Option(
        None, "--scale", help="Duration scale of the records (overrides --quick)."
    ),
    no_progress: bool = typer.Option(False, "--no-progress", help="Do not show progress bars."),
    no_control: bool = typer.Option(
        False,
        "--no-control",
        help="Skip the control-relevance step (quarter-car loop; with --quick: soft and skyhook, "
        "no gain fronts).",
    ),
    control_roads: str = typer.Option(
        "C", "--control-roads", help="ISO 8608 classes of the control-relevance step (A..H)."
    ),
    control_duration: float = typer.Option(
        3.0, "--control-duration", help="Road length of the control-relevance step [s] (>= 2)."
    ),
) -> None:
    """Generate the paper's Table II experiments on the virtual rig and compare every model.

    Writes a report.
    """
    import time

    from rich.console import Console

    from mrdamper import compiled
    from mrdamper.study import doe_protocol, run_study

    refuse_unused(ctx, "demo", _modes(no_control=no_control))
    _check_out(out, force)
    _headless()
    kinds = _models(models)
    sc = scale if scale is not None else (QUICK_SCALE if quick else 1.0)
    if not (isinstance(sc, float) and 0.0 < sc <= 1.0):
        raise DataValidationError("scale", f"expected a duration scale in (0, 1], got {sc!r}")
    try:
        from mrdamper.rig.doe import table_ii
    except ImportError as exc:
        raise SchemaError(
            f"demo: the virtual rig is not available on this installation ({exc})"
        ) from None
    console = Console(stderr=True)
    t0 = time.perf_counter()
    console.print(
        f"[bold]mrdamper demo[/]: the paper's Table II experiments on the virtual rig "
        f"(durations x {sc:g}, 1 kHz, seed {seed}), then every model identified and scored.",
        highlight=False,
    )
    # on a fresh installation, compile the models' kernels on another core meanwhile (already
    # started by the launcher, mrdamper.cli.launch, when the demo was run from the command line)
    compiled.compile_ahead(
        kinds or [s.kind for s in doe_protocol().resolved_models()], last=compiled.RIG_KERNELS
    )
    try:
        compiled.wait_rig()  # started at launch: the rig's damper kernel, on the other core
        data = table_ii(seed=seed, scale=sc)
    except BaseException:
        compiled.finish_ahead(cancel=True)
        raise
    n = sum(e.n for e in data)
    console.print(
        f"Generated {len(data)} records ({n / 1e6:.2f} million samples) in "
        f"{time.perf_counter() - t0:.1f} s.",
        highlight=False,
    )
    try:
        with finished_lines("demo", show=not no_progress):
            res = run_study(
                data,
                doe_protocol(),
                kinds,
                workers=workers,
                seed=seed,
                progress=not no_progress,
                control=control_settings(no_control, control_roads, control_duration, quick),
            )
    finally:
        compiled.finish_ahead(cancel=True)  # no-op: the study waited for it
    write_or_fail(res, out, force, show=not no_progress)
    console.print(
        f"Done in {time.perf_counter() - t0:.0f} s. Open {out / 'report.html'} in a browser.",
        highlight=False,
    )


def register(app: typer.Typer) -> None:
    """Add the ``study`` and ``demo`` commands to ``app``."""
    app.command("study")(reader_options()(study))
    app.command("demo")(demo)
