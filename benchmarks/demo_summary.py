"""The virtual Table II comparison as a result file: ``mrdamper demo`` run into a temporary folder,
its ``summary.csv`` (one row per model: mean, median and quartiles of ESR and SSSE over the scored
records, fit and simulation times) stored as ``results/table2.json`` (``--quick``:
``results/table2-quick.json``, records shortened ten times).

Usage::

    python benchmarks/demo_summary.py            # full length (Table II at 1 kHz)
    python benchmarks/demo_summary.py --quick    # every duration x 0.1

The demo runs with one worker (in-process: the fit and simulation times are not shared with a
second worker on the same core) and seed 0, as ``mrdamper demo --workers 1``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
from _results import current_commit, write_result


def run_demo(quick: bool, out: Path, workers: int = 1) -> tuple[pd.DataFrame, float]:
    """Run ``mrdamper demo`` into ``out``; its summary table and the command's wall time [s]."""
    cmd = [sys.executable, "-m", "mrdamper", "demo", "--out", str(out)]
    cmd += ["--workers", str(workers), "--no-progress"] + (["--quick"] if quick else [])
    env = dict(os.environ, MPLBACKEND="Agg")
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
        raise SystemExit(f"mrdamper demo failed (exit {proc.returncode})")
    return pd.read_csv(out / "summary.csv"), wall


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="every duration x 0.1")
    args = ap.parse_args(argv)
    commit = current_commit()  # the code the run starts with (HEAD may move while it runs)
    with tempfile.TemporaryDirectory(prefix="mrdamper-demo-summary-") as tmp:
        summary, wall = run_demo(args.quick, Path(tmp) / "demo")
    print(summary.to_string(index=False))
    print(f"\nmrdamper demo{' --quick' if args.quick else ''}: {wall:.1f} s")
    name = "table2-quick" if args.quick else "table2"
    path = write_result(
        name,
        summary,
        command="python benchmarks/demo_summary.py" + (" --quick" if args.quick else ""),
        measures=(
            "the virtual Table II comparison (mrdamper demo"
            + (" --quick, durations x 0.1" if args.quick else ", full length")
            + ", seed 0, one worker): per model, free-run ESR and SSSE [N] over the scored "
            "records, fit and simulation wall times [s]"
        ),
        extra={"demo_wall_s": round(wall, 1)},
        commit=commit,
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
