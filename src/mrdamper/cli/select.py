"""``mrdamper select DATA...``: which model for my damper?

Cross-validates every model kind on the records in the given files / folders
(:func:`mrdamper.study.cross_validate`: folds by condition or record, time blocks for one
record; folds that leave the training envelope; a stress test of every kind fitted on all the
records), prints the table of left-out free-run ESR and recommends one kind with the reason and
the envelope it was validated in. ``--inside-only`` skips the beyond-envelope folds and the
stress test (faster; the recommendation then rewards interpolation only).
The fits run on ``--workers`` processes (default: the cores), the same table whatever their
number; a kind far above the leader after its first two fits is dropped (successive halving, its
status says so; ``--no-halving`` fits every kind on every fold); ``--time-budget SECONDS`` starts
no fit once the budget has run out and lists the kinds it could not compare.
``--csv`` also writes the table (atomically; never overwriting without ``--force``). On standard
error a line per finished kind; on a terminal also a live line with the fits done, the elapsed
time and an estimate of the time left (``--no-progress`` turns both off).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from mrdamper._io import csv_kind
from mrdamper.cli._modes import refuse_unused
from mrdamper.cli._options import InputChannel, Pattern
from mrdamper.cli._records import reader_options
from mrdamper.cli._status import NoProgress
from mrdamper.errors import DataValidationError
from mrdamper.kinds import kind_list

__all__ = ["SELECTION_CSV", "register", "select"]

#: The kind of file ``select --csv`` writes (``--force`` replaces only such a file).
SELECTION_CSV = csv_kind(
    "table written by 'mrdamper select' (model, mean_esr, ...)", ("model", "mean_esr")
)


def _kind_settings(items: list[str] | None) -> dict[str, dict[str, Any]]:
    """``KIND.KEY=VALUE`` items -> ``{kind: {key: value}}`` (values read as JSON)."""
    from mrdamper.cli.models import parse_settings
    from mrdamper.models import known_kinds

    out: dict[str, dict[str, Any]] = {}
    for item in items or []:
        kind, dot, rest = item.partition(".")
        if not dot or "=" not in rest or not kind:
            raise DataValidationError(
                "--set", f"expected KIND.KEY=VALUE (e.g. lpv.n_m=2), got {item!r}"
            )
        if kind.strip() not in known_kinds():
            raise DataValidationError(
                "--set",
                f"unknown model kind {kind.strip()!r} in {item!r}; expected one of {known_kinds()}",
            )
        out.setdefault(kind.strip(), {}).update(parse_settings([rest]))
    return out


def select(
    ctx: typer.Context,
    data: Annotated[list[Path], typer.Argument(help="Data files or folders (the user's records).")],
    models: Annotated[
        list[str] | None,
        typer.Option(
            "--model",
            "-m",
            help=f"Model kind to include, one of {kind_list()} (repeatable; default: all).",
        ),
    ] = None,
    folds: Annotated[
        str,
        typer.Option(
            "--folds", help="auto | condition | record | time (time: blocks of one record)."
        ),
    ] = "auto",
    n_folds: Annotated[
        int, typer.Option("--n-folds", help="Folds for 'record' (at most) and 'time'.")
    ] = 5,
    input_: InputChannel = None,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set", help="Estimator setting of one kind, KIND.KEY=VALUE (JSON value), repeatable."
        ),
    ] = None,
    inside_only: Annotated[
        bool,
        typer.Option(
            "--inside-only",
            help="Skip the folds beyond the training envelope and the stress test (faster).",
        ),
    ] = False,
    workers: Annotated[
        int | None,
        typer.Option("--workers", help="Worker processes (default: the cores; 1: in-process)."),
    ] = None,
    no_halving: Annotated[
        bool,
        typer.Option(
            "--no-halving",
            help="Fit every kind on every fold (default: drop a kind far above the leader after "
            "its first two fits).",
        ),
    ] = False,
    time_budget: Annotated[
        float | None,
        typer.Option(
            "--time-budget", help="Start no fit after this many seconds; report what was compared."
        ),
    ] = None,
    csv: Annotated[
        Path | None, typer.Option("--csv", help="Also write the table to this CSV file.")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite --csv if it exists.")] = False,
    pattern: Pattern = None,
    no_progress: NoProgress = False,
    for_: Annotated[
        str,
        typer.Option(
            "--for",
            help="fit: rank kinds by free-run error on left-out records; control: by their "
            "fidelity in the quarter-car loop (held-out loop-like records of the control "
            "extension; on virtual-rig records against the true damper).",
        ),
    ] = "fit",
    loop_roads: Annotated[
        str | None,
        typer.Option("--loop-roads", help="--for control: ISO 8608 classes (default B,C,D)."),
    ] = None,
    loop_speeds: Annotated[
        str | None,
        typer.Option("--loop-speeds", help="--for control: speeds [m/s] (default 10,25)."),
    ] = None,
    loop_duration: Annotated[
        float | None,
        typer.Option("--loop-duration", help="--for control: road length [s] (default 10)."),
    ] = None,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Cross-validate every model kind on DATA and recommend one."""
    from mrdamper._io import atomic_write_text, check_writable
    from mrdamper.cli._status import working
    from mrdamper.cli.models import _input_of, read_records
    from mrdamper.study.selection import FOLD_KINDS, HALVING, cross_validate

    if for_ not in ("fit", "control"):
        raise DataValidationError("--for", f"expected fit or control, got {for_!r}")
    refuse_unused(ctx, "select", {f"--for {for_}"})
    if for_ == "control":
        from mrdamper.cli.select_control import select_for_control

        select_for_control(
            data,
            models,
            input_,
            _kind_settings(settings),
            csv,
            force,
            pattern,
            no_progress,
            read_kw,
            (loop_roads, loop_speeds, loop_duration),
        )
        return

    if time_budget is not None and not time_budget > 0:
        raise DataValidationError(
            "--time-budget", f"expected a number of seconds above 0, got {time_budget:g}"
        )
    if workers is not None and workers < 1:
        raise DataValidationError("--workers", f"expected a positive integer, got {workers}")
    if csv is not None:
        check_writable(csv, force=force, inputs=list(data), kind=SELECTION_CSV, option="--csv")
    with working("cross-validating", show=not no_progress):
        records = read_records(data, pattern, read_kw)
        source = _input_of(input_, records)
        fold_kind = next((f for f in FOLD_KINDS if f == folds), None)
        if fold_kind is None:
            raise DataValidationError(
                "--folds", f"expected auto, condition, record or time, got {folds!r}"
            )
        res = cross_validate(
            records,
            models=models,
            folds=fold_kind,
            n_folds=n_folds,
            input=source,
            settings=_kind_settings(settings),
            beyond=not inside_only,
            stress=not inside_only,
            workers=workers,
            halving=None if no_halving else HALVING,
            time_budget=time_budget,
        )
    tab = res.table.reset_index()
    beyond = f" + {res.n_beyond} beyond the training envelope" if res.n_beyond else ""
    typer.echo(
        f"{len(records)} record(s); {res.n_folds} {res.split} folds{beyond}; free-run ESR on the "
        "left-out data\n"
    )
    cols = [
        "model",
        "mean_esr",
        "worst_esr",
        "folds_failed",
        "beyond_esr",
        "rank_esr",
        "clipped",
        "fit_s",
        "status",
    ]
    typer.echo(tab[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}", na_rep="-"))
    for _, row in tab[tab["error"] != ""].iterrows():
        typer.echo(f"  {row['model']}: {row['error']}")
    for fold in dict.fromkeys(res.scores.loc[res.scores["beyond"], "fold"]):
        typer.echo(f"  {fold}")
    for note in res.notes:
        typer.echo(f"note: {note}", err=True)
    typer.echo(f"\nrecommended: {res.recommended or 'none'}: {res.reason}")
    if not (tab["folds_ok"] > 0).any():
        why = "every fit failed in every fold"
        if tab["status"].str.contains("time budget ran out").all():
            why = "the time budget ran out before any fold"
        typer.echo(f"error: {why} (see above); nothing written", err=True)
        raise typer.Exit(1)
    if csv is not None:
        atomic_write_text(csv, tab.to_csv(index=False), force=force, kind=SELECTION_CSV)
        typer.echo(f"wrote {csv}")


def register(app: typer.Typer) -> None:
    """Add the ``select`` command to ``app``."""
    app.command("select")(reader_options()(select))
