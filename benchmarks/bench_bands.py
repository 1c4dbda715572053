"""Coverage of the prediction bands: the nominal 90 % band of every kind on held-out data.

Every kind is fitted with its band (:func:`mrdamper.uncertainty.fit_with_band`: the fit of the
whole plus two calibration fits on halves of the training records) on the training part of each
protocol and predicts the held-out records with ``range_policy="clip"``. Per protocol and kind
the table gives the coverage (share of held-out samples whose measured force lies inside the
band, pooled over the protocol's test records), the mean band width as a fraction of the RMS
measured force (pooled the same way), the mean test ESR, and the CPU time of the fit of the whole
and of the band's calibration.

Protocols (the splits of ``benchmarks/accuracy_real_data.py`` and
``benchmarks/generalisation.py``; nothing is chosen on test records):

* ``quiroz``: Quiroz ``sine_unfiltered`` leave one amplitude/frequency condition out (six folds,
  pooled);
* ``dyke``: Dyke ``ranran_50.csv``, first 70 % trains, last 30 % tests (voltage input);
* ``labcontrol``: Labcontrol ``train/`` against ``test/`` (voltage input);
* ``quiroz-freq``, ``quiroz-cross``, ``rig-chirp``, ``rig-road``: the generalisation scenarios
  (a), (b) and (c) (the rig's with ``--quick`` records unless ``--full``).

Rows are written to ``--out`` (default ``results/bands.csv``) after each kind, atomically, below
a header of ``#`` lines (command, commit, date, load average), so a long run can be read while it
goes.

``--table FILE...`` prints, instead of running, the markdown table of ``docs/results.md``
("Prediction bands") from result files: coverage and width per kind and protocol (a cell left
empty: not measured; a kind measured in several files: the first file's row).

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bands.py                      # everything
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bands.py --protocols dyke --kinds lpv sp1
    python benchmarks/bench_bands.py --table results/bands*.csv
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from mrdamper._io import atomic_write_text
from mrdamper.data import ExperimentSet
from mrdamper.data.readers import read_csv, read_directory
from mrdamper.models import available_models, get_estimator
from mrdamper.uncertainty import band_of, fit_with_band, predict_interval

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO.parent / "shared" / "data"))
DYKE_FS = 3004.8
LEVEL = 0.9
PROTOCOLS = (
    "dyke",
    "labcontrol",
    "quiroz",
    "quiroz-freq",
    "quiroz-cross",
    "rig-chirp",
    "rig-road",
)

Split = tuple[str, ExperimentSet, ExperimentSet, dict[str, Any]]


def splits(protocol: str, full: bool) -> list[Split]:
    """``(fold label, train, test, settings)`` of one protocol."""
    if protocol == "quiroz":
        data = read_directory(DATA / "quiroz2022_utfsm" / "sine_unfiltered")
        return [(str(c), tr, te, {}) for c, tr, te in data.leave_one_group_out("condition")]
    if protocol == "dyke":
        e = read_csv(DATA / "dyke1996_nees" / "ranran_50.csv", fs=DYKE_FS)
        cut = round(0.7 * e.n)
        train = ExperimentSet([e.slice(0, cut, name="dyke_train")])
        test = ExperimentSet([e.slice(cut, None, name="dyke_test")])
        return [("70/30", train, test, {"input": "voltage"})]
    if protocol == "labcontrol":
        root = DATA / "labcontrol2021_utfpr"
        pattern = r"ensaio.*V\.csv"
        train = read_directory(root / "train", pattern)
        test = read_directory(root / "test", pattern)
        return [("train/test", train, test, {"input": "voltage"})]
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import generalisation as gen

    if protocol in ("rig-chirp", "rig-road"):
        sc = gen.scenario_rig(quick=not full)
        key = next(
            k for k in sc.tests if k.startswith("chirp" if protocol == "rig-chirp" else "road")
        )
        return [(key, sc.train, sc.tests[key], {})]
    sc = (
        gen.scenario_quiroz_frequency if protocol == "quiroz-freq" else gen.scenario_quiroz_cross
    )(quick=not full)
    test = ExperimentSet([e for t in sc.tests.values() for e in t])
    return [(" + ".join(sc.tests), sc.train, test, {})]


def run_kind(kind: str, protocol: str, parts: list[Split]) -> dict[str, Any]:
    """Fit ``kind`` with its band on every split of ``protocol``; one summary row."""
    inside = n = 0
    width_sum = f2_sum = 0.0
    esr, fit_cpu, band_cpu, methods, errors = [], 0.0, 0.0, set(), []
    for label, train, test, settings in parts:
        c0 = time.process_time()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = fit_with_band(get_estimator(kind, **settings), train)
        except Exception as exc:  # noqa: BLE001 - reported as a row, never dropped
            errors.append(f"{label}: {type(exc).__name__}: {str(exc)[:80]}")
            continue
        band = band_of(model)
        assert band is not None
        band_cpu += band.cost_s
        fit_cpu += time.process_time() - c0 - band.cost_s
        methods.add(band.method)
        model = model.with_range_policy("clip")
        for e in test:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    iv = predict_interval(model, e, LEVEL)
            except Exception as exc:  # noqa: BLE001 - reported
                errors.append(f"{label}/{e.name}: {type(exc).__name__}")
                continue
            F = np.asarray(e.F, dtype=np.float64)
            inside += int(np.sum((F >= iv.lower) & (F <= iv.upper)))
            n += F.size
            width_sum += float(np.sum(iv.upper - iv.lower))
            f2_sum += float(np.sum(F**2))
            err = F - iv.F_pred
            esr.append(float(np.sum(err**2) / np.sum((F - F.mean()) ** 2)))
    return {
        "protocol": protocol,
        "kind": kind,
        "coverage": inside / n if n else np.nan,
        "width_rms": (width_sum / n) / np.sqrt(f2_sum / n) if n else np.nan,
        "mean_esr": float(np.mean(esr)) if esr else np.nan,
        "n_test_samples": n,
        "fit_cpu_s": round(fit_cpu, 2),
        "band_cpu_s": round(band_cpu, 2),
        "method": "/".join(sorted(methods)),
        "error": "; ".join(errors),
    }


def header(argv: list[str]) -> str:
    """The ``#`` lines above the table: command, commit, date, load average."""
    try:
        commit = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
        ).stdout.strip()
    except OSError:
        commit = "unknown"
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    cmd = "python benchmarks/bench_bands.py " + " ".join(argv)
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return (
        f"# command: {cmd.strip()}\n# commit: {commit}\n# date: {date}\n"
        f"# load average at start (1, 5, 15 min): {load}\n# level: {LEVEL}\n"
    )


def read_results(paths: list[Path]) -> pd.DataFrame:
    """The rows of result files (``#`` header lines skipped), the first file's row winning when
    a protocol and kind repeat."""
    frames = [pd.read_csv(p, comment="#") for p in paths]
    rows = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    return rows.drop_duplicates(["protocol", "kind"], keep="first")


def table(rows: pd.DataFrame) -> str:
    """Markdown table: one row per kind, per protocol ``coverage / width`` (empty: not
    measured; ``failed``: the fit failed on every split), and the median over the protocols of
    the band calibration's CPU time over the fit's."""
    protocols = [p for p in PROTOCOLS if p in set(rows["protocol"])]
    kinds = [k for k in available_models() if k in set(rows["kind"])]
    head = "| kind | " + " | ".join(protocols) + " | band CPU / fit CPU |"
    out = [head, "|---|" + "---|" * (len(protocols) + 1)]
    for kind in kinds:
        mine = rows[rows["kind"] == kind]
        ok = mine[mine["fit_cpu_s"] > 0]
        ratio = np.median(ok["band_cpu_s"] / ok["fit_cpu_s"]) if len(ok) else np.nan
        cells = []
        for protocol in protocols:
            hit = rows[(rows["kind"] == kind) & (rows["protocol"] == protocol)]
            if hit.empty:
                cells.append("")
                continue
            r = hit.iloc[0]
            cov, width = float(r["coverage"]), float(r["width_rms"])
            cells.append("failed" if np.isnan(cov) else f"{cov:.1%} / {width:.2f}")
        cost = "" if np.isnan(ratio) else f"{ratio:.2g}"
        out.append(f"| {kind} | " + " | ".join(cells) + f" | {cost} |")
    return "\n".join(out).replace("%", " %")


def main(argv: list[str] | None = None) -> pd.DataFrame:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--table"]:
        rows = read_results([Path(a) for a in argv[1:]])
        print(table(rows))
        return rows
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--kinds", nargs="*", default=None, help="model kinds (default: every kind)")
    p.add_argument("--protocols", nargs="*", default=list(PROTOCOLS), choices=PROTOCOLS)
    p.add_argument("--full", action="store_true", help="full-length rig records")
    p.add_argument("--out", type=Path, default=REPO / "results" / "bands.csv")
    args = p.parse_args(argv)
    kinds = args.kinds or available_models()
    head = header(argv)
    rows: list[dict[str, Any]] = []
    for protocol in args.protocols:
        parts = splits(protocol, args.full)
        for kind in kinds:
            t0 = time.perf_counter()
            row = run_kind(kind, protocol, parts)
            rows.append(row)
            took = time.perf_counter() - t0
            print(
                f"{protocol:12s} {kind:8s} coverage {row['coverage']:.3f} width "
                f"{row['width_rms']:.3f} ESR {row['mean_esr']:.4g} ({took:.0f} s)"
                f"{'  ' + row['error'][:100] if row['error'] else ''}",
                flush=True,
            )
            args.out.parent.mkdir(parents=True, exist_ok=True)
            frame = pd.DataFrame(rows)
            atomic_write_text(
                args.out, head + frame.to_csv(index=False, float_format="%.4g"), force=True
            )
    return pd.DataFrame(rows)


if __name__ == "__main__":
    main()
