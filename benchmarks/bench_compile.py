"""Compile time of every numba kernel used by ``mrdamper demo``, from an empty kernel cache.

Usage::

    python benchmarks/bench_compile.py                 # demo --quick, 1 worker, empty cache
    python benchmarks/bench_compile.py --full          # the full demo
    python benchmarks/bench_compile.py --workers 2     # as the default demo (two processes)
    python benchmarks/bench_compile.py --signatures    # also list every compiled signature
    python benchmarks/bench_compile.py --models sp1    # only these model kinds (quick check)

The demo runs in a fresh process with ``NUMBA_CACHE_DIR`` pointing at a new empty folder, so
every kernel it needs is compiled (as on a fresh install), then a second time with the cache the
first run wrote (the peer, as the second run of ``bench_first_run.py``). Every compilation is
recorded from numba's event API (``numba:compile``): per kernel (dispatcher) the number of
signatures compiled, the inclusive wall time of its compilations when it was the outermost one
(including callees compiled on the way) and its own time (without nested compilations of other
kernels). The table is sorted by own time; the sum of the own times is the total compile time.
With ``--workers 2`` the times of both worker processes and the parent are added up.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_PROFILE = r"""
import json, os, time
from numba.core import event
stack, rec = [], {}
class L(event.Listener):
    def on_start(self, ev):
        stack.append([time.perf_counter(), 0.0, time.process_time(), 0.0])
    def on_end(self, ev):
        t0, nested, c0, cnested = stack.pop()
        dt = time.perf_counter() - t0
        dc = time.process_time() - c0
        f = ev.data["dispatcher"].py_func
        k = f.__module__ + "." + f.__qualname__
        r = rec.setdefault(k, {"n": 0, "self": 0.0, "top": 0.0, "cpu": 0.0, "sigs": []})
        r["n"] += 1
        r["self"] += dt - nested
        r["cpu"] += dc - cnested
        r["sigs"].append(str(ev.data["args"]))
        if stack:
            stack[-1][1] += dt
            stack[-1][3] += dc
        else:
            r["top"] += dt
            r["top_cpu"] = r.get("top_cpu", 0.0) + dc
            path = os.path.join(os.environ["MRD_COMPILE_LOG"], f"{os.getpid()}.json")
            with open(path, "w") as fh:
                json.dump(rec, fh)
event.register("numba:compile", L())
os.register_at_fork(after_in_child=rec.clear)
"""

# Installed in every process of the demo (the parent and its forked or spawned workers).
_SITE = r"""
import os
if os.environ.get("MRD_COMPILE_LOG"):
    exec(compile(open(os.environ["MRD_PROFILE_CODE"]).read(), "profile", "exec"))
"""


def merge(logdir: Path) -> dict[str, dict]:
    """Per-kernel compile records of every process that wrote to ``logdir``, added up."""
    out: dict[str, dict] = {}
    for p in sorted(logdir.glob("*.json")):
        for k, r in json.loads(p.read_text()).items():
            m = out.setdefault(k, {"n": 0, "self": 0.0, "top": 0.0, "cpu": 0.0, "sigs": []})
            m["n"] += r["n"]
            m["cpu"] += r["cpu"]
            m["top_cpu"] = m.get("top_cpu", 0.0) + r.get("top_cpu", 0.0)
            m["self"] += r["self"]
            m["top"] += r["top"]
            m["sigs"] += r["sigs"]
    return out


def _cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def profile_env(root: Path, logdir: Path) -> dict[str, str]:
    """Environment that makes every Python process started with it (and its children) record
    its numba compilations into ``logdir`` (through a ``sitecustomize`` module in ``root``)."""
    logdir.mkdir()
    code = root / "profile.py"
    code.write_text(_PROFILE)
    boot = root / "boot"
    boot.mkdir(exist_ok=True)
    (boot / "sitecustomize.py").write_text(_SITE)
    path = os.environ.get("PYTHONPATH", "")
    return {
        "MRD_COMPILE_LOG": str(logdir),
        "MRD_PROFILE_CODE": str(code),
        "PYTHONPATH": os.pathsep.join(p for p in (str(boot), path) if p),
    }


def _run(args: list[str], cache: Path, logdir: Path, root: Path) -> tuple[float, float]:
    env = dict(os.environ)
    env.update(profile_env(root, logdir))
    env.update(
        NUMBA_CACHE_DIR=str(cache),
        MPLBACKEND="Agg",
        OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"),
    )
    c0 = _cpu()
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "mrdamper", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=root,
        check=False,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
        raise SystemExit(f"demo failed (exit {proc.returncode})")
    return wall, _cpu() - c0


def _numba_version() -> str:
    import numba

    return str(numba.__version__)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="the full demo instead of --quick")
    ap.add_argument("--workers", type=int, default=1, help="worker processes of the demo")
    ap.add_argument("--signatures", action="store_true", help="list every compiled signature")
    ap.add_argument("--models", help="comma-separated model kinds (default: the demo's)")
    ap.add_argument("--json", type=Path, help="also write the per-kernel records to this file")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-compile-") as tmp:
        root = Path(tmp)
        cache = root / "cache"
        cache.mkdir()
        base = ["demo", "--no-progress", "--workers", str(args.workers)]
        base += [] if args.full else ["--quick"]
        base += ["--models", args.models] if args.models else []
        first = _run([*base, "--out", str(root / "out1")], cache, root / "log1", root)
        rec1 = merge(root / "log1")
        second = _run([*base, "--out", str(root / "out2")], cache, root / "log2", root)
        rec2 = merge(root / "log2")
    mode = ("demo" if args.full else "demo --quick") + (
        f" --models {args.models}" if args.models else ""
    )
    print(
        f"python {sys.version.split()[0]}, numba {_numba_version()}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f} (1 min, at the end); `mrdamper {mode}`, "
        f"{args.workers} worker(s)\n"
    )
    print(
        "| kernel | signatures | own compile CPU [s] | own compile wall [s] "
        "| as outermost compile, incl. callees: CPU [s] |"
    )
    print("|---|---|---|---|---|")
    for k, r in sorted(rec1.items(), key=lambda kv: -kv[1]["cpu"]):
        print(
            f"| {k.removeprefix('mrdamper.')} | {r['n']} | {r['cpu']:.2f} | {r['self']:.2f} "
            f"| {r.get('top_cpu', 0.0):.2f} |"
        )
        if args.signatures:
            for sig in r["sigs"]:
                print(f"|   {sig} | | | | |")
    for label, (wall, cpu), rec in (
        (f"first `{mode}` (empty cache)", first, rec1),
        (f"second `{mode}` (cache filled)", second, rec2),
    ):
        print(
            f"\n{label}: {wall:.1f} s wall, {cpu:.1f} s CPU; compiling "
            f"{sum(r['n'] for r in rec.values())} signatures of {len(rec)} functions, "
            f"{sum(r['cpu'] for r in rec.values()):.1f} s CPU / "
            f"{sum(r['self'] for r in rec.values()):.1f} s wall",
            end="",
        )
    print(
        f"\nratio first / second: {first[0] / second[0]:.2f} wall, {first[1] / second[1]:.2f} CPU"
    )
    if args.json:
        args.json.write_text(json.dumps({"first": rec1, "second": rec2}, indent=1))


if __name__ == "__main__":
    main()
