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

With ``--profile`` both runs also record the compilation of every numba kernel in every process of
the demo (CPU time, from numba's event API, as ``bench_compile.py``) and print the costliest.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TARGET = 1.3


def _run(
    python: Path, out: Path, quick: bool, profile: bool, cwd: Path, tag: str
) -> tuple[float, float, dict[str, dict]]:
    args = ["demo", "--out", str(out), "--no-progress"] + (["--quick"] if quick else [])
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env.update(MPLBACKEND="Agg", OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    if profile:  # record the compilations of every process (the demo's workers included)
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from bench_compile import profile_env

        env.update(profile_env(cwd, cwd / f"compile-log-{tag}"))
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [str(python), "-m", "mrdamper", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd,
        check=False,
    )
    wall = time.perf_counter() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = ru.ru_utime + ru.ru_stime - ru0.ru_utime - ru0.ru_stime
    if proc.returncode != 0:
        print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
        raise SystemExit(f"demo failed (exit {proc.returncode})")
    compiles: dict[str, dict] = {}
    if profile:
        from bench_compile import merge

        compiles = merge(cwd / f"compile-log-{tag}")
    return wall, cpu, compiles


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
        first, cpu1, c1 = _run(python, root / "out1", args.quick, args.profile, root, "1")
        second, cpu2, c2 = _run(python, root / "out2", args.quick, args.profile, root, "2")
    mode = "demo --quick" if args.quick else "demo"
    ratio = first / second
    print(
        f"\nload average at the end {os.getloadavg()[0]:.2f} (1 min)\n"
        f"\n| case | wall [s] | CPU, all processes [s] |\n|---|---|---|\n"
        f"| first `{mode}` (empty kernel cache) | {first:.1f} | {cpu1:.1f} |\n"
        f"| second `{mode}` | {second:.1f} | {cpu2:.1f} |\n"
        f"| ratio first / second | {ratio:.2f} (target <= {TARGET}: "
        f"{'met' if ratio <= TARGET else 'NOT met'}) | {cpu1 / cpu2:.2f} |"
    )
    if args.profile:
        for label, rec in (("first", c1), ("second", c2)):
            print(
                f"\nkernel compilation, {label} run (all processes): "
                f"{sum(r['cpu'] for r in rec.values()):.1f} s CPU, "
                f"{sum(r['n'] for r in rec.values())} signatures of {len(rec)} functions",
                end="",
            )
        print("\ncostliest in the first run (own compile CPU [s], signatures):")
        for k, r in sorted(c1.items(), key=lambda kv: -kv[1]["cpu"])[:12]:
            print(f"  {r['cpu']:6.2f} s  {r['n']}  {k}")


if __name__ == "__main__":
    main()
