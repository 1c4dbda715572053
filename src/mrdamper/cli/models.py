"""``mrdamper fit``, ``mrdamper simulate`` and ``mrdamper score``: models from the command line.

* ``fit MODEL DATA... --out model.json`` identifies any registered model kind on the records in
  the given files / folders and saves it as JSON (never overwriting without ``--force``).
  Options given on the command line become estimator settings; a setting the model does not
  take is an error that lists the settings it does take. ``--choice-records PATH`` (repeatable;
  LPV and LTI) gives records the open settings are chosen on instead of the inner folds
  (``choice_records``; with the default ``stiffness="auto"`` they also decide the LPV model's
  parallel stiffness). On a terminal a live line on standard
  error shows the stage (reading records, then the fit's stages with ``k/N`` where they count)
  and the elapsed time, then ``...: done in X s``; ``--no-progress`` turns it off.
* ``simulate model.json DATA --out predicted.csv`` writes ``t``, measured ``F`` and predicted
  ``F_pred`` [s, N, N] of one record, atomically; ``--interval 0.9`` adds the band's ``F_lower``
  and ``F_upper`` [N] (a model fitted with ``fit --band``, :mod:`mrdamper.uncertainty`).
* ``score model.json DATA... [--json]`` prints ESR and SSSE (paper eqs 24 and 23) per record and
  their mean. A record whose simulation diverges is listed as such; the command then exits 1.
  On a terminal it shows the same live line as ``fit`` (``--no-progress`` turns it off).
"""

from __future__ import annotations

import json
import sys
import typing
from pathlib import Path
from typing import Annotated, Any, cast

import typer

from mrdamper._io import csv_kind
from mrdamper.cli._options import ForceOut, InputChannel, Pattern
from mrdamper.cli._records import read_paths, reader_options
from mrdamper.cli._status import NoProgress
from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models.base import MODEL_FILE, RangePolicy
from mrdamper.models.registry import get_estimator, known_kinds, load_model

__all__ = ["estimator_settings", "parse_settings", "read_records", "register"]

_RANGE_POLICIES: tuple[str, ...] = typing.get_args(RangePolicy)
_INPUTS: tuple[str, ...] = typing.get_args(ElectricalSource)
#: The kind of file ``simulate`` writes (``--force`` replaces only such a file).
SIMULATION_CSV = csv_kind(
    "table written by 'mrdamper simulate' (t, F, F_pred)", ("t", "F", "F_pred")
)


# ----------------------------------------------------------------------------- helpers
def read_records(
    paths: list[Path], pattern: str | None = None, read_kw: dict[str, Any] | None = None
) -> list[Experiment]:
    """Read files and folders into a list of records (folders: ``pattern`` or a default).

    Folders use ``pattern`` when given; otherwise the sine-record pattern if any file name matches
    it (its named groups become metadata), else every CSV / Parquet / MAT file. ``read_kw`` are
    the reader options (see :func:`mrdamper.cli._records.reader_options`).
    """
    out = read_paths(paths, pattern, read_kw or {})
    names = [e.name for e in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise DataValidationError("DATA", f"record names repeat across the inputs: {dup}")
    return out


def estimator_settings(kind: str) -> list[str]:
    """Names of the settings the estimator of ``kind`` accepts."""
    return type(get_estimator(kind)).settings_names()


def parse_settings(items: list[str] | None) -> dict[str, Any]:
    """Parse ``KEY=VALUE`` strings; values are read as JSON (numbers, true/false, null, lists)
    and fall back to plain strings."""
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not key:
            raise DataValidationError("--set", f"expected KEY=VALUE, got {item!r}")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out


def _choose_input(records: list[Experiment]) -> ElectricalSource:
    from mrdamper.data.inspection import common_input

    source = common_input(records)
    if source is not None:
        return source
    raise DataValidationError(
        "--input",
        "the records do not all share one electrical channel ('i' or 'voltage'); choose --input",
    )


def _input_of(input_: str | None, records: list[Experiment]) -> ElectricalSource:
    """The electrical input the models read: ``--input`` when given (checked), else the channel
    every record has."""
    if input_ is None:
        return _choose_input(records)
    if input_ not in _INPUTS:
        raise DataValidationError("--input", f"expected one of {list(_INPUTS)}, got {input_!r}")
    return cast(ElectricalSource, input_)


def _check_policy(policy: str) -> RangePolicy:
    if policy not in _RANGE_POLICIES:
        raise DataValidationError(
            "--range-policy", f"expected one of {list(_RANGE_POLICIES)}, got {policy!r}"
        )
    return cast(RangePolicy, policy)


# ----------------------------------------------------------------------------- commands
def fit(
    model: Annotated[str, typer.Argument(help=f"Model kind: {', '.join(known_kinds())}.")],
    data: Annotated[list[Path], typer.Argument(help="Training data files or folders.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output model file (JSON).")],
    force: ForceOut = False,
    input_: InputChannel = None,
    n_m: Annotated[
        int | None, typer.Option("--n-m", help="Model order of the LPV / LTI model (n_m).")
    ] = None,
    n_rho: Annotated[
        int | None,
        typer.Option("--n-rho", help="Degree of the LPV coefficients in rho (n_rho)."),
    ] = None,
    refine: Annotated[
        bool | None,
        typer.Option("--refine/--no-refine", help="Nonlinear refinement after the linear fit."),
    ] = None,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of any random start.")] = None,
    n_starts: Annotated[
        int | None, typer.Option("--n-starts", help="Number of multi-start runs.")
    ] = None,
    offset: Annotated[
        bool | None, typer.Option("--offset/--no-offset", help="Identify a constant force offset.")
    ] = None,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set", help="Any other estimator setting, KEY=VALUE (JSON value), repeatable."
        ),
    ] = None,
    pattern: Pattern = None,
    choice_records: Annotated[
        list[Path] | None,
        typer.Option(
            "--choice-records",
            help="Held-out records (files or folders, repeatable) on which the open settings "
            "are chosen instead of inner folds of DATA (LPV / LTI: the hysteretic input's stroke "
            "and blend, and with the default stiffness=auto the parallel stiffness).",
        ),
    ] = None,
    no_progress: Annotated[
        bool,
        typer.Option(
            "--no-progress",
            help="No live status line (it is shown on standard error only when that is a "
            "terminal: the stage of the fit, its k/N and the elapsed time).",
        ),
    ] = False,
    band: Annotated[
        bool,
        typer.Option(
            "--band",
            help="Also calibrate a prediction band on held-out residuals (two more fits on halves "
            "of DATA) and store it in the model file (for --interval and the export's W(s)).",
        ),
    ] = False,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Identify MODEL on the records in DATA and save it as JSON."""
    from mrdamper._io import check_writable
    from mrdamper.cli._status import working

    accepted = estimator_settings(model)  # unknown kind: SchemaError naming the known kinds
    inputs = [*data, *(choice_records or [])]
    check_writable(out, force, inputs=inputs, kind=MODEL_FILE)  # fail before a long fit
    estimator_type = type(get_estimator(model))
    if choice_records and "choice_records" not in getattr(estimator_type, "fit_options", ()):
        raise DataValidationError(
            "--choice-records", f"model {model!r} chooses no setting on given records (LPV, LTI do)"
        )
    with working(f"fitting {model}", show=not no_progress) as status:
        records = read_records(list(data), pattern, read_kw)
        options: dict[str, Any] = {}
        if choice_records:
            options["choice_records"] = read_records(list(choice_records), pattern, read_kw)
        given: dict[str, Any] = {
            "input": input_ or _choose_input(records),
            "n_m": n_m,
            "n_rho": n_rho,
            "refine": refine,
            "seed": seed,
            "n_starts": n_starts,
            "offset": offset,
        }
        given = {k: v for k, v in given.items() if v is not None}
        given.update(parse_settings(settings))
        renamed = getattr(estimator_type, "renamed_settings", {})
        unknown = [k for k in given if k not in accepted and k not in renamed]
        if unknown:
            flag = unknown[0].replace("_", "-")
            raise DataValidationError(
                f"--{flag}",
                f"model {model!r} does not take the setting {unknown[0]!r}; its settings are "
                f"{accepted}",
            )
        status.message = (
            f"fitting {model} on {len(records)} record(s), {sum(r.n for r in records)} samples"
        )
        estimator = get_estimator(model, **given)
        if band:
            from mrdamper.uncertainty import fit_with_band

            fitted = fit_with_band(estimator, records, **options)
        else:
            fitted = estimator.fit(records, **options)
    path = fitted.save(out, force=force)
    stiffness = getattr(fitted, "stiffness", 0.0)
    extra = f"; stiffness k_x = {stiffness:.4g} N/m" if stiffness else ""
    if band:
        from mrdamper.uncertainty import band_of

        b = band_of(fitted)
        assert b is not None
        extra += f"; band calibrated on {b.n_samples} held-out samples ({b.method})"
    typer.echo(f"{model}: identified on {len(records)} record(s){extra}; wrote {path}")


def simulate(
    model_file: Annotated[Path, typer.Argument(help="Model file written by 'mrdamper fit'.")],
    data: Annotated[Path, typer.Argument(help="One data file.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output CSV: t, F, F_pred.")],
    force: ForceOut = False,
    range_policy: Annotated[
        str | None,
        typer.Option("--range-policy", help="error | warn | clip | ignore (default: the model's)."),
    ] = None,
    interval: Annotated[
        float | None,
        typer.Option(
            "--interval",
            help="Also write the prediction band at this coverage (0.5-0.99, e.g. 0.9): columns "
            "F_lower, F_upper [N] (the model must have been fitted with --band).",
        ),
    ] = None,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """Free-run simulation of one record; writes t [s], measured F [N] and predicted F_pred [N]
    (with --interval, the band's F_lower and F_upper [N] too)."""
    from mrdamper._io import atomic_write_text, check_writable

    check_writable(out, force, inputs=[model_file, data], kind=SIMULATION_CSV)
    m = load_model(model_file)
    band = None
    if interval is not None:
        from mrdamper.uncertainty import check_level, require_band

        check_level(interval, "--interval")
        band = require_band(m, "--interval")
    if range_policy is not None:
        m = m.with_range_policy(_check_policy(range_policy))
    if data.is_dir():
        raise DataValidationError("DATA", f"{data} is a folder; simulate takes one record file")
    [exp] = read_records([data], read_kw=read_kw)
    res = m.simulate(exp)
    frame = res.to_frame()[["t", "F", "F_pred"]]
    note = ""
    if band is not None and interval is not None:
        lower, upper = band.interval(frame["F_pred"].to_numpy(), interval, exp.dt)
        frame = frame.assign(F_lower=lower, F_upper=upper)
        measured = frame["F"].to_numpy()
        inside = float(((measured >= lower) & (measured <= upper)).mean())
        note = f", {inside:.1%} of F inside the {interval:g} band"
    path = atomic_write_text(
        out, frame.to_csv(index=False, float_format="%.10g"), force=force, kind=SIMULATION_CSV
    )
    s = res.scores
    typer.echo(f"{exp.name}: ESR {s.esr:.4g}, SSSE {s.ssse:.4g} N{note}; wrote {path}")


def score(
    model_file: Annotated[Path, typer.Argument(help="Model file written by 'mrdamper fit'.")],
    data: Annotated[list[Path], typer.Argument(help="Data files or folders.")],
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
    range_policy: Annotated[
        str | None,
        typer.Option("--range-policy", help="error | warn | clip | ignore (default: the model's)."),
    ] = None,
    pattern: Pattern = None,
    no_progress: NoProgress = False,
    read_kw: dict[str, Any] | None = None,
) -> None:
    """ESR and SSSE of the model's free-run prediction for each record, and their mean."""
    from mrdamper.cli._status import working
    from mrdamper.progress import report

    m = load_model(model_file)
    if range_policy is not None:
        m = m.with_range_policy(_check_policy(range_policy))
    rows: list[dict[str, Any]] = []
    with working(f"scoring {m.kind}", show=not no_progress):
        records = read_records(list(data), pattern, read_kw)
        for k, e in enumerate(records):
            report("simulating records", k, len(records))
            try:
                s = m.score(e)
                rows.append({"record": e.name, "esr": s.esr, "ssse": s.ssse})
            except SimulationDivergedError as exc:
                rows.append(
                    {"record": e.name, "esr": None, "ssse": None, "diverged_at_sample": exc.sample}
                )
    ok = [r for r in rows if r["esr"] is not None]
    mean = {
        "esr": sum(r["esr"] for r in ok) / len(ok) if ok else None,
        "ssse": sum(r["ssse"] for r in ok) / len(ok) if ok else None,
        "n_scored": len(ok),
        "n_diverged": len(rows) - len(ok),
    }
    result = {"model": m.kind, "model_file": str(model_file), "records": rows, "mean": mean}
    if as_json:
        typer.echo(json.dumps(result, indent=2))
    else:
        _print_scores(result)
    if mean["n_diverged"]:
        sys.exit(1)


def _print_scores(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(f"{result['model']}: {result['model_file']}"))
    table.add_column("record")
    table.add_column("ESR [-]", justify="right")
    table.add_column("SSSE [N]", justify="right")
    for r in result["records"]:
        if r["esr"] is None:
            table.add_row(escape(r["record"]), f"diverged at sample {r['diverged_at_sample']}", "-")
        else:
            table.add_row(escape(r["record"]), f"{r['esr']:.4g}", f"{r['ssse']:.4g}")
    mean = result["mean"]
    label = f"mean of {mean['n_scored']}" + (
        f" ({mean['n_diverged']} diverged)" if mean["n_diverged"] else ""
    )
    table.add_row(
        escape(label),
        "-" if mean["esr"] is None else f"{mean['esr']:.4g}",
        "-" if mean["ssse"] is None else f"{mean['ssse']:.4g}",
        style="bold",
    )
    Console(width=120).print(table)


def register(app: typer.Typer) -> None:
    """Add the ``fit``, ``simulate`` and ``score`` commands to ``app``."""
    app.command("fit")(reader_options()(fit))
    app.command("simulate")(reader_options()(simulate))
    app.command("score")(reader_options()(score))
