"""The default ``mrdamper fit lpv`` command, side by side with an earlier release in the same run.

Usage::

    python benchmarks/bench_lpv_default.py                    # peer abf5e8f, 3 timed pairs
    python benchmarks/bench_lpv_default.py --repeats 5 --peer v0.3.0
    python benchmarks/bench_lpv_default.py --set model_fs=200  # another setting, both trees

The peer is checked out with ``git worktree add --detach`` into a temporary folder (removed at the
end) and run with its own ``PYTHONPATH``; this checkout runs with ``PYTHONPATH=src``. Each case is
the real command, ``python -m mrdamper fit lpv DATA --out FILE [--set ...]``, in a fresh process:
imports, reading the records, the choice of the hysteretic input's stroke and blend, the full fit
and writing the model all count. One untimed run of each tree first fills its compiled-kernel
cache; then the two trees alternate (``--repeats`` pairs). The environment is the user's (BLAS
threads included), as the command runs for them. Printed: every time, the medians of wall time and
of CPU time (the process's user + system time) and their ratios (peer / this checkout).

Accuracy beside speed: both fitted models are loaded by this checkout and scored in free run on
held-out records (``--held-out``, default the Quiroz records of the filtered conditions, which the
unfiltered training records do not contain): mean ESR of each, and the largest relative
difference of their coefficients. Target of the default command on the Quiroz sines: <= 20 s on an
idle 2-core machine, with the same held-out accuracy.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO.parent / "shared" / "data"))
TARGET_S = 20.0


def _fit(src: Path, data: Path, out: Path, settings: list[str]) -> tuple[float, float]:
    """Wall and CPU time [s] of one ``fit lpv`` command run with ``src`` on the path."""
    env = {**os.environ, "PYTHONPATH": str(src), "MPLBACKEND": "Agg"}
    cmd = [sys.executable, "-m", "mrdamper", "fit", "lpv", str(data), "--out", str(out)]
    cmd += ["--force", "--no-progress"]
    for s in settings:
        cmd += ["--set", s]
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    return wall, (ru.ru_utime - ru0.ru_utime) + (ru.ru_stime - ru0.ru_stime)


def _accuracy(ours: Path, peer: Path, held_out: Path) -> str:
    """Mean held-out ESR of both models and the largest relative difference of coefficients."""
    from mrdamper import load_model, read_directory

    records = read_directory(held_out)
    models = {"this checkout": load_model(ours), "peer": load_model(peer)}
    parts = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, m in models.items():
            esr = [m.with_range_policy("ignore").score(e).esr for e in records]
            parts.append(f"{name} {np.mean(esr):.5f}")
    a, b = (np.r_[m.alpha.ravel(), m.beta.ravel()] for m in models.values())
    rel = float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))
    settings = {n: (m.stroke, m.blend) for n, m in models.items()}
    return (
        f"held-out mean ESR on {len(records)} records of {held_out.name}: {', '.join(parts)}; "
        f"stroke, blend chosen: {settings}; largest relative coefficient difference {rel:.1e}"
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--peer", default="abf5e8f", help="commit (or tag) of the earlier release")
    ap.add_argument("--repeats", type=int, default=3, help="timed pairs (default 3)")
    ap.add_argument("--data", type=Path, default=DATA / "quiroz2022_utfsm" / "sine_unfiltered")
    ap.add_argument("--held-out", type=Path, default=DATA / "quiroz2022_utfsm" / "sine_filtered")
    ap.add_argument("--set", dest="settings", action="append", default=[], metavar="NAME=VALUE")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SystemExit(f"--repeats: expected a positive number of pairs, got {args.repeats}")
    if not args.data.is_dir():
        raise SystemExit(f"--data: expected a folder of records, got {args.data} (not a folder)")
    tmp = Path(tempfile.mkdtemp(prefix="mrdamper-bench-lpv-"))
    tree = tmp / "peer"
    subprocess.run(
        ["git", "-C", str(REPO), "worktree", "add", "--detach", str(tree), args.peer],
        check=True,
        capture_output=True,
    )
    try:
        trees = {"this checkout": REPO / "src", f"peer {args.peer}": tree / "src"}
        outs = {name: tmp / f"model-{k}.json" for k, name in enumerate(trees)}
        for name, src in trees.items():  # untimed: fills each tree's compiled-kernel cache
            _fit(src, args.data, outs[name], args.settings)
        times: dict[str, list[tuple[float, float]]] = {name: [] for name in trees}
        for _ in range(args.repeats):
            for name, src in trees.items():
                times[name].append(_fit(src, args.data, outs[name], args.settings))
        cmd = " ".join(["mrdamper fit lpv", args.data.name] + [f"--set {s}" for s in args.settings])
        print(f"`{cmd}`, {args.repeats} timed run(s) per tree, alternating")
        print("| tree | wall [s] | median wall [s] | median CPU [s] |")
        print("|---|---|---|---|")
        med = {}
        for name, ts in times.items():
            walls = ", ".join(f"{w:.1f}" for w, _ in ts)
            med[name] = (statistics.median(w for w, _ in ts), statistics.median(c for _, c in ts))
            print(f"| {name} | {walls} | {med[name][0]:.1f} | {med[name][1]:.1f} |")
        ours, peer = med["this checkout"], med[f"peer {args.peer}"]
        print(
            f"peer / this checkout: wall {peer[0] / ours[0]:.2f}x, CPU {peer[1] / ours[1]:.2f}x "
            f"(target for the default command: <= {TARGET_S:g} s on an idle 2-core machine)"
        )
        if args.held_out.is_dir():
            print(_accuracy(outs["this checkout"], outs[f"peer {args.peer}"], args.held_out))
        try:
            load = os.getloadavg()
            print(f"load average at the end: {load[0]:.1f} (1 min), {load[2]:.1f} (15 min)")
        except OSError:
            pass
    finally:
        subprocess.run(
            ["git", "-C", str(REPO), "worktree", "remove", "--force", str(tree)],
            check=False,
            capture_output=True,
        )
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
