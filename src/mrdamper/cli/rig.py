"""``mrdamper rig``: the virtual test rig from the command line.

``mrdamper rig doe --out DIR [--seed N] [--scale S] [--fs HZ] [--damper NAME|FILE] [--workers W]
[--force]``
generates the paper's Table II design of experiments and writes one CSV per record plus
``manifest.csv``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from mrdamper.errors import DataValidationError

__all__ = ["register", "rig_app"]

rig_app = typer.Typer(
    help="Virtual test rig: generate the paper's design of experiments.", no_args_is_help=True
)


def _damper(spec: str | None):  # type: ignore[no-untyped-def]
    from mrdamper.models.registry import load_model
    from mrdamper.rig.reference import REFERENCE_DAMPERS, reference_damper

    if spec is None:
        return None
    if spec in REFERENCE_DAMPERS:
        return reference_damper(spec)
    path = Path(spec)
    if path.suffix.lower() == ".json" or path.exists():
        return load_model(path)
    raise DataValidationError(
        "--damper", f"expected a reference damper name {list(REFERENCE_DAMPERS)} or a model JSON file, got {spec!r}"
    )


@rig_app.command("doe")
def doe(
    out: Annotated[Path, typer.Option("--out", help="Output folder (must be absent or empty unless --force).")],
    seed: Annotated[int, typer.Option("--seed", min=0, help="Root seed; the same seed gives byte-identical files.")] = 0,
    scale: Annotated[float, typer.Option("--scale", help="Duration factor (0.1: 3 s and 60 s records).")] = 1.0,
    fs: Annotated[float, typer.Option("--fs", help="Sampling rate [Hz].")] = 1000.0,
    damper: Annotated[
        str | None,
        typer.Option("--damper", help="Reference damper name (quiroz2022, spencer1997) or a model JSON file."),
    ] = None,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Worker processes (same files for any number).")] = 1,
    force: Annotated[bool, typer.Option("--force", help="Write into a non-empty folder, overwriting.")] = False,
) -> None:
    """Generate the paper's Table II DoE on the virtual rig and write CSV files + manifest.csv."""
    from mrdamper._io import check_output
    from mrdamper.rig.doe import table_ii
    from mrdamper.rig.doe_io import write_records

    check_output(out, force=force, folder=True, inputs=[damper] if damper and Path(damper).exists() else [])
    t0 = time.perf_counter()
    records = table_ii(seed=seed, scale=scale, fs=fs, damper=_damper(damper), workers=workers)
    t1 = time.perf_counter()
    manifest = write_records(records, out, force=force)
    t2 = time.perf_counter()
    samples = sum(r.n for r in records)
    typer.echo(
        f"{len(records)} records, {samples} samples ({samples / fs:g} s at {fs:g} Hz), "
        f"seed {seed}, scale {scale:g}: generated in {t1 - t0:.1f} s, written in {t2 - t1:.1f} s"
    )
    typer.echo(f"manifest: {manifest}")


def register(app: typer.Typer) -> None:
    """Add the ``rig`` command group to ``app``."""
    app.add_typer(rig_app, name="rig")
