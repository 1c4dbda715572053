"""Wall time of ``mrdamper demo`` (full Table II at 1 kHz, all models) and ``mrdamper demo
--quick``, each with 1 worker (in-process) and 2 worker processes side by side, in the same run.

Targets on a 2-core machine: full demo < 180 s, quick demo < 60 s.

Usage::

    python benchmarks/bench_demo.py              # quick x {1, 2} workers, full x {1, 2} workers
    python benchmarks/bench_demo.py --no-full    # quick only
    python benchmarks/bench_demo.py --full-workers 2   # full demo with 2 workers only
    python benchmarks/bench_demo.py --quick --models lpv,sp1   # only these models (a smoke run)

Each case runs the real command line in a fresh process (imports and compiled-kernel cache loads
included) into a temporary folder, after one untimed warm-up of ``--quick`` that fills the numba
cache. The table also prints the study's own wall time, the slowest models from timings.json and a
digest of results.csv (timings are in timings.csv) (equal digests: the same numbers whatever the
number of workers).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

TARGETS = {"quick": 60.0, "full": 180.0}


def _demo(out: Path, workers: int, quick: bool, models: str | None) -> list[str]:
    """The ``mrdamper demo`` command line of one case."""
    cmd = [sys.executable, "-m", "mrdamper", "demo", "--out", str(out)]
    cmd += ["--workers", str(workers), "--no-progress"]
    cmd += ["--quick"] if quick else []
    return cmd + (["--models", models] if models else [])


def run(mode: str, workers: int, root: Path, models: str | None = None) -> dict[str, object]:
    out = root / f"{mode}-{workers}"
    cmd = _demo(out, workers, mode == "quick", models)
    env = dict(os.environ, MPLBACKEND="Agg")
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
        raise SystemExit(f"{mode} demo with {workers} worker(s) failed (exit {proc.returncode})")
    study = json.loads((out / "study.json").read_text())
    timings = json.loads((out / "timings.json").read_text())
    res = pd.read_csv(out / "results.csv")
    digest = hashlib.sha1(res.to_csv(index=False).encode()).hexdigest()[:12]
    summ = pd.DataFrame([{"model": m, **t} for m, t in timings["per_model"].items()])
    slow = (
        summ.assign(t=summ["fit_time_s"] + summ["sim_time_s"])
        .sort_values("t", ascending=False)
        .head(3)
    )
    return {
        "mode": mode,
        "workers": workers,
        "wall_s": wall,
        "study_s": float(timings["wall_time_s"]),
        "target_s": TARGETS[mode],
        "slowest": ", ".join(
            f"{r.model} {r.fit_time_s:.0f}+{r.sim_time_s:.0f} s" for r in slow.itertuples()
        ),
        "headline": study["headline"].get("text", ""),
        "results_sha1": digest,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--no-full", action="store_true", help="skip the full-length demo")
    ap.add_argument(
        "--quick", action="store_true", help="only the --quick demo (same as --no-full)"
    )
    ap.add_argument(
        "--full-workers",
        type=int,
        nargs="*",
        default=[1, 2],
        help="worker counts for the full demo",
    )
    ap.add_argument(
        "--quick-workers",
        type=int,
        nargs="*",
        default=[1, 2],
        help="worker counts for the quick demo",
    )
    ap.add_argument(
        "--models",
        default=None,
        help="comma-separated model kinds passed to every demo (default: all installed)",
    )
    args = ap.parse_args()
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory(prefix="bench-demo-") as tmp:
        root = Path(tmp)
        subprocess.run(
            _demo(root / "warm", 1, True, args.models),
            capture_output=True,
            env=dict(os.environ, MPLBACKEND="Agg"),
            check=True,
        )
        rows = [run("quick", w, root, args.models) for w in args.quick_workers]
        if not (args.no_full or args.quick):
            rows += [run("full", w, root, args.models) for w in args.full_workers]
    df = pd.DataFrame(rows)
    for mode in df["mode"].unique():
        sel = df["mode"] == mode
        base = df.loc[sel & (df["workers"] == df.loc[sel, "workers"].min()), "wall_s"].iloc[0]
        df.loc[sel, "speedup_vs_fewest_workers"] = base / df.loc[sel, "wall_s"]
    df["within_target"] = df["wall_s"] < df["target_s"]
    cols = [
        "mode",
        "workers",
        "wall_s",
        "study_s",
        "target_s",
        "within_target",
        "speedup_vs_fewest_workers",
        "results_sha1",
        "slowest",
    ]
    with pd.option_context("display.width", 200, "display.max_colwidth", 80):
        print(df[cols].to_string(index=False, float_format=lambda x: f"{x:.2f}"))
    for r in rows:
        print(f"{r['mode']} / {r['workers']} worker(s): {r['headline']}")
    for mode in df["mode"].unique():
        same = len(set(df.loc[df["mode"] == mode, "results_sha1"])) == 1
        print(
            f"{mode}: results.csv without timing columns identical across worker counts: "
            f"{'yes' if same else 'NO'}"
        )


if __name__ == "__main__":
    main()
