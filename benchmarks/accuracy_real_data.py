"""Free-run accuracy of every registered model kind on the three shared real data sets.

Protocols (no tuning on test data):

* Quiroz (constant-current sine records, ``sine_unfiltered``): leave one amplitude/frequency
  condition out (train on five conditions, all currents; test on the sixth). Mean test ESR and
  SSSE per model, per fold and overall.
* Dyke (``ranran_50.csv``, random displacement, switching command voltage): first 70 % of the
  record trains, last 30 % tests. Every model with a drive-lag setting (LPV, LTI, P-15,
  SP-1..SP-4, tanh, Bouc-Wen, Dahl, LuGre) identifies the lag of the drive on the training part
  only (its default ``eta="auto"``: first 80 % fits, last 20 % validates,
  ``mrdamper.models.lag``); the chosen rate is printed.
* Labcontrol (``labcontrol2021_utfpr``, constant-voltage sine records at 100 Hz on a third
  damper): fit on ``train/`` (23 records, four voltage levels), score every record of ``test/``
  (15 records).

Every model is fitted with its estimator's defaults plus the data set's electrical input; the LPV
and LTI models run at their default model rate (the lowest record rate, at least 500 Hz: 500 Hz on
Quiroz and Labcontrol, the record rate on Dyke). ``--set KIND.KEY=VALUE`` overrides a setting
(ablations, e.g. ``--set lpv.eta=250.0`` for a fixed lag). A model that fails to fit or to
simulate is reported as a row with its error, never dropped.

Run::

    python benchmarks/accuracy_real_data.py                 # both protocols, every model
    python benchmarks/accuracy_real_data.py --models lpv lti sp1 --protocol quiroz
    python benchmarks/accuracy_real_data.py --models p15 --set p15.method=equation-error
    python benchmarks/accuracy_real_data.py --models tanh dahl --protocol dyke --set tanh.eta=250.0
"""

from __future__ import annotations

import argparse
import ast
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.data.readers import read_csv, read_directory
from mrdamper.models import available_models, get_estimator

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO.parent / "shared" / "data"))
DYKE_FS = 3004.8


#: Extra estimator settings per kind from ``--set KIND.KEY=VALUE`` (override the ones below).
EXTRA: dict[str, dict[str, Any]] = {}


def settings_for(kind: str, protocol: str) -> dict[str, Any]:
    """Estimator settings per kind and protocol (defaults plus the data set's input)."""
    s: dict[str, Any] = {}
    if protocol in ("dyke", "labcontrol"):
        s["input"] = "voltage"
    return {**s, **EXTRA.get(kind, {})}


def fit_and_score(
    kind: str,
    settings: dict[str, Any],
    train: Any,
    test: ExperimentSet,
    range_policy: str | None = None,
) -> list[dict[str, Any]]:
    """Fit ``kind`` on ``train``; one row per test record (or one error row).

    ``range_policy`` (e.g. ``"clip"``) is applied to the fitted model before scoring.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = get_estimator(kind, **settings).fit(train)
            if range_policy is not None:
                model = model.with_range_policy(range_policy)
    except Exception as exc:  # noqa: BLE001 - any failure is reported as a row, never dropped
        return [
            {
                "model": kind,
                "record": "(fit)",
                "esr": np.nan,
                "ssse": np.nan,
                "fit_s": time.perf_counter() - t0,
                "fit_cpu_s": time.process_time() - c0,
                "eta": "-",
                "error": f"{type(exc).__name__}: {exc}",
            }
        ]
    fit_s = time.perf_counter() - t0
    fit_cpu_s = time.process_time() - c0
    lag = getattr(model, "eta", None)
    eta = "-" if lag is None else f"{lag:g}"
    rows = []
    for e in test:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sc = model.score(e)
            rows.append(
                {
                    "model": kind,
                    "record": e.name,
                    "esr": sc.esr,
                    "ssse": sc.ssse,
                    "fit_s": fit_s,
                    "fit_cpu_s": fit_cpu_s,
                    "eta": eta,
                    "error": "",
                }
            )
        except Exception as exc:  # noqa: BLE001 - reported as a row
            rows.append(
                {
                    "model": kind,
                    "record": e.name,
                    "esr": np.nan,
                    "ssse": np.nan,
                    "fit_s": fit_s,
                    "fit_cpu_s": fit_cpu_s,
                    "eta": eta,
                    "error": f"{type(exc).__name__}: {exc}",
                }
            )
    return rows


def quiroz(models: list[str], folds: list[str] | None = None) -> pd.DataFrame:
    """Leave one condition out; ``folds``: only the folds holding out these conditions."""
    data = read_directory(DATA / "quiroz2022_utfsm" / "sine_unfiltered")
    rows = []
    for cond, train, test in data.leave_one_group_out("condition"):
        if folds is not None and cond not in folds:
            continue
        for kind in models:
            for r in fit_and_score(kind, settings_for(kind, "quiroz"), train, test):
                rows.append({"fold": cond, **r})
            last = rows[-1]
            print(
                f"  quiroz fold {cond:>12s} {kind:8s} fit {last['fit_s']:6.2f} s  "
                f"{'error: ' + last['error'][:70] if last['error'] else ''}",
                file=sys.stderr,
                flush=True,
            )
    return pd.DataFrame(rows)


def _dyke_parts() -> tuple[Experiment, Experiment]:
    e = read_csv(DATA / "dyke1996_nees" / "ranran_50.csv", fs=DYKE_FS)
    cut = round(0.7 * e.n)
    return e.slice(0, cut, name="dyke_train"), e.slice(cut, None, name="dyke_test")


def dyke(models: list[str]) -> pd.DataFrame:
    train, test = _dyke_parts()
    rows = []
    for kind in models:
        # the command voltage of the test part exceeds the training range by < 0.1 %: clip it
        rows += fit_and_score(
            kind, settings_for(kind, "dyke"), train, ExperimentSet([test]), "clip"
        )
        last = rows[-1]
        print(
            f"  dyke {kind:8s} fit {last['fit_s']:6.2f} s  eta {last['eta']}  "
            f"{'error: ' + last['error'][:70] if last['error'] else ''}",
            file=sys.stderr,
            flush=True,
        )
    return pd.DataFrame(rows)


def labcontrol(models: list[str]) -> pd.DataFrame:
    """Fit on the Labcontrol ``train/`` records, score every ``test/`` record."""
    root = DATA / "labcontrol2021_utfpr"
    pattern = r"ensaio(?P<test>[^_]+)_(?P<series>.+)_(?P<voltage>[\d.]+)V\.csv"
    train = read_directory(root / "train", pattern=pattern)
    test = read_directory(root / "test", pattern=pattern)
    rows = []
    for kind in models:
        rows += fit_and_score(kind, settings_for(kind, "labcontrol"), train, test, "clip")
        last = rows[-1]
        print(
            f"  labcontrol {kind:8s} fit {last['fit_s']:6.2f} s  "
            f"{'error: ' + last['error'][:70] if last['error'] else ''}",
            file=sys.stderr,
            flush=True,
        )
    return pd.DataFrame(rows)


def to_markdown(df: pd.DataFrame, index: bool = True) -> str:
    """Markdown table of ``df`` (floats with 4 significant digits)."""
    d = df.reset_index() if index else df
    fmt = [
        [f"{x:.4g}" if isinstance(x, float) else str(x) for x in row]
        for row in d.itertuples(index=False)
    ]
    head = "| " + " | ".join(map(str, d.columns)) + " |"
    sep = "|" + "|".join("---" for _ in d.columns) + "|"
    return "\n".join([head, sep] + ["| " + " | ".join(r) + " |" for r in fmt])


def summarise(df: pd.DataFrame) -> pd.DataFrame:
    g = df.groupby("model", sort=False)
    return pd.DataFrame(
        {
            "mean_esr": g["esr"].mean(),
            "mean_ssse_N": g["ssse"].mean(),
            "records": g["esr"].count(),
            "failed": g["error"].apply(lambda s: int((s != "").sum())),
            "fit_s_total": g.apply(
                lambda d: (
                    d.drop_duplicates("fold")["fit_s"].sum() if "fold" in d else d["fit_s"].iloc[0]
                )
            ),
        }
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--models", nargs="*", default=None, help="model kinds (default: every available)"
    )
    ap.add_argument(
        "--protocol",
        choices=("quiroz", "dyke", "labcontrol", "both", "all"),
        default="both",
        help="both: quiroz and dyke; all: the three data sets",
    )
    ap.add_argument(
        "--csv", type=Path, default=None, help="also write the per-record rows to this CSV"
    )
    ap.add_argument(
        "--folds",
        nargs="*",
        default=None,
        metavar="CONDITION",
        help="Quiroz: only the folds holding out these conditions (e.g. 10mm_2Hz)",
    )
    ap.add_argument(
        "--result",
        default=None,
        metavar="NAME",
        help="also store the per-record rows as results/NAME.json (benchmarks/_results.py)",
    )
    ap.add_argument(
        "--set",
        dest="extra",
        action="append",
        default=[],
        metavar="KIND.KEY=VALUE",
        help="extra estimator setting, e.g. p15.method=equation-error (repeatable)",
    )
    args = ap.parse_args(argv)
    from _results import current_commit

    commit = current_commit()  # the code the run starts with (HEAD may move while it runs)
    for item in args.extra:
        key, sep, raw = item.partition("=")
        kind, dot, name = key.partition(".")
        if not (sep and dot and kind and name):
            ap.error(f"--set: expected KIND.KEY=VALUE, got {item!r}")
        try:
            value = ast.literal_eval(raw)
        except (ValueError, SyntaxError):
            value = raw
        EXTRA.setdefault(kind, {})[name] = value
    models = args.models or available_models()
    pd.set_option("display.width", 200)
    print(f"models: {models}\n")
    frames = []
    if args.protocol in ("quiroz", "both", "all"):
        q = quiroz(models, args.folds)
        frames.append(q.assign(protocol="quiroz"))
        print("## Quiroz leave-one-condition-out: mean test ESR per fold")
        print(
            q.pivot_table(
                index="fold", columns="model", values="esr", aggfunc="mean", sort=False
            ).pipe(to_markdown)
        )
        print("\n## Quiroz summary (mean over all test records)")
        print(summarise(q).pipe(to_markdown))
    if args.protocol in ("dyke", "both", "all"):
        d = dyke(models)
        frames.append(d.assign(protocol="dyke"))
        print("\n## Dyke test (last 30 %; eta: the drive lag identified on the training part)")
        print(d.set_index("model")[["esr", "ssse", "eta", "fit_s", "error"]].pipe(to_markdown))
    if args.protocol in ("labcontrol", "all"):
        lab = labcontrol(models)
        frames.append(lab.assign(protocol="labcontrol"))
        print("\n## Labcontrol train/ -> test/: mean test ESR per voltage level")
        level = lab["record"].str.extract(r"_([0-9.]+)V$", expand=False).fillna("(fit)")
        print(
            lab.assign(level=level)
            .pivot_table(index="level", columns="model", values="esr", aggfunc="mean", sort=False)
            .pipe(to_markdown)
        )
        print("\n## Labcontrol summary (mean over all test records)")
        print(summarise(lab).pipe(to_markdown))
    if args.csv is not None:
        from mrdamper._io import atomic_write_text

        atomic_write_text(args.csv, pd.concat(frames).to_csv(index=False), force=True)
    if args.result is not None:
        from _results import write_result

        argv_used = sys.argv[1:] if argv is None else argv
        rows = pd.concat(frames, ignore_index=True)
        level = rows["record"].str.extract(r"_([0-9.]+)V$", expand=False)
        rows["level"] = level.where(rows["protocol"] == "labcontrol")
        write_result(
            args.result,
            rows,
            command=" ".join(["python benchmarks/accuracy_real_data.py", *argv_used]),
            commit=commit,
            measures=(
                "free-run test ESR (eq. 24) and SSSE (eq. 23, N) of every model kind on each "
                "test record of the measured data sets (Quiroz leave-one-condition-out, Dyke "
                "70/30, Labcontrol train/ -> test/); fit_s, fit_cpu_s: wall and CPU time of "
                "the fit [s]; eta: the drive-lag rate chosen [1/s]"
            ),
        )


if __name__ == "__main__":
    main()
