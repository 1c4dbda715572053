"""``mrdamper quartercar``: semi-active controllers on a quarter car with the identified damper.

``quartercar MODEL.json --out DIR`` drives the quarter car
(:mod:`mrdamper.control.loop.quarter_car`)
over ISO 8608 roads and a bump with every controller and writes, atomically and never over an
existing file without ``--force``:

* ``DIR/quartercar.csv``: the metrics table (one row per road and controller);
* ``DIR/time_<road>.png``: time histories of the first ISO road (2 s in its middle) and of the bump;
* ``DIR/spectra_<road>.png``: body-acceleration PSD and transmissibility of the first ISO road.

The table is also printed. With ``--c-inverse LIB.so`` (a shared library compiled from MODEL's
C export, ``mrdamper export --format c``) the library's inverse drives the car in place of the
Python one (:mod:`mrdamper.control.export.c_inverse`).

With ``--plant PLANT`` (a model file, ``rig`` for the virtual rig's reference damper or
``rig:NAME``) the controller is still built from MODEL but the car is also driven with PLANT as its
damper: ``DIR/closed_loop.csv`` gets the metrics predicted (MODEL as damper) against those achieved
(PLANT as damper) per controller, road and speed (:mod:`mrdamper.control.loop.fidelity`) and
``DIR/closed_loop_runs.csv`` the numerics of every run (plant sub-steps, halving change,
high-frequency share, training-envelope excursions); warnings go to standard error, one line
per finding over every run.
The car (``--car``), the gains (``--c-sky``, ``--c-ground``, ``--alpha``) and the inverse's
settings (``--reg``, ``--rate``) are those of both sides, checked as without ``--plant``; the bump
options are refused (the comparison runs the ISO roads), as is a model or plant identified at one
level. When every loop with the model (or the plant) as damper fails the command stops with one
line and writes nothing; when some fail, the tables are written and the exit status is 1.
Which option each mode refuses is one table, :mod:`mrdamper.cli._modes`.

With ``--tune`` the passive inputs and the semi-active gains are swept on each ISO road
(:mod:`mrdamper.control.loop.fronts`), with MODEL as the damper and, with ``--plant``, with PLANT:
``DIR/fronts.csv`` (every point), ``DIR/fronts.png`` (predicted and achieved fronts) and the gains
chosen on the model, printed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from mrdamper._io import FileKind, csv_kind, png_kind
from mrdamper.cli._help import kinds_text
from mrdamper.cli._modes import refuse_unused
from mrdamper.controller_names import BUILTIN_CONTROLLERS
from mrdamper.errors import DataValidationError

__all__ = ["QUARTERCAR_CSV", "register"]

#: The kinds of file ``quartercar`` writes (``--force`` replaces only such files).
QUARTERCAR_CSV = csv_kind(
    "table written by 'mrdamper quartercar' (road, controller, ...)", ("road", "controller")
)
_PNG = png_kind()
#: The tables of ``quartercar --plant`` (predicted against achieved, and one row per run).
_FIDELITY_FILES: dict[str, FileKind] = {
    "closed_loop.csv": csv_kind(
        "table written by 'mrdamper quartercar --plant' (controller, road, ...)",
        ("controller", "road"),
    ),
    "closed_loop_runs.csv": csv_kind(
        "runs written by 'mrdamper quartercar --plant'", ("controller", "road")
    ),
}

#: The sweep of ``quartercar --tune``.
_FRONTS_CSV = csv_kind(
    "gain sweep written by 'mrdamper quartercar --tune' (road, speed_m_s, side, ...)",
    ("road", "speed_m_s", "side"),
)


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_").lower()


def _png_writer(fig: Any) -> Callable[[Path], object]:
    """Writer of ``fig`` as PNG into a given path (the figure is closed once written)."""
    import matplotlib.pyplot as plt

    def write(path: Path) -> None:
        try:
            fig.savefig(path, format="png", dpi=100, metadata={"Software": None})
        finally:
            plt.close(fig)

    return write


def quartercar(
    ctx: typer.Context,
    model_file: Annotated[
        Path,
        typer.Argument(
            help=f"Damper model file written by 'mrdamper fit' (any kind: {kinds_text()})."
        ),
    ],
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Output folder for the table and figures.")
    ],
    roads: Annotated[
        str, typer.Option("--roads", help="ISO 8608 classes, comma-separated (A..H).")
    ] = "A,B,C,D,E",
    bump: Annotated[
        bool, typer.Option("--bump/--no-bump", help="Also drive over one bump.")
    ] = True,
    controllers: Annotated[
        str,
        typer.Option("--controllers", help=f"Comma-separated: {', '.join(BUILTIN_CONTROLLERS)}."),
    ] = ",".join(BUILTIN_CONTROLLERS),
    speed: Annotated[float, typer.Option("--speed", help="Vehicle speed [m/s].")] = 20.0,
    duration: Annotated[
        float, typer.Option("--duration", help="Length of each ISO road [s].")
    ] = 20.0,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the road phases.")] = 0,
    bump_height: Annotated[float, typer.Option("--bump-height", help="Bump height [m].")] = 0.05,
    bump_length: Annotated[float, typer.Option("--bump-length", help="Bump length [m].")] = 2.0,
    car: Annotated[
        list[str] | None,
        typer.Option(
            "--car",
            help="Quarter-car parameter KEY=VALUE (m_s, m_u, k_s, k_t, c_t, travel_limit, "
            "motion_ratio); repeatable.",
        ),
    ] = None,
    c_sky: Annotated[float, typer.Option("--c-sky", help="Skyhook gain [N s/m].")] = 3000.0,
    c_ground: Annotated[
        float, typer.Option("--c-ground", help="Groundhook gain [N s/m].")
    ] = 3000.0,
    alpha: Annotated[float, typer.Option("--alpha", help="Hybrid weight of skyhook [-].")] = 0.5,
    reg: Annotated[
        float | None, typer.Option("--reg", help="Inverse regularisation weight [N/A].")
    ] = None,
    rate: Annotated[float | None, typer.Option("--rate", help="Input rate bound [A/s].")] = None,
    i_range: Annotated[
        str | None,
        typer.Option(
            "--i-range",
            help="Input limits LO,HI [A] (default: the model's identified range within the "
            "rated range of the damper its records came from).",
        ),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite existing output files.")
    ] = False,
    tune: Annotated[
        bool,
        typer.Option(
            "--tune",
            help="Sweep the passive inputs and the semi-active gains on the model (and on PLANT "
            "when given): writes fronts.csv and fronts.png and prints the gains chosen.",
        ),
    ] = False,
    plant: Annotated[
        str | None,
        typer.Option(
            "--plant",
            help="The damper in the car: a model file, a damper FMU (.fmu, exported by mrdamper), "
            "'rig' or 'rig:NAME' (reference damper); writes predicted (MODEL) against achieved "
            "(PLANT) metrics.",
        ),
    ] = None,
    c_inverse: Annotated[
        Path | None,
        typer.Option(
            "--c-inverse",
            help="A shared library compiled from MODEL's C export (mrdamper export --format c): "
            "its inverse drives the car in place of the Python one (settings fixed at export).",
        ),
    ] = None,
) -> None:
    """Compare passive and semi-active controllers on a quarter car whose damper is the model."""
    from mrdamper._io import check_output, check_writable, write_files
    from mrdamper.control.loop.quarter_car import Controller
    from mrdamper.control.loop.quarter_car_study import compare_controllers
    from mrdamper.models.registry import load_model

    if out.exists() and not out.is_dir():
        raise DataValidationError("--out", f"{out} exists and is not a folder")
    if not (speed > 0):
        raise DataValidationError("--speed", f"expected a vehicle speed > 0 [m/s], got {speed:g}")
    modes = (("--c-inverse", c_inverse), ("--plant", plant), ("--tune", tune))
    refuse_unused(ctx, "quartercar", {m for m, on in modes if on})
    qc = _car(car)  # checked in every mode, as are the gains
    ctrls = [
        Controller(c.strip(), c_sky=c_sky, c_ground=c_ground, alpha=alpha)
        for c in controllers.split(",")
        if c.strip()
    ]
    if tune:
        _tune(model_file, plant, out, roads, speed, duration, seed, force, qc)
        return
    if plant is not None:
        _fidelity(model_file, plant, out, roads, ctrls, speed, duration, seed, force, qc, reg, rate)
        return
    inputs = [model_file] + ([c_inverse] if c_inverse is not None else [])
    check_output(out, force=force, folder=True, mode="add", inputs=inputs)
    check_writable(out / "quartercar.csv", force, inputs=inputs, kind=QUARTERCAR_CSV)
    m = load_model(model_file)
    extra: dict[str, Any] = {}
    if c_inverse is not None:
        from mrdamper.control.export.c_inverse import load_c_inverse

        extra["c_inverse"] = load_c_inverse(m, c_inverse)
        if i_range is None:  # the limits the C inverse was exported with: the identified range
            from mrdamper.control.inverse.current import model_input_limits

            i_range = ",".join(repr(b) for b in model_input_limits(m))
    classes = [r.strip().upper() for r in roads.split(",") if r.strip()]
    try:
        cmp = compare_controllers(
            m,
            road_classes=classes,
            bump=bump,
            controllers=ctrls,
            car=qc,
            speed=speed,
            duration=duration,
            seed=seed,
            bump_height=bump_height,
            bump_length=bump_length,
            reg=reg,
            rate=rate,
            i_range=_pair("--i-range", i_range),
            **extra,
        )
    except TypeError as exc:
        raise DataValidationError("MODEL", str(exc)) from exc
    table = cmp.table()
    text = table.to_csv(index=False, float_format="%.6g")
    files: dict[str, tuple[FileKind, Callable[[Path], object]]] = {
        "quartercar.csv": (QUARTERCAR_CSV, lambda p: p.write_text(text, encoding="utf-8"))
    }
    iso = [r for r in cmp.roads if r.startswith("ISO")]
    mid = 0.5 * duration
    for road in iso[:1]:  # a 2 s window in the middle of the road
        fig = cmp.plot_time(road, t_range=(max(0.0, mid - 1.0), mid + 1.0))
        files[f"time_{_slug(road)}.png"] = (_PNG, _png_writer(fig))
    for road in [r for r in cmp.roads if r.startswith("bump")]:
        files[f"time_{_slug(road)}.png"] = (_PNG, _png_writer(cmp.plot_time(road)))
    if iso:
        files[f"spectra_{_slug(iso[0])}.png"] = (_PNG, _png_writer(cmp.plot_spectra(iso[0])))
    try:
        write_files(out, files, force=force)
    finally:
        import matplotlib.pyplot as plt

        plt.close("all")
    from mrdamper.control.loop.fidelity import HF_SHARE, discrete_rate, input_unit, oscillation

    shown = {  # the printed table: every column with its unit
        "road": "road",
        "controller": "controller",
        "rms_acc": "rms_acc [m/s²]",
        "rms_acc_wk": "rms_acc_wk [m/s²]",
        "rms_tyre_load": "rms_tyre_load [N]",
        "rms_travel": "rms_travel [m]",
        "max_travel": "max_travel [m]",
        "travel_over_limit": "time over travel limit [-]",
        "mean_input": f"mean_input [{input_unit(m)}]",
    }
    typer.echo(
        table[list(shown)]
        .rename(columns=shown)
        .to_string(index=False, float_format=lambda v: f"{v:.4g}")
    )
    osc = [
        (road, ctrl, *oscillation(res))
        for (road, ctrl), res in cmp.results.items()
        if road.startswith("ISO")
    ]
    osc = [o for o in osc if o[2] > HF_SHARE]
    if osc:
        from mrdamper.control.loop.fidelity import oscillation_note

        road, ctrl, share, peak = max(osc, key=lambda o: o[2])
        runs = ", ".join(f"{c} {r}" for r, c, _s, _p in osc)
        typer.echo(
            f"warning: {len(osc)} loop(s) oscillate ({runs}), their metrics are the model's "
            f"loop, not the damper's; the strongest, {ctrl} {road}: "
            f"{oscillation_note(share, peak, qc, discrete_rate(m))}",
            err=True,
        )
    from mrdamper.control.loop.quarter_car_study import limits_note

    if i_range is None and limits_note(m):
        typer.echo(f"note: {limits_note(m)}", err=True)
    for (road, ctrl), why in cmp.refused.items():
        typer.echo(f"warning: {ctrl}, {road}: not run: {why}", err=True)
    if cmp.step_note():
        typer.echo(f"{m.kind} damper through its per-sample step: {cmp.step_note()}")
    how = f" (inverse: {c_inverse.name})" if c_inverse is not None else ""
    typer.echo(f"{m.kind}{how}: wrote {', '.join(files)} in {out}")


def _pair(flag: str, text: str | None) -> tuple[float, float] | None:
    """``LO,HI`` as two floats with ``LO <= HI`` (None for None)."""
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise DataValidationError(flag, f"expected LO,HI (two numbers), got {text!r}") from None
    if not lo <= hi:
        raise DataValidationError(flag, f"expected LO <= HI, got {text!r}")
    return lo, hi


def _car(car: list[str] | None) -> Any:
    """The :class:`QuarterCar` of the ``--car KEY=VALUE`` settings."""
    from mrdamper.cli.models import parse_settings
    from mrdamper.control.loop.quarter_car import QuarterCar

    car_kw = parse_settings(car)
    fields = ("m_s", "m_u", "k_s", "k_t", "c_t", "travel_limit", "motion_ratio")
    unknown = sorted(set(car_kw) - set(fields))
    if unknown:
        raise DataValidationError(
            "--car", f"unknown parameter(s) {unknown}; expected some of {list(fields)}"
        )
    return QuarterCar(**car_kw)


def _inputs(model_file: Path, plant: str | None) -> list[Path]:
    return [model_file] + ([Path(plant)] if plant is not None and Path(plant).is_file() else [])


def _text_writer(text: str) -> Callable[[Path], object]:
    return lambda p: p.write_text(text, encoding="utf-8")


def _tune(
    model_file: Path,
    plant: str | None,
    out: Path,
    roads: str,
    speed: float,
    duration: float,
    seed: int,
    force: bool,
    car: Any,
) -> None:
    from mrdamper._io import check_output, check_writable, write_files
    from mrdamper.control.loop.fidelity import check_sides, input_unit
    from mrdamper.control.loop.fronts import gain_fronts
    from mrdamper.models.registry import load_model

    inputs = _inputs(model_file, plant)
    check_output(out, force=force, folder=True, mode="add", inputs=inputs)
    check_writable(out / "fronts.csv", force, inputs=inputs, kind=_FRONTS_CSV)
    check_writable(out / "fronts.png", force, inputs=inputs, kind=_PNG)
    m = load_model(model_file)
    res = gain_fronts(
        m,
        plant,
        road_classes=[r.strip().upper() for r in roads.split(",") if r.strip()],
        speeds=[speed],
        duration=duration,
        seed=seed,
        car=car,
    )
    check_sides(  # a side whose every point failed: an error, nothing written
        res.rows,
        lambda r: None if r.get("status") == "ok" else str(r.get("status")),
        res.model_kind,
        res.plant_kind,
    )
    text = res.table().to_csv(index=False, float_format="%.6g")
    files: dict[str, tuple[FileKind, Callable[[Path], object]]] = {
        "fronts.csv": (_FRONTS_CSV, _text_writer(text)),
        "fronts.png": (_PNG, _png_writer(res.plot())),
    }
    write_files(out, files, force=force)
    chosen = res.chosen()
    sides = ["predicted"] + (["achieved"] if plant is not None else [])
    cols = ["road", "controller", "c_sky", "c_ground", "alpha"]
    for side in sides:
        cols += [f"{c}_{side}" for c in ("a_w", "rms_travel", "aw_gain_pct", "tyre_gain_pct")]
    shown = chosen[cols].rename(columns=lambda c: c.replace("_predicted", " pred.").replace(
        "_achieved", " ach.").replace("_pct", " [%]"))  # fmt: skip
    typer.echo("gains chosen on the model (gain over passive at equal travel, positive = better):")
    typer.echo(shown.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    gaps = res.widest_gaps()
    if len(gaps):
        typer.echo(
            "widest model-plant gap over the sweep, 100 (predicted - achieved) / achieved "
            "(mean input: predicted - achieved): "
            + "; ".join(_gap_text(row, input_unit(m)) for _, row in gaps.iterrows())
        )
    typer.echo(f"{m.kind}: wrote {', '.join(files)} in {out}")


def _gap_text(row: Any, unit: str) -> str:
    """``a_w +29.0 % (hybrid, c_sky 8000, c_ground 8000, alpha 0.5, ISO C)``, or for the mean
    input its difference ``mean_current +0.012 A (...)``: one point of the sweep."""
    from mrdamper.control.loop.fronts import gap_size

    if row["controller"] == "passive":
        where = f"passive at {row['level']:.0%} of the input range"
    else:
        gains = [
            f"{name} {row[name]:g}"
            for name in ("c_sky", "c_ground", "alpha")
            if math.isfinite(float(row[name]))
        ]
        where = ", ".join([str(row["controller"]), *gains])
    return f"{row['metric']} {gap_size(row, unit)} ({where}, ISO {row['road']})"


def _fidelity(
    model_file: Path,
    plant: str,
    out: Path,
    roads: str,
    controllers: list[Any],
    speed: float,
    duration: float,
    seed: int,
    force: bool,
    car: Any,
    reg: float | None,
    rate: float | None,
) -> None:
    from mrdamper._io import check_output, check_writable, write_files
    from mrdamper.control.loop.closed_loop import resolve_plant
    from mrdamper.control.loop.fidelity import closed_loop_fidelity, failed_runs
    from mrdamper.control.loop.stroke_cells import flag_cells, stroke_note
    from mrdamper.models.registry import load_model

    inputs = _inputs(model_file, plant)
    check_output(out, force=force, folder=True, mode="add", inputs=inputs)
    for name, kind in _FIDELITY_FILES.items():
        check_writable(out / name, force, inputs=inputs, kind=kind)
    m = load_model(model_file)
    res = closed_loop_fidelity(
        m,
        resolve_plant(plant),
        road_classes=[r.strip().upper() for r in roads.split(",") if r.strip()],
        speeds=[speed],
        controllers=controllers,
        duration=duration,
        seed=seed,
        car=car,
        reg=reg,
        rate=rate,
    )
    failed = failed_runs(res)  # a side whose every loop failed: an error, nothing written
    table = flag_cells(res.table(), res.runs_frame())
    texts = {
        "closed_loop.csv": table.to_csv(index=False, float_format="%.6g"),
        "closed_loop_runs.csv": res.runs_frame().to_csv(index=False, float_format="%.6g"),
    }

    write_files(
        out,
        {name: (kind, _text_writer(texts[name])) for name, kind in _FIDELITY_FILES.items()},
        force=force,
    )
    shown = table.assign(metric=[f"{k} [{res.unit(k)}]" for k in table["metric"]]).rename(
        columns={"speed_m_s": "speed [m/s]", "error_pct": "error [%]"}
    )
    typer.echo(shown.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    stroke = stroke_note(table)
    for note in [*res.notes, *([stroke] if stroke else [])]:
        typer.echo(f"warning: {note}", err=True)
    typer.echo(
        f"{m.kind} controller, {res.plant_kind} plant: wrote {', '.join(_FIDELITY_FILES)} in {out}"
    )
    if failed:
        typer.echo(
            f"error: {failed} loop run(s) diverged or were refused (see the warnings and "
            "closed_loop_runs.csv)",
            err=True,
        )
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add the ``quartercar`` command to ``app``."""
    app.command("quartercar")(quartercar)
