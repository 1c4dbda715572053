"""``mrdamper select DATA --for control``: which model kind for a controller.

Ranks the kinds by their fidelity in the quarter-car loop (:mod:`mrdamper.study.control_select`):
each kind is fitted once on DATA less a held-out half of the control extension's loop-like
records; on virtual-rig records (whose damper is known) every controller runs on ISO 8608 roads
with the model and with the true damper, and the kind's score is the worst |error| [%] over the
loop metrics in the cells within its training stroke; on measured records the score is the
free-run ESR on the held-out loop-like records. Prints the table (and writes it with ``--csv``)
and recommends the first kind.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from mrdamper._io import csv_kind
from mrdamper.errors import DataValidationError

__all__ = ["CONTROL_SELECTION_CSV", "select_for_control"]

#: The kind of file ``select --for control --csv`` writes.
CONTROL_SELECTION_CSV = csv_kind(
    "table written by 'mrdamper select --for control' (model, rank, ...)", ("model", "rank")
)


def _loop(roads: str | None, speeds: str | None, duration: float | None) -> dict[str, Any]:
    """The closed-loop check's settings from the options (defaults where not given)."""
    from mrdamper.study import control_select as cs

    out: dict[str, Any] = {
        "roads": cs.ROADS,
        "speeds": cs.SPEEDS,
        "duration": cs.DURATION,
    }
    if roads is not None:
        out["roads"] = tuple(r.strip().upper() for r in roads.split(",") if r.strip())
    if speeds is not None:
        try:
            out["speeds"] = tuple(float(s) for s in speeds.split(",") if s.strip())
        except ValueError:
            raise DataValidationError(
                "--loop-speeds", f"expected speeds [m/s] separated by commas, got {speeds!r}"
            ) from None
    if duration is not None:
        if not duration >= 2.0:
            raise DataValidationError(
                "--loop-duration", f"expected a road length >= 2 s, got {duration:g}"
            )
        out["duration"] = float(duration)
    return out


def select_for_control(
    data: list[Path],
    models: list[str] | None,
    input_: str | None,
    settings: dict[str, dict[str, Any]],
    csv: Path | None,
    force: bool,
    pattern: str | None,
    no_progress: bool,
    read_kw: dict[str, Any] | None,
    loop: tuple[str | None, str | None, float | None],
) -> None:
    """The ``--for control`` mode of ``mrdamper select`` (options as there)."""
    from mrdamper._io import atomic_write_text, check_writable
    from mrdamper.cli._status import working
    from mrdamper.cli.models import _choose_input, read_records
    from mrdamper.models import known_kinds
    from mrdamper.study.control_select import control_select

    kinds = list(models) if models else known_kinds()
    for k in kinds:
        if k not in known_kinds():
            raise DataValidationError(
                "--model", f"unknown kind {k!r}; expected one of {known_kinds()}"
            )
    checks = _loop(*loop)
    if csv is not None:
        check_writable(
            csv, force=force, inputs=list(data), kind=CONTROL_SELECTION_CSV, option="--csv"
        )
    with working("ranking kinds in the loop", show=not no_progress):
        records = read_records(data, pattern, read_kw)
        source = input_ or _choose_input(records)
        res = control_select(records, kinds, input=source, settings=settings, **checks)
    how = (
        f"closed loop against the true damper ({res.truth}): ISO "
        f"{', '.join(checks['roads'])} at {', '.join(f'{s:g}' for s in checks['speeds'])} m/s, "
        f"{checks['duration']:g} s roads; worst |error| [%] of a_w, RMS acceleration, tyre load, "
        "travel and tracking over the cells within the training stroke"
        if res.truth is not None
        else "free-run ESR on the held-out loop-like records"
    )
    typer.echo(
        f"{len(records)} record(s), {len(res.held_out)} loop-like held out; ranked by the {how}\n"
    )
    tab = res.table
    typer.echo(tab.to_string(index=False, float_format=lambda x: f"{x:.4g}", na_rep="-"))
    for note in res.notes:
        typer.echo(f"note: {note}", err=True)
    typer.echo(f"\nrecommended for control: {res.recommended or 'none'}")
    if res.recommended is None:
        typer.echo("error: no kind could be scored (see above); nothing written", err=True)
        raise typer.Exit(1)
    if csv is not None:
        atomic_write_text(csv, tab.to_csv(index=False), force=force, kind=CONTROL_SELECTION_CSV)
        typer.echo(f"wrote {csv}")
