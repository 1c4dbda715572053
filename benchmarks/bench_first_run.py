"""First run on a fresh install: ``mrdamper demo`` twice in a new virtual environment.

Usage::

    python benchmarks/bench_first_run.py              # full demo: 3 fresh installs, 2 runs each
    python benchmarks/bench_first_run.py --quick      # demo --quick instead (a few minutes)
    python benchmarks/bench_first_run.py --repeat 1   # one fresh install only

For each of ``--repeat`` installs (3 by default), a virtual environment is created in a temporary
folder (``--system-site-packages``, so the dependencies are those of this interpreter) and this
checkout is installed into it as a regular, non-editable package (``pip install --no-deps``; pip
fetches only the build backend): the package files are new copies, so no compiled-kernel cache
exists. The demo then runs twice in that environment, each time in a fresh process; the second run
finds the kernels the first one cached.
Target: first run <= 1.3 x the second. The run-to-run spread of a single pair is about +-0.1 on
this ratio, so the result is the median ratio over the fresh installs, with every pair printed.

With ``--profile`` both runs also record the compilation of every numba kernel in every process of
the demo (CPU time, from numba's event API, as ``bench_compile.py``) and print the costliest.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
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


def _fresh_install(root: Path) -> Path:
    """A new virtual environment in ``root`` with this checkout installed; its python."""
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
    return python


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--quick", action="store_true", help="time `mrdamper demo --quick` instead of the full demo"
    )
    ap.add_argument("--profile", action="store_true", help="also time every kernel compilation")
    ap.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="fresh installs, each with a first and a second run (the median ratio is the result)",
    )
    args = ap.parse_args()
    mode = "demo --quick" if args.quick else "demo"
    rows = []
    c1: dict[str, dict] = {}
    c2: dict[str, dict] = {}
    for rep in range(max(1, args.repeat)):
        with tempfile.TemporaryDirectory(prefix="bench-first-run-") as tmp:
            root = Path(tmp)
            python = _fresh_install(root)
            first, cpu1, c1 = _run(python, root / "out1", args.quick, args.profile, root, "1")
            second, cpu2, c2 = _run(python, root / "out2", args.quick, args.profile, root, "2")
        rows.append((first, cpu1, second, cpu2))
        print(
            f"  install {rep + 1}: first {first:.1f} s, second {second:.1f} s, "
            f"ratio {first / second:.2f}",
            flush=True,
        )
    ratios = sorted(r[0] / r[2] for r in rows)
    median = float(statistics.median(ratios))
    print(
        f"\nload average at the end {os.getloadavg()[0]:.2f} (1 min)\n"
        f"\n| install | first `{mode}` (empty kernel cache) [s] | second [s] | ratio wall "
        f"| ratio CPU, all processes |\n|---|---|---|---|---|"
    )
    for i, (first, cpu1, second, cpu2) in enumerate(rows):
        print(
            f"| {i + 1} | {first:.1f} | {second:.1f} | {first / second:.2f} | {cpu1 / cpu2:.2f} |"
        )
    print(
        f"\nmedian ratio first / second over {len(rows)} fresh installs: {median:.2f} "
        f"(range {ratios[0]:.2f}-{ratios[-1]:.2f}; target <= {TARGET}: "
        f"{'met' if median <= TARGET else 'NOT met'})"
    )
    if args.profile:
        for label, rec in (("first", c1), ("second", c2)):
            print(
                f"\nkernel compilation, {label} run of the last install (all processes): "
                f"{sum(r['cpu'] for r in rec.values()):.1f} s CPU, "
                f"{sum(r['n'] for r in rec.values())} signatures of {len(rec)} functions",
                end="",
            )
        print("\ncostliest in the first run (own compile CPU [s], signatures):")
        for k, r in sorted(c1.items(), key=lambda kv: -kv[1]["cpu"])[:12]:
            print(f"  {r['cpu']:6.2f} s  {r['n']}  {k}")


if __name__ == "__main__":
    main()
