"""First run on a fresh install: ``mrdamper demo`` twice in a new virtual environment.

Usage::

    python benchmarks/bench_first_run.py            # full demo, twice
    python benchmarks/bench_first_run.py --quick    # demo --quick, twice (about a minute)

A virtual environment is created in a temporary folder (``--system-site-packages``, so the
dependencies are those of this interpreter) and this checkout is installed into it as a regular,
non-editable package (``pip install --no-deps``; pip fetches only the build backend): the package
files are new copies, so no compiled-kernel cache exists. The demo then runs twice in that
environment, each time in a fresh process; the second run finds the kernels the first one cached.
Target: first run <= 1.3 x the second.

With ``--profile`` both runs also record the compilation of every numba kernel (wall time of each
top-level compile, from numba's event API) and print the ten costliest.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TARGET = 1.3

_PROFILE = r"""
import atexit, json, runpy, sys, time
from numba.core import event
stack, tot = [], {}
class L(event.Listener):
    def on_start(self, ev):
        stack.append(time.perf_counter())
    def on_end(self, ev):
        dt = time.perf_counter() - stack.pop()
        if not stack:
            f = ev.data["dispatcher"].py_func
            k = f.__module__ + "." + f.__qualname__
            tot[k] = tot.get(k, 0.0) + dt
event.register("numba:compile", L())
atexit.register(lambda: print("COMPILE " + json.dumps(tot), file=sys.stderr))
sys.argv = ["mrdamper"] + sys.argv[1:]
runpy.run_module("mrdamper", run_name="__main__")
"""


def _run(
    python: Path, out: Path, quick: bool, profile: bool, cwd: Path
) -> tuple[float, dict[str, float]]:
    args = ["demo", "--out", str(out), "--no-progress"] + (["--quick"] if quick else [])
    cmd = (
        [str(python), "-c", _PROFILE, *args] if profile else [str(python), "-m", "mrdamper", *args]
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env.update(MPLBACKEND="Agg", OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
        raise SystemExit(f"demo failed (exit {proc.returncode})")
    compiles: dict[str, float] = {}
    for line in proc.stderr.splitlines():
        if line.startswith("COMPILE "):
            compiles = json.loads(line[len("COMPILE ") :])
    return wall, compiles


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--quick", action="store_true", help="time `mrdamper demo --quick` instead of the full demo"
    )
    ap.add_argument("--profile", action="store_true", help="also time every kernel compilation")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-first-run-") as tmp:
        root = Path(tmp)
        venv = root / "venv"
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)],
            check=True,
        )
        python = venv / "bin" / "python"
        subprocess.run(
            [
                str(python),
                "-m",
                "pip",
                "install",
                "-q",
                "--no-deps",
                "--disable-pip-version-check",
                str(REPO),
            ],
            check=True,
            capture_output=True,
        )
        where = subprocess.run(
            [str(python), "-c", "import mrdamper, os; print(os.path.dirname(mrdamper.__file__))"],
            capture_output=True,
            text=True,
            check=True,
            cwd=root,
            env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"},
        ).stdout.strip()
        print(
            f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs; installed into {where} "
            f"in {time.perf_counter() - t0:.1f} s",
            flush=True,
        )
        if not where.startswith(str(venv)):
            raise SystemExit(
                f"the fresh environment imports mrdamper from {where}, not from the new install"
            )
        first, c1 = _run(python, root / "out1", args.quick, args.profile, root)
        second, c2 = _run(python, root / "out2", args.quick, args.profile, root)
    mode = "demo --quick" if args.quick else "demo"
    ratio = first / second
    print(
        f"\n| case | wall [s] |\n|---|---|\n| first `{mode}` (empty kernel cache) | {first:.1f} |\n"
        f"| second `{mode}` | {second:.1f} |\n| ratio first / second | {ratio:.2f} "
        f"(target <= {TARGET}: {'met' if ratio <= TARGET else 'NOT met'}) |"
    )
    if args.profile:
        print(
            f"\nkernel compilation: first run {sum(c1.values()):.1f} s in {len(c1)} kernels, "
            f"second run {sum(c2.values()):.1f} s in {len(c2)} kernels"
        )
        for k, v in sorted(c1.items(), key=lambda kv: -kv[1])[:10]:
            print(f"  {v:6.2f} s  {k}")


if __name__ == "__main__":
    main()
