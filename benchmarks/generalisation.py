"""Generalisation benchmark: free-run accuracy on excitations the models were not trained on.

Four scenarios, every registered model kind, one table of mean test ESR (eq. 24):

* **(a) Quiroz frequency extrapolation** (``sine_unfiltered``): train on the conditions up to
  3 Hz (25 mm / 0.25 Hz, 25 mm / 0.5 Hz, 10 mm / 2 Hz, 5 mm / 3 Hz; all currents), test on
  5 mm / 4 Hz and 2 mm / 5 Hz.
* **(b) Quiroz cross-set**: train on the 30 ``sine_unfiltered`` records, test on the
  ``sine_filtered`` conditions that training lacks (10 mm / 1 Hz and 25 mm / 0.1 Hz; the author's
  causal smoothing of those files is part of the test).
* **(c) virtual rig** with the reference damper calibrated on Quiroz (``quiroz2022``): train on
  constant-current sines at Quiroz's six conditions (25 mm reduced to the rig's 18 mm) and five
  currents, test on a 1-15 Hz linear
  chirp (constant velocity amplitude 0.1 m/s) at 0, 0.5 and 1 A and on an ISO 8608 road profile
  (class C, up to 10 Hz) with an APRBS current.
* **(d) Dyke 70/30** (``ranran_50.csv``): first 70 % trains, last 30 % tests; every estimator
  with a drive-lag setting ``eta`` identifies its lag on the training part (its default).
* **(e) Labcontrol** (``labcontrol2021_utfpr``, a third damper on a shaking table, four constant
  voltages, 100 Hz): train on ``train/``, test on ``test/``.

Nothing is chosen on test records. Every model uses its estimator defaults plus the data set's
electrical input; the LPV/LTI model rate is the estimator's default: 500 Hz on Quiroz (records at
200 Hz and 1 kHz) and Labcontrol (100 Hz), the record rate on the rig (1 kHz) and Dyke. The extra
column ``lpv-val`` is the LPV model with its order ``n_m`` and model rate chosen on a validation
split of the training data only (leave one training condition out for (a)-(c); last 20 % of the
training part for (d)); on Quiroz the rates 200, 500 and 1000 Hz are candidates (the latter two
up-sample the 200 Hz records); ``lpv-val`` uses the paper's static input ``u`` (with the default
hysteretic input every candidate would fit six times). ``lpv-u`` is the LPV
model with the paper's static zone-law input (``input_signal="u"``, the default before the
hysteretic input); the ``lpv`` column has the default hysteretic input, its stroke scale and
pre-yield share chosen beyond the training envelope (the estimator's default
``choose_on="beyond"``: fitted below the training records' highest frequency band, scored on it).
Scoring uses ``range_policy="clip"`` (measured
currents and voltages leave the training range by sensor noise only). A model that fails to fit or
simulate is reported (``failed`` in the table), never dropped.

**Recommended against best** (``--select``): ``mrdamper select`` (:func:`mrdamper.study.
cross_validate`, with its folds beyond the training envelope and its stress test) is run on each
scenario's training records with the same kinds and settings; the columns ``select`` (the kind it
recommends), ``select_esr`` (that kind's test ESR, from the table) and ``select/best`` (its ratio to
the best kind of the row among the registered kinds, the ``lpv-*`` variants excluded since
``select`` does not consider them) say how far the recommendation is from the best choice.

Run::

    python benchmarks/generalisation.py          # every scenario, full length
    python benchmarks/generalisation.py --quick  # shorter rig records, fewer grids (a test runs it)
    python benchmarks/generalisation.py --quick --select --scenarios rig  # with select's column
    python benchmarks/generalisation.py --quick --models lpv --lpv-choose-on training
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import scipy.signal as sps

from mrdamper.cli.models import parse_settings
from mrdamper.data import ExperimentSet
from mrdamper.data.readers import read_csv, read_directory
from mrdamper.models import available_models, get_estimator
from mrdamper.models.lag import lag_setting
from mrdamper.models.lpv import LPVEstimator
from mrdamper.models.lpv.estimator import outer_slope_choices
from mrdamper.models.rates import rate_rule
from mrdamper.models.registry import takes_lag
from mrdamper.rig import VirtualRig, reference_damper
from mrdamper.signals import aprbs, ramped_sine, road_profile

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO.parent / "shared" / "data"))
QUIROZ = DATA / "quiroz2022_utfsm"
DYKE_FS = 3004.8
#: Quiroz's six sine conditions (amplitude [m], frequency [Hz]); the rig's 40 mm stroke and
#: +-25 mm LVDT take 18 mm in place of Quiroz's 25 mm.
RIG_CONDITIONS = (
    (0.018, 0.25),
    (0.018, 0.5),
    (0.010, 2.0),
    (0.005, 3.0),
    (0.005, 4.0),
    (0.002, 5.0),
)
CURRENTS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Labcontrol file names ``ensaio{test}_{series}_{voltage}V.csv`` (voltage in the column).
LABCONTROL_PATTERN = r"ensaio.*V\.csv"


@dataclass
class Scenario:
    """Training records, named test sets and the per-kind estimator settings of one scenario."""

    name: str
    train: ExperimentSet
    tests: dict[str, ExperimentSet]
    settings: Callable[[str], dict[str, Any]]
    #: (fit part, validation part) pairs of the training data for the ``lpv-val`` choice
    folds: list[tuple[ExperimentSet, ExperimentSet]]
    #: candidate LPV settings for ``lpv-val``
    grid: list[dict[str, Any]]


# ----------------------------------------------------------------------------- fitting and scoring
def fit_model(kind: str, settings: dict[str, Any], train: ExperimentSet) -> tuple[Any, float, str]:
    """Fit ``kind``; returns ``(model or None, fit time [s], error message)``."""
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = get_estimator(kind, **settings).fit(train).with_range_policy("clip")
    except Exception as exc:  # noqa: BLE001 - every failure becomes a reported row
        return None, time.perf_counter() - t0, f"{type(exc).__name__}: {exc}"
    return model, time.perf_counter() - t0, ""


def mean_esr(model: Any, records: ExperimentSet) -> tuple[float, str]:
    """Mean free-run ESR over ``records`` (NaN and the first error if any record fails)."""
    out = []
    for e in records:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(model.score(e).esr)
        except Exception as exc:  # noqa: BLE001 - reported
            return float("nan"), f"{e.name}: {type(exc).__name__}: {exc}"
    return float(np.mean(out)), ""


def choose_lpv(sc: Scenario) -> tuple[dict[str, Any], pd.DataFrame]:
    """LPV settings with the lowest mean validation ESR over ``sc.folds`` (training data only)."""
    rows = []
    for cand in sc.grid:
        settings = {**sc.settings("lpv"), "input_signal": "u", **cand}
        vals = []
        err = ""
        for fit_part, val_part in sc.folds:
            m, _, err = fit_model("lpv", settings, fit_part)
            if m is None:
                break
            val, err = mean_esr(m, val_part)
            if err:
                break
            vals.append(val)
        rows.append(
            {**cand, "val_esr": float(np.mean(vals)) if not err else np.nan, "error": err[:60]}
        )
    tab = pd.DataFrame(rows)
    if not tab["val_esr"].notna().any():
        return sc.settings("lpv"), tab
    best = tab.loc[tab["val_esr"].idxmin()]
    return {**sc.settings("lpv"), "input_signal": "u", **{k: best[k] for k in sc.grid[0]}}, tab


#: Share of the total training weight given to the reference-model records (a priori, not tuned).
AUG_SHARE = 0.5


def fit_augmented(
    sc: Scenario, settings: dict[str, Any], reference: Any, base: Any
) -> tuple[Any, float, str]:
    """LPV trained on the measured records plus broadband records simulated by the Spencer model
    fitted on the same records (``mrdamper.models.augment``); zone laws from the measured
    records."""
    if reference is None or base is None:
        return None, 0.0, "needs the spencer and lpv fits of the same scenario"
    from mrdamper.models.augment import reference_records

    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fs = rate_rule(
                [e.fs for e in sc.train], settings.get("model_fs"), LPVEstimator.min_model_fs
            )
            syn, _ = reference_records(
                sc.train, reference=reference, input=settings.get("input", "i"), fs=fs, seed=0
            )
            w_syn = AUG_SHARE / (1 - AUG_SHARE) * len(sc.train) / len(syn)
            est = get_estimator("lpv", **{**settings, "zone_laws": base.zone_laws})
            model = est.fit(
                [*sc.train, *syn], record_weights=[1.0] * len(sc.train) + [w_syn] * len(syn)
            )
    except Exception as exc:  # noqa: BLE001 - reported
        return None, time.perf_counter() - t0, f"{type(exc).__name__}: {exc}"
    return model.with_range_policy("clip"), time.perf_counter() - t0, ""


def run_scenario(sc: Scenario, models: list[str], with_val: bool) -> list[dict[str, Any]]:
    """One row per (model, test set)."""
    rows = []
    plan = [(k, k, sc.settings(k)) for k in models]
    if with_val and "lpv" in models and sc.grid:
        chosen, tab = choose_lpv(sc)
        print(f"\n[{sc.name}] lpv-val grid (validation on training data only):", file=sys.stderr)
        print(tab.to_string(index=False), file=sys.stderr)
        plan.append(("lpv-val", "lpv", chosen))
    fitted: dict[str, Any] = {}
    if "lpv" in models and "spencer" in models:
        plan.append(("lpv-aug", "lpv", sc.settings("lpv")))
    if "lpv" in models:
        plan.append(("lpv-u", "lpv", {**sc.settings("lpv"), "input_signal": "u"}))
    for label, kind, settings in plan:
        if label == "lpv-aug":
            model, fit_s, err = fit_augmented(
                sc, settings, fitted.get("spencer"), fitted.get("lpv")
            )
        else:
            model, fit_s, err = fit_model(kind, settings, sc.train)
        fitted[label] = model
        for test_name, records in sc.tests.items():
            esr, serr = (float("nan"), err) if model is None else mean_esr(model, records)
            rows.append(
                {
                    "scenario": sc.name,
                    "test": test_name,
                    "model": label,
                    "esr": esr,
                    "fit_s": fit_s,
                    "error": serr,
                }
            )
        print(
            f"  {sc.name:14s} {label:8s} fit {fit_s:6.2f} s "
            f"{('error: ' + err[:80]) if err else ''}",
            file=sys.stderr,
            flush=True,
        )
    return rows


def select_on(sc: Scenario, models: list[str]) -> tuple[str | None, float, str]:
    """``(recommended kind, select's run time [s], reason)`` of ``cross_validate`` on the
    scenario's training records (the scenario's input and per-kind settings)."""
    from mrdamper.study import cross_validate

    source = sc.settings("bingham").get("input", "i")
    settings = {k: {a: b for a, b in sc.settings(k).items() if a != "input"} for k in models}
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = cross_validate(sc.train, models=models, input=source, settings=settings)
    print(f"\n[{sc.name}] select:\n{res.table.to_string()}", file=sys.stderr, flush=True)
    return res.recommended, time.perf_counter() - t0, res.reason


# ----------------------------------------------------------------------------- scenarios
def _loco(train: ExperimentSet) -> list[tuple[ExperimentSet, ExperimentSet]]:
    return [(fit, val) for _, fit, val in train.leave_one_group_out("condition")]


def _defaults(kind: str) -> dict[str, Any]:
    """Settings of a scenario whose kinds all run with their estimator defaults (current input)."""
    return {}


#: 500 Hz and 1 kHz up-sample the 200 Hz records (linear interpolation, with a warning).
QUIROZ_GRID = [{"n_m": n, "model_fs": fs} for n in (2, 3, 4) for fs in (200.0, 500.0, 1000.0)]


def scenario_quiroz_frequency(quick: bool) -> Scenario:
    """(a) train on conditions up to 3 Hz, test on 4 and 5 Hz."""
    data = read_directory(QUIROZ / "sine_unfiltered")
    train = data.where(lambda e: e.metadata["frequency"] <= 3.0)
    tests = {c: data.filter(condition=c) for c in ("5mm_4Hz", "2mm_5Hz")}
    grid = [] if quick else QUIROZ_GRID
    return Scenario("(a) quiroz-freq", train, tests, _defaults, _loco(train), grid)


def scenario_quiroz_cross(quick: bool) -> Scenario:
    """(b) train on sine_unfiltered, test on the sine_filtered conditions training lacks."""
    train = read_directory(QUIROZ / "sine_unfiltered")
    filt = read_directory(QUIROZ / "sine_filtered")
    seen = {e.metadata["condition"] for e in train}
    lacking = sorted({e.metadata["condition"] for e in filt} - seen)
    tests = {f"filtered {c}": filt.filter(condition=c) for c in lacking}
    grid = [] if quick else QUIROZ_GRID
    return Scenario("(b) quiroz-cross", train, tests, _defaults, _loco(train), grid)


def scenario_rig(quick: bool) -> Scenario:
    """(c) virtual rig, reference damper calibrated on Quiroz."""
    fs = 1000.0
    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=fs)
    currents = (0.0, 0.5, 1.0) if quick else CURRENTS
    cycles = 2 if quick else 4
    seed = 100
    train = []
    for amp, f in RIG_CONDITIONS:
        for cur in currents:
            x = ramped_sine(fs, amplitude=amp, frequency=f, cycles=cycles)
            seed += 1
            cond = f"{amp * 1e3:g}mm_{f:g}Hz"
            train.append(
                rig.run(
                    x,
                    np.full(x.size, cur),
                    seed=seed,
                    name=f"rig_{cond}_{cur:g}A",
                    metadata={"condition": cond, "current": cur, "frequency": f},
                )
            )
    train_set = ExperimentSet(train, name="rig-sines")
    dur = 8.0 if quick else 20.0
    t = np.arange(round(dur * fs)) / fs
    f_inst = 1.0 + (15.0 - 1.0) * t / dur
    amp = 0.1 / (2 * np.pi * f_inst)  # constant velocity amplitude 0.1 m/s
    chirp = amp * sps.chirp(t, f0=1.0, t1=dur, f1=15.0, method="linear", phi=-90)
    chirp *= np.clip(np.minimum(t, dur - t) / 0.5, 0.0, 1.0)
    chirps = [
        rig.run(
            chirp,
            np.full(t.size, cur),
            seed=900 + k,
            name=f"chirp_{cur:g}A",
            metadata={"current": cur},
        )
        for k, cur in enumerate((0.0, 0.5, 1.0))
    ]
    rdur = 10.0 if quick else 30.0
    x_road = road_profile(fs, rdur, seed=7, max_frequency=10.0, stroke=0.04)
    i_road = aprbs(fs, rdur, low=0.0, high=1.0, min_hold=0.2, seed=8)
    road = rig.run(x_road, i_road, seed=950, name="road_aprbs")
    tests = {
        "chirp 1-15 Hz, 0/0.5/1 A": ExperimentSet(chirps),
        "road + APRBS current": ExperimentSet([road]),
    }
    grid = (
        []
        if quick
        else [{"n_m": n, "model_fs": r} for n in (2, 3, 4) for r in (200.0, 500.0, 1000.0)]
    )
    return Scenario("(c) rig", train_set, tests, _defaults, _loco(train_set), grid)


def scenario_dyke(quick: bool) -> Scenario:
    """(d) Dyke 70/30, every model with its defaults (the drive lag identified on the training
    part by every model with an ``eta`` setting, ``mrdamper.models.lag``)."""
    e = read_csv(DATA / "dyke1996_nees" / "ranran_50.csv", fs=DYKE_FS)
    cut = round(0.7 * e.n)
    train, test = e.slice(0, cut, name="dyke_train"), e.slice(cut, None, name="dyke_test")

    def settings(kind: str) -> dict[str, Any]:
        return {"input": "voltage"}

    c2 = round(0.8 * train.n)
    folds = [
        (
            ExperimentSet([train.slice(0, c2, name="fit")]),
            ExperimentSet([train.slice(c2, None, name="val")]),
        )
    ]
    grid = [] if quick else [{"n_m": n} for n in (2, 3, 4, 5)]
    return Scenario(
        "(d) dyke",
        ExperimentSet([train]),
        {"last 30 %": ExperimentSet([test])},
        settings,
        folds,
        grid,
    )


def scenario_labcontrol(quick: bool) -> Scenario:
    """(e) Labcontrol shaking table (a third damper): train on ``train/``, test on ``test/``."""
    root = DATA / "labcontrol2021_utfpr"
    train = read_directory(root / "train", LABCONTROL_PATTERN)
    test = read_directory(root / "test", LABCONTROL_PATTERN)
    folds = [
        (
            ExperimentSet([e for k, e in enumerate(train) if k % 3 != j]),
            ExperimentSet([e for k, e in enumerate(train) if k % 3 == j]),
        )
        for j in range(3)
    ]
    grid = [] if quick else [{"n_m": n} for n in (2, 3, 4)]
    return Scenario(
        "(e) labcontrol",
        train,
        {"test/, 4 voltages": test},
        lambda kind: {"input": "voltage"},
        folds,
        grid,
    )


SCENARIOS: dict[str, Callable[[bool], Scenario]] = {
    "quiroz-freq": scenario_quiroz_frequency,
    "quiroz-cross": scenario_quiroz_cross,
    "rig": scenario_rig,
    "dyke": scenario_dyke,
    "labcontrol": scenario_labcontrol,
}


# ----------------------------------------------------------------------------- output
def table(
    rows: list[dict[str, Any]], selected: dict[str, str | None] | None = None
) -> pd.DataFrame:
    """Mean test ESR, one row per (scenario, test set), one column per model, plus the best (and,
    with ``selected`` (scenario -> recommended kind), ``select``, ``select_esr`` and
    ``select/best``: against the best registered kind, variants excluded)."""
    df = pd.DataFrame(rows)
    tab = df.pivot_table(
        index=["scenario", "test"],
        columns="model",
        values="esr",
        aggfunc="mean",
        sort=False,
        dropna=False,
    )
    order = list(dict.fromkeys(df["model"]))
    keys = list(dict.fromkeys(zip(df["scenario"], df["test"])))
    tab = tab.reindex(
        index=pd.MultiIndex.from_tuples(keys, names=["scenario", "test"]), columns=order
    )
    tab["best"] = [row.idxmin() if row.notna().any() else "-" for _, row in tab.iterrows()]
    if selected:
        kinds = [c for c in order if c in set(available_models())]
        picks, esrs, ratios = [], [], []
        for (scenario, _), row in tab.iterrows():
            pick = selected.get(scenario)
            best = pd.to_numeric(row[kinds], errors="coerce").min()
            esr = float(row[pick]) if pick in row.index else float("nan")
            picks.append(pick or "-")
            esrs.append(esr)
            ratios.append(esr / best if best > 0 else float("nan"))
        tab["select"] = picks
        tab["select_esr"] = esrs
        tab["select/best"] = ratios
    return tab


def to_markdown(tab: pd.DataFrame) -> str:
    """Markdown table (3 significant digits; failed fits as ``failed``)."""
    d = tab.reset_index()
    head = "| " + " | ".join(map(str, d.columns)) + " |"
    sep = "|" + "|".join("---" for _ in d.columns) + "|"

    def cell(x: Any) -> str:
        if isinstance(x, float):
            return "failed" if np.isnan(x) else f"{x:.3g}"
        return str(x)

    return "\n".join(
        [head, sep]
        + ["| " + " | ".join(cell(x) for x in r) + " |" for r in d.itertuples(index=False)]
    )


def _with_lpv(
    settings: Callable[[str], dict[str, Any]], name: str, value: Any
) -> Callable[[str], dict[str, Any]]:
    """A scenario's settings with the LPV's setting ``name`` given."""
    return lambda kind: {**settings(kind), **({name: value} if kind == "lpv" else {})}


def _with_lag(
    settings: Callable[[str], dict[str, Any]], eta: Any
) -> Callable[[str], dict[str, Any]]:
    """A scenario's settings with ``eta`` given to every kind that has a lag setting."""
    return lambda kind: {**settings(kind), **({"eta": eta} if takes_lag(kind) else {})}


def main(argv: list[str] | None = None) -> pd.DataFrame:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="short rig records, no validation grids")
    ap.add_argument(
        "--models", nargs="*", default=None, help="model kinds (default: every available)"
    )
    ap.add_argument("--scenarios", nargs="*", choices=list(SCENARIOS), default=list(SCENARIOS))
    ap.add_argument(
        "--csv", type=Path, default=None, help="also write the per-test rows to this CSV"
    )
    ap.add_argument(
        "--select",
        action="store_true",
        help="also run mrdamper select on each training set (columns select, select/best)",
    )
    ap.add_argument(
        "--lpv-choose-on",
        choices=["beyond", "training", "held-out"],
        default=None,
        help="where the LPV input's stroke and blend are chosen (default: the estimator's)",
    )
    ap.add_argument(
        "--lpv-model-fs",
        type=float,
        default=None,
        help="the LPV model rate [Hz] (default: the estimator's, at least 500 Hz)",
    )
    ap.add_argument(
        "--lpv-outer-slopes",
        choices=outer_slope_choices(),
        default=None,
        help="the LPV zone laws' outer slopes (default: the estimator's)",
    )
    ap.add_argument(
        "--eta",
        default=None,
        help="lag setting of every kind that has one ('auto', 'identify' or a rate [1/s]; "
        "default: the estimator's)",
    )
    ap.add_argument(
        "--lpv-set",
        action="append",
        default=None,
        metavar="KEY=VALUE",
        help="any other LPV setting, e.g. n_m=5 (repeatable; values read as JSON)",
    )
    ap.add_argument(
        "--result",
        default=None,
        metavar="NAME",
        help="also store the per-test rows as results/NAME.json (benchmarks/_results.py) and, "
        "with --select, the recommendations as results/NAME-select.json",
    )
    args = ap.parse_args(argv)
    from _results import current_commit

    commit = current_commit()  # the code the run starts with (HEAD may move while it runs)
    lpv_extra = parse_settings(args.lpv_set)
    models = args.models or available_models()
    rows: list[dict[str, Any]] = []
    selected: dict[str, str | None] = {}
    t0 = time.perf_counter()
    for name in args.scenarios:
        sc = SCENARIOS[name](args.quick)
        for setting, value in (
            ("choose_on", args.lpv_choose_on),
            ("model_fs", args.lpv_model_fs),
            ("outer_slopes", args.lpv_outer_slopes),
            *lpv_extra.items(),
        ):
            if value is not None:
                sc = dataclasses.replace(sc, settings=_with_lpv(sc.settings, setting, value))
        if args.eta is not None:
            sc = dataclasses.replace(sc, settings=_with_lag(sc.settings, lag_setting(args.eta)))
        print(
            f"{sc.name}: {len(sc.train)} training records; tests "
            f"{ {k: len(v) for k, v in sc.tests.items()} }",
            file=sys.stderr,
            flush=True,
        )
        rows += run_scenario(sc, models, with_val=not args.quick)
        if args.select:
            pick, secs, reason = select_on(sc, models)
            selected[sc.name] = pick
            print(f"  select: {pick} in {secs:.0f} s: {reason}", file=sys.stderr, flush=True)
    tab = table(rows, selected)
    print(
        f"## Generalisation: mean test ESR ({'quick' if args.quick else 'full'}; "
        f"{time.perf_counter() - t0:.0f} s)\n"
    )
    print(to_markdown(tab))
    errors = [r for r in rows if r["error"]]
    if errors:
        print("\nFailures:")
        for r in errors:
            print(f"- {r['scenario']} / {r['test']} / {r['model']}: {r['error'][:160]}")
    if args.csv is not None:
        from mrdamper._io import atomic_write_text

        atomic_write_text(args.csv, pd.DataFrame(rows).to_csv(index=False), force=True)
    if args.result is not None:
        _store(args.result, rows, tab if args.select else None, argv, commit)
    return tab


def _store(
    name: str,
    rows: list[dict[str, Any]],
    tab: pd.DataFrame | None,
    argv: list[str] | None,
    commit: str,
) -> None:
    """Write the per-test rows (and ``select``'s picks) as result files."""
    from _results import write_result

    used = sys.argv[1:] if argv is None else argv
    command = " ".join(["OPENBLAS_NUM_THREADS=1 python benchmarks/generalisation.py", *used])
    write_result(
        name,
        pd.DataFrame(rows),
        command=command,
        commit=commit,
        measures=(
            "mean free-run test ESR of every model kind trained on one excitation and scored on "
            "another (the scenarios of benchmarks/generalisation.py); fit_s: wall time of the fit"
        ),
    )
    if tab is not None:
        picks = tab.reset_index()[["scenario", "test", "best", "select", "select_esr"]]
        picks["select_over_best"] = tab["select/best"].to_numpy()
        write_result(
            f"{name}-select",
            picks,
            command=command,
            commit=commit,
            measures=(
                "the kind mrdamper select recommends from each scenario's training records, its "
                "test ESR and that ESR over the best kind's"
            ),
        )


if __name__ == "__main__":
    main()
