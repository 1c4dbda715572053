"""``mrdamper export`` and ``mrdamper inverse``: hand an identified model to control design.

* ``export MODEL.json --out FILE [--format mat|json] [--force]`` writes the LPV / LTI model's
  matrices (see :mod:`mrdamper.control.export.matrices`); other model kinds are refused with one
  line.
* ``export MODEL.json --format c --out DIR`` writes C99 code of the model and its inverse
  (:mod:`mrdamper.control.export.c_export`).
* ``export MODEL.json --format fmu --out damper.fmu [--inverse] [--dt S]`` writes an FMI 2.0
  co-simulation FMU of the model or of its inverse (:mod:`mrdamper.control.export.fmu`).
* ``inverse MODEL.json DATA --out FILE`` answers "which current would have produced this
  force": the record's measured force ``F`` is the desired force, its motion the motion. Writes
  ``t, F_desired, <input>, F_achieved, saturated`` [s, N, A|V, N, 0/1] as CSV, atomically.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from mrdamper._io import csv_kind
from mrdamper.cli._help import kinds_text
from mrdamper.cli._modes import refuse_unused
from mrdamper.cli._options import ForceOut
from mrdamper.cli._records import reader_options
from mrdamper.errors import DataValidationError

__all__ = ["INVERSE_CSV", "register"]

#: The kind of file ``inverse`` writes (``--force`` replaces only such a file).
INVERSE_CSV = csv_kind(
    "table written by 'mrdamper inverse' (t, F_desired, ...)", ("t", "F_desired")
)
#: The formats of ``export`` (the first two: the state-space matrices of :data:`STATE_SPACE`).
FORMATS = ("mat", "json", "c", "fmu")
#: The kinds whose matrices ``--format mat|json`` writes.
STATE_SPACE = ("lpv", "lti")


def export(
    ctx: typer.Context,
    model_file: Annotated[
        Path,
        typer.Argument(
            help=f"Model file written by 'mrdamper fit': any kind ({kinds_text()}) for --format "
            f"c and fmu; {' or '.join(STATE_SPACE)} for {' and '.join(FORMATS[:2])}."
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            "--out", "-o", help="Output file (.mat, .json or .fmu), or folder for --format c."
        ),
    ],
    fmt: Annotated[
        str | None,
        typer.Option(
            "--format", help=f"{' | '.join(FORMATS)} (default: from the --out suffix, else mat)."
        ),
    ] = None,
    name: Annotated[
        str | None,
        typer.Option(
            "--name",
            help=(
                "C identifier prefix and file stem (--format c, default mrd_damper; --format fmu:"
                " the model identifier, default the --out stem)."
            ),
        ),
    ] = None,
    reg: Annotated[
        float | None,
        typer.Option(
            "--reg",
            help="Inverse regularisation weight [N/A] (--format c; default from the model).",
        ),
    ] = None,
    dt: Annotated[
        float | None,
        typer.Option(
            "--dt",
            help=(
                "Sample time [s] of a Spencer, P-15, tanh, Bouc-Wen, Dahl or LuGre model's C "
                "step and of their or a static map's FMU (default: the sample time the model "
                "was fitted at, recorded in the model file; LPV, LTI and NARX models run at "
                "their own rate)."
            ),
        ),
    ] = None,
    inverse: Annotated[
        bool, typer.Option("--inverse", help="FMU of the model's inverse (--format fmu).")
    ] = False,
    force: ForceOut = False,
) -> None:
    """Write the LPV model's matrices A(rho), B, C(rho), D, grid poles and zone laws
    for control design, (--format c) C99 code of the model and its inverse, or (--format fmu) an
    FMI 2.0 co-simulation FMU of the model or its inverse."""
    from mrdamper._io import check_output, check_writable
    from mrdamper.control.export.matrices import EXPORT_FILE, export_lpv
    from mrdamper.models.registry import load_model

    if fmt is None:
        fmt = {".json": "json", ".fmu": "fmu"}.get(out.suffix.lower(), "mat")
    if fmt not in FORMATS:
        raise DataValidationError("--format", f"expected one of {list(FORMATS)}, got {fmt!r}")
    forward_fmu = fmt == "fmu" and not inverse  # the mode "--format fmu": no inverse in it
    refuse_unused(ctx, "export", {f"--format {fmt}"} if fmt != "fmu" or forward_fmu else set())
    if fmt == "fmu":
        from mrdamper.control.export.fmu import FMU_FILE, export_fmu

        check_writable(out, force, inputs=[model_file], kind=FMU_FILE)
        m = load_model(model_file)
        ident = name or (out.stem if out.stem.isidentifier() else "mrd_damper")
        path = export_fmu(m, out, name=ident, inverse=inverse, dt=dt, reg=reg, force=force)
        typer.echo(
            f"{m.kind}: wrote {path} (FMI 2.0 co-simulation{', inverse' if inverse else ''})"
        )
        return
    if fmt == "c":
        from mrdamper.control.export.c_export import export_c, needs_dt
        from mrdamper.control.export.fmu import training_dt

        check_output(out, force=force, folder=True, mode="add", inputs=[model_file])
        m = load_model(model_file)
        c_dt = dt if dt is not None or not needs_dt(m) else training_dt(m)
        h, c = export_c(m, out, name=name or "mrd_damper", reg=reg, dt=c_dt, force=force)
        typer.echo(f"{m.kind}: wrote {h} and {c} (C99)")
        return
    check_writable(out, force, inputs=[model_file], kind=EXPORT_FILE)
    m = load_model(model_file)
    if m.kind not in STATE_SPACE:
        raise DataValidationError(
            "MODEL",
            f"{model_file} holds a {m.kind!r} model; --format {fmt} writes the state-space "
            f"models {' and '.join(map(repr, STATE_SPACE))} (--format c and fmu take every kind)",
        )
    path = export_lpv(m, out, format="json" if fmt == "json" else "mat", force=force)
    from mrdamper.uncertainty import band_of, uncertainty_weights

    weights = (
        f"uncertainty weight W(s) at {len(uncertainty_weights(m))} input level(s)"
        if band_of(m) is not None
        else "no band stored, so no uncertainty weight W(s) (fit with --band)"
    )
    typer.echo(f"{m.kind}: wrote {path} ({fmt}; {weights})")


def inverse(
    ctx: typer.Context,
    model_file: Annotated[
        Path,
        typer.Argument(help="Model file (any kind; without an inverse form: through its step)."),
    ],
    data: Annotated[
        Path, typer.Argument(help="One record file; its force column F is the desired force.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output CSV.")],
    force: ForceOut = False,
    method: Annotated[str, typer.Option("--method", help="regularised | exact.")] = "regularised",
    reg: Annotated[
        float | None,
        typer.Option("--reg", help="Regularisation weight [N/A] (default from the model)."),
    ] = None,
    rate: Annotated[float | None, typer.Option("--rate", help="Input rate bound [A/s].")] = None,
    horizon: Annotated[
        float | None,
        typer.Option(
            "--horizon",
            help=(
                "Lead horizon [s] of an LPV model with a drive lag (default 1/eta; 0: present "
                "sample only)."
            ),
        ),
    ] = None,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Current that would have produced the record's measured force (causal inverse of the model).

    Prints the force error and, when the record has the model's electrical input, the median input
    error over |v| > 20 % of its peak and the forward model's SSSE with the measured and with the
    recovered input."""
    from mrdamper._io import atomic_write_text, check_writable
    from mrdamper.cli.models import read_records
    from mrdamper.control.inverse.current import inverse_current
    from mrdamper.models.registry import load_model

    refuse_unused(ctx, "inverse", {f"--method {method}"})
    check_writable(out, force, inputs=[model_file, data], kind=INVERSE_CSV)
    m = load_model(model_file)
    if data.is_dir():
        raise DataValidationError("DATA", f"{data} is a folder; inverse takes one record file")
    [exp] = read_records([data], read_kw=read_kw)
    try:
        res = inverse_current(m, exp, exp.F, method=method, reg=reg, rate=rate, horizon=horizon)
    except TypeError as exc:
        raise DataValidationError("MODEL", str(exc)) from exc
    frame = res.to_frame()[["t", "F_desired", res.input, "F_achieved", "saturated"]].copy()
    frame["saturated"] = frame["saturated"].astype(int)
    path = atomic_write_text(
        out, frame.to_csv(index=False, float_format="%.10g"), force=force, kind=INVERSE_CSV
    )
    err = res.error
    rms = float((err**2).mean() ** 0.5)
    typer.echo(
        f"{exp.name}: {m.kind} inverse ({method}), RMS force error {rms:.4g} N, "
        f"{100 * res.saturated_fraction:.1f} % of samples saturated; wrote {path}"
    )
    if m.input in exp.channel_names:
        from mrdamper.control.inverse.inverse_check import check_inverse

        chk = check_inverse(m, exp, method=method, reg=reg, rate=rate, horizon=horizon)
        unit = "A" if m.input == "i" else "V"
        typer.echo(
            f"  median |{m.input} error| over |v| > 20 % of peak: {chk.median_input_error:.4g} "
            f"{unit}; SSSE with measured {m.input}: {chk.ssse_model:.4g} N, with inverse "
            f"{m.input}: {chk.ssse_inverse:.4g} N (ratio {chk.ssse_ratio:.3g})"
        )


def register(app: typer.Typer) -> None:
    """Add the ``export`` and ``inverse`` commands to ``app``."""
    app.command("export")(export)
    app.command("inverse")(reader_options()(inverse))
