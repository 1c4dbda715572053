"""Closed-loop fidelity benchmark: each model kind's predicted loop metrics against the true damper.

For each reference damper of the virtual rig, the Table II design of experiments is generated on
it, every model kind is identified with defaults on it, and
:func:`mrdamper.control.loop.fidelity.closed_loop_fidelity` runs the five controllers on ISO 8608
roads at two speeds with the model as the damper (predicted) and with the reference damper as the
damper (achieved), same controller and inverse. A kind that cannot be fitted, stepped or inverted
keeps a row with its one-line reason. Writes ``OUT/closed_loop_<damper>.csv`` (all rows),
``OUT/closed_loop_runs_<damper>.csv`` and ``OUT/closed_loop_summary_<damper>.csv``, and prints the
worst |error| [%] per kind and metric, then per kind and controller in the layout of
``docs/results.md`` (worst over the roads, class C in brackets, tracking and mean current).

Run (the full benchmark takes hours on one core; ``--scale`` shortens the DoE records,
``--duration`` the roads)::

    PYTHONPATH=src python3 benchmarks/closed_loop.py --out bench-cl
    PYTHONPATH=src python3 benchmarks/closed_loop.py --out bench-cl --scale 0.1 --duration 6 \\
        --kinds sp1,spencer --roads C --speeds 20
    PYTHONPATH=src python3 benchmarks/closed_loop.py --out bench-cl-ext --extension ...
"""

from __future__ import annotations

import argparse
import time
import warnings
from functools import partial
from pathlib import Path
from typing import Any

import pandas as pd

from mrdamper.control.loop.doe_extension import control_extension, first_model
from mrdamper.control.loop.fidelity import MAX_SUBSTEPS, closed_loop_fidelity, input_unit
from mrdamper.control.loop.fronts import gain_fronts
from mrdamper.errors import MrDamperError
from mrdamper.models.lag import lag_setting
from mrdamper.models.lpv.estimator import outer_slope_choices
from mrdamper.models.registry import get_estimator, known_kinds, takes_lag
from mrdamper.rig.doe import table_ii
from mrdamper.rig.doe_control import HIGHPASS
from mrdamper.rig.reference import REFERENCE_DAMPERS, reference_damper


def _write(out: Path, name: str, tables: list, runs: list, failed: list) -> None:
    """Write what is done so far (after every kind: a long run keeps its finished kinds)."""
    if tables:
        table = pd.concat(tables, ignore_index=True)
        table.to_csv(out / f"closed_loop_{name}.csv", index=False, float_format="%.6g")
        pd.concat(runs, ignore_index=True).to_csv(
            out / f"closed_loop_runs_{name}.csv", index=False, float_format="%.6g"
        )
    pd.DataFrame(failed, columns=["kind", "reason"]).to_csv(
        out / f"closed_loop_failed_{name}.csv", index=False
    )


def training_records(
    truth: Any, scale: float, *, highpass: float = HIGHPASS, first: str = "sp1"
) -> tuple[list, list, list]:
    """Table II on ``truth`` at ``scale`` and the control extension: ``(table_ii, extension,
    held_out)``, the extension (seed 1) replaying the loops of a ``first`` model fitted on Table II
    and the held-out extension (seed 2) on which the LPV model's stroke and blend are chosen."""
    doe = list(table_ii(seed=0, scale=scale, damper=truth))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = first_model(doe, first, input=truth.input)
    extension = partial(
        control_extension, scale=scale, damper=truth, model=model, highpass=highpass
    )
    return doe, list(extension(seed=1)), list(extension(seed=2))


#: The four loop metrics of the per-controller summary, in its order.
SUMMARY_METRICS = ("a_w", "rms_acc", "rms_tyre_load", "rms_travel")


def controller_summary(table: pd.DataFrame, runs: pd.DataFrame, unit: str = "A") -> pd.DataFrame:
    """Per kind and controller: the worst |error| [%] over the roads of ``a_w`` / RMS
    acceleration / RMS tyre load / RMS travel (class C alone in brackets), the worst RMS
    tracking and mean-current errors (with the worst mean-input gap in milli-``unit``, the
    damper's input unit), and the runs the halving check refused or that diverged, as
    ``docs/results.md`` tabulates them."""
    t = table.assign(abs_err=table["error_pct"].abs())
    refused = runs[runs["refused"].notna()] if "refused" in runs else runs.iloc[:0]
    rows = []
    for (kind, ctrl), d in t.groupby(["kind", "controller"], sort=False):
        worst = d.groupby("metric")["abs_err"].max()
        on_c = d[d["road"] == "C"].groupby("metric")["abs_err"].max()

        def cells(s: pd.Series) -> str:
            return " / ".join(f"{s.get(m, float('nan')):.1f}" for m in SUMMARY_METRICS)

        text = f"{cells(worst)} ({cells(on_c)})"
        if (
            d["metric"].eq("rms_tracking").any()
            and d.loc[d["metric"] == "rms_tracking", "error_pct"].notna().any()
        ):
            text += (
                f"; tracking {worst.get('rms_tracking', float('nan')):.1f}, "
                f"current {worst.get('mean_current', float('nan')):.1f}{_current_gap(d, unit)}"
            )
        n_ref = int(((refused["kind"] == kind) & (refused["controller"] == ctrl)).sum())
        if n_ref:
            text += f"; {n_ref} run(s) refused or diverged"
        rows.append({"kind": kind, "controller": ctrl, "worst [%]": text})
    return pd.DataFrame(rows)


def _current_gap(rows: pd.DataFrame, unit: str) -> str:
    """Where the table has the values: the mean-input gap of the worst row in milli-``unit``,
    against the achieved mean (a relative error on a mean of a few mA says little)."""
    cur = rows[(rows["metric"] == "mean_current") & rows["abs_err"].notna()]
    if cur.empty or not {"predicted", "achieved"} <= set(cur.columns):
        return ""
    at = cur.loc[cur["abs_err"].idxmax()]
    gap = 1e3 * abs(at["predicted"] - at["achieved"])
    return f" ({gap:.1f} of {1e3 * at['achieved']:.1f} m{unit})"


#: What :func:`front_summary` prints.
FRONT_HEADER = (
    "worst |predicted - achieved| / achieved [%] of a_w / tyre load / travel / mean current, "
    "over every gain and at the gain chosen on the model"
)


def front_summary(fronts: pd.DataFrame, chosen: pd.DataFrame) -> pd.DataFrame:
    """Per kind and controller (passive: the front of constant inputs), the worst |error| [%]
    over the gain sweep of each metric, the gains where ``a_w``, tyre load or travel is worst
    (not the mean current, whose relative error is large where it is near 0), how many points were
    refused (by the halving check, on either side), and the worst |error| at the gain chosen on
    the model (``FrontsResult.chosen``) of ``a_w``, tyre load and travel."""
    metrics = ("a_w", "rms_tyre_load", "rms_travel", "mean_current")
    rows = []
    f = fronts.assign(abs_err=fronts["error_pct"].abs())
    for (kind, ctrl), d in f.groupby(["kind", "controller"], sort=False):
        worst = d.groupby("metric")["abs_err"].max()
        mech = d[d["metric"] != "mean_current"]["abs_err"]  # small means make large ratios
        at = d.loc[mech.idxmax()] if mech.notna().any() else None
        where = (
            "-"
            if at is None
            else ", ".join(
                f"{k} {at[k]:g}" for k in ("level", "c_sky", "c_ground", "alpha") if pd.notna(at[k])
            )
        )
        points = d[d["metric"] == "a_w"]
        row = {
            "kind": kind,
            "controller": ctrl,
            "over the sweep": " / ".join(f"{worst.get(m, float('nan')):.1f}" for m in metrics),
            "worst at": where,
            "refused": int(points["error_pct"].isna().sum()),
            "chosen gain": "-",
            "at the chosen gain": "-",
        }
        c = chosen[(chosen["kind"] == kind) & (chosen["controller"] == ctrl)]
        if len(c):
            errs = []
            for m in metrics[:3]:
                p, q = c[f"{m}_predicted"], c[f"{m}_achieved"]
                errs.append(float((100 * (p - q) / q).abs().max()))
            gains = c.iloc[0]
            row["chosen gain"] = ", ".join(
                f"{k} {gains[k]:g}" for k in ("c_sky", "c_ground", "alpha") if pd.notna(gains[k])
            )
            row["at the chosen gain"] = " / ".join(f"{e:.1f}" for e in errs)
        rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--dampers", default=",".join(REFERENCE_DAMPERS))
    ap.add_argument("--kinds", default=",".join(known_kinds()))
    ap.add_argument("--roads", default="B,C,D")
    ap.add_argument("--speeds", default="10,25")
    ap.add_argument("--controllers", default="soft,hard,skyhook,groundhook,hybrid")
    ap.add_argument("--scale", type=float, default=1.0, help="DoE duration factor [-]")
    ap.add_argument("--duration", type=float, default=20.0, help="road length [s]")
    ap.add_argument("--seed", type=int, default=0, help="road profile seed")
    ap.add_argument(
        "--max-substeps",
        type=int,
        default=MAX_SUBSTEPS,
        help="finest plant step [steps per road sample]",
    )
    ap.add_argument(
        "--extension",
        action="store_true",
        help="train on Table II + the control-oriented extension (control.doe_extension: the "
        "loop of a first model fitted on Table II, replayed on the rig); the LPV model's stroke "
        "and blend are then chosen on held-out extension records (seed 2; the fit option "
        "choice_records)",
    )
    ap.add_argument(
        "--lpv-fs",
        type=float,
        default=None,
        help="LPV model rate [Hz] (default: the record rate); records are up-sampled to it",
    )
    ap.add_argument(
        "--lpv-outer-slopes",
        choices=outer_slope_choices(),
        default=None,
        help="the LPV zone laws' outer slopes (default: the estimator's)",
    )
    ap.add_argument("--lpv-stroke", type=float, default=None, help="LPV stroke scale [m] (fixed)")
    ap.add_argument(
        "--lpv-stiffness",
        default=None,
        help="LPV parallel stiffness: 'identify' or a fixed value [N/m] (default: the estimator's)",
    )
    ap.add_argument("--lpv-blend", type=float, default=None, help="LPV pre-yield share [-] (fixed)")
    ap.add_argument(
        "--fronts",
        action="store_true",
        help="also sweep every controller's gains (control.fronts.gain_fronts) with each model "
        "and with the true damper: fronts_<damper>.csv has predicted against achieved at every "
        "gain, and the worst |error| over the sweep and at the gains chosen on the model print",
    )
    ap.add_argument(
        "--eta",
        default=None,
        help="lag setting of every kind that has one ('auto', 'identify' or a rate [1/s]; "
        "default: the estimator's, 'auto')",
    )
    ap.add_argument(
        "--highpass",
        type=float,
        default=HIGHPASS,
        help="high-pass corner of the extension's replayed travel [Hz] (default: the "
        "extension's, mrdamper.rig.doe_control.HIGHPASS)",
    )
    ap.add_argument(
        "--first",
        default="sp1",
        help="kind of the first model (fitted on Table II) whose loop gives the extension",
    )
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    speeds = [float(s) for s in a.speeds.split(",")]
    # the roads and the halving check of every loop run: the fidelity runs and the gain sweep
    loop = {
        "road_classes": a.roads.split(","),
        "speeds": speeds,
        "duration": a.duration,
        "seed": a.seed,
        "max_substeps": a.max_substeps,
    }
    for name in a.dampers.split(","):
        truth = reference_damper(name)
        t0 = time.perf_counter()
        held_out: list = []
        if not a.extension:
            doe = list(table_ii(seed=0, scale=a.scale, damper=truth))
        else:
            doe, ext, held_out = training_records(
                truth, a.scale, highpass=a.highpass, first=a.first
            )
            rig_s = [sum(r.n for r in recs) * r0.dt for recs, r0 in ((doe, doe[0]), (ext, ext[0]))]
            print(f"{name}: rig time Table II {rig_s[0]:.0f} s + extension {rig_s[1]:.0f} s")
            doe = doe + ext
        print(f"{name}: DoE {time.perf_counter() - t0:.0f} s")
        tables, runs, failed = [], [], []
        fronts: list[pd.DataFrame] = []
        chosen: list[pd.DataFrame] = []
        for kind in a.kinds.split(","):
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    lpv_settings = {"model_fs": a.lpv_fs} if kind == "lpv" and a.lpv_fs else {}
                    if kind == "lpv" and a.lpv_outer_slopes:
                        lpv_settings["outer_slopes"] = a.lpv_outer_slopes
                    if kind == "lpv" and a.lpv_stroke is not None:
                        lpv_settings["stroke"] = a.lpv_stroke
                    if kind == "lpv" and a.lpv_blend is not None:
                        lpv_settings["blend"] = a.lpv_blend
                    if kind == "lpv" and a.lpv_stiffness is not None:
                        k = a.lpv_stiffness
                        lpv_settings["stiffness"] = k if k == "identify" else float(k)
                    settings = dict(lpv_settings)
                    if a.eta is not None and takes_lag(kind):
                        settings["eta"] = lag_setting(a.eta)
                    if kind == "lpv" and held_out:  # stroke and blend scored on held_out
                        est = get_estimator(
                            kind, input=truth.input, choose_on="held-out", **settings
                        )
                        model = est.fit(doe, choice_records=held_out)
                        print(f"{name} lpv: {model.provenance['hysteretic_note']}")
                    else:
                        model = get_estimator(kind, input=truth.input, **settings).fit(doe)
                    if "drive_lag" in model.provenance:
                        print(f"{name} {kind}: lag eta = {model.eta:g} 1/s identified")
                    if getattr(model, "stiffness", 0.0):
                        print(f"{name} {kind}: stiffness k_x = {model.stiffness:.0f} N/m")
                    run = partial(closed_loop_fidelity, model, truth, **loop)
                    try:
                        res = run(controllers=a.controllers.split(","))
                    except MrDamperError as exc:  # no inverse: the passive controllers only
                        passive = [c for c in a.controllers.split(",") if c in ("soft", "hard")]
                        if "invers" not in str(exc) or not passive:
                            raise
                        failed.append({"kind": kind, "reason": f"semi-active: {exc}"})
                        res = run(controllers=passive)
            except Exception as exc:  # noqa: BLE001 - a failing kind keeps its row and reason
                failed.append({"kind": kind, "reason": f"{type(exc).__name__}: {exc}"})
                print(f"{name} {kind}: {failed[-1]['reason']}")
                _write(a.out, name, tables, runs, failed)
                continue
            if a.fronts:
                t1 = time.perf_counter()
                sweep = gain_fronts(model, truth, **loop)
                fronts.append(sweep.fidelity().assign(kind=kind))
                chosen.append(sweep.chosen().assign(kind=kind))
                print(f"{name} {kind}: gain sweep {time.perf_counter() - t1:.0f} s")
            tables.append(res.table().assign(kind=kind))
            runs.append(res.runs_frame().assign(kind=kind))
            for note in res.notes[:3]:
                print(f"{name} {kind}: warning: {note}")
            print(f"{name} {kind}: {time.perf_counter() - t0:.0f} s")
            _write(a.out, name, tables, runs, failed)
            if fronts:
                pd.concat(fronts, ignore_index=True).to_csv(
                    a.out / f"fronts_{name}.csv", index=False, float_format="%.6g"
                )
        if fronts:
            print(f"\n{name}: over each controller's gain sweep, " + FRONT_HEADER)
            print(front_summary(pd.concat(fronts), pd.concat(chosen)).to_string(index=False))
        if not tables:
            continue
        table = pd.concat(tables, ignore_index=True)
        worst = (
            table.assign(abs_err=table["error_pct"].abs())
            .pivot_table(index="kind", columns="metric", values="abs_err", aggfunc="max")
            .round(1)
        )
        print(f"\n{name}: worst |predicted - achieved| / achieved [%] over controllers and roads")
        print(worst.to_string())
        summary = controller_summary(table, pd.concat(runs, ignore_index=True), input_unit(truth))
        summary.to_csv(a.out / f"closed_loop_summary_{name}.csv", index=False)
        print(
            f"\n{name}: per controller, worst over the roads of a_w / RMS acc. / tyre load / "
            "travel [%] (class C in brackets)"
        )
        print(summary.to_string(index=False))


if __name__ == "__main__":
    main()
