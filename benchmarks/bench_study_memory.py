"""Peak memory of the study's own process: records read by the workers or all read first.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_study_memory.py            # full Table II
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_study_memory.py --quick    # seconds
    python benchmarks/bench_study_memory.py --scale 0.5 --models sp1 --workers 2 --cache /tmp/m

A Table II design of experiments is written once by ``mrdamper rig doe --format parquet``
(``--scale`` of the durations, 1 kHz, seed 0) into ``--cache``. A campaign of ``k`` copies
(``--copies``) is a folder holding every record file ``k`` times under other names (links, so
``k`` times the records and samples; metadata is stored in the files). The same study (``doe``
preset, ``--models``, ``--workers`` local processes, seed 0) then runs on each campaign twice, each
time in a fresh Python process, on records from ``mrdamper.study.study_records``:

* ``parent``: every record read into this process first and shared with the workers (the way
  studies of files ran before records could be read by the workers);
* ``worker``: the process reads each file once for its header, then the fit and simulation
  tasks read what they use; the study's process holds the analysis and figure records only.

For each it prints the peak resident memory of the study's process
(``resource.getrusage(RUSAGE_SELF).ru_maxrss`` at its end), the same for its worker processes
(``RUSAGE_CHILDREN``: the largest one), the wall time, and whether the two runs gave identical
results (``results.csv`` without timing columns). The ratio worker / parent is the number to
compare, and how each grows with the campaign; absolute numbers depend on the machine and its
load.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

MODES = ("parent", "worker")

_CHILD = r"""
import hashlib, json, resource, sys, time
from mrdamper.study import doe_protocol, run_study, study_records
from mrdamper.study.tables import TIMING_COLUMNS
folder, mode, models, workers = sys.argv[1], sys.argv[2], sys.argv[3].split(","), int(sys.argv[4])
t0 = time.perf_counter()
records = study_records(folder, load=mode)
res = run_study(records, doe_protocol(), models, workers=workers, seed=0, progress=False)
wall = time.perf_counter() - t0
strip = [c for c in res.results.columns if c not in TIMING_COLUMNS]
digest = hashlib.sha256(res.results[strip].to_csv(index=False).encode()).hexdigest()
kib = 1024.0 if sys.platform != "darwin" else 1.0  # ru_maxrss: KiB on Linux, bytes on macOS
print(json.dumps({
    "mode": mode,
    "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * kib / 2**20,
    "child_rss_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * kib / 2**20,
    "wall_s": wall,
    "records": len(records),
    "samples": int(sum(e.n for e in records)),
    "digest": digest,
}))
"""


def _ensure_doe(cache: Path, scale: float) -> Path:
    folder = cache / f"doe_parquet_scale{scale:g}"
    if (folder / "manifest.csv").is_file():
        return folder
    cmd = [
        sys.executable,
        "-m",
        "mrdamper",
        "rig",
        "doe",
        "--out",
        str(folder),
        "--format",
        "parquet",
        "--scale",
        str(scale),
        "--no-progress",
    ]
    subprocess.run(cmd, check=True)
    return folder


def _campaign(doe: Path, copies: int) -> Path:
    """A folder with every record file of ``doe`` ``copies`` times (hard or symbolic links)."""
    if copies == 1:
        return doe
    folder = doe.parent / f"{doe.name}_x{copies}"
    if folder.is_dir():
        return folder
    tmp = doe.parent / f".{folder.name}.partial"
    tmp.mkdir()
    for f in sorted(doe.glob("*.parquet")):
        for k in range(copies):
            link = tmp / f"c{k}_{f.name}"
            try:
                os.link(f, link)
            except OSError:
                link.symlink_to(f.resolve())
    tmp.rename(folder)
    return folder


def _run(folder: Path, mode: str, models: str, workers: int) -> dict[str, object]:
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, str(folder), mode, models, str(workers)],
        check=True,
        capture_output=True,
        text=True,
    )
    out: dict[str, object] = json.loads(proc.stdout.strip().splitlines()[-1])
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="durations x 0.07, one model")
    ap.add_argument("--scale", type=float, default=1.0, help="duration scale of Table II")
    ap.add_argument("--models", default="sp1,bingham", help="comma-separated model kinds")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes")
    ap.add_argument("--cache", type=Path, default=None, help="folder for the generated DoE")
    ap.add_argument("--copies", type=int, nargs="+", default=[1, 3], help="campaign sizes")
    args = ap.parse_args(argv)
    scale = 0.07 if args.quick else args.scale
    models = "bingham" if args.quick else args.models
    copies = [1, 2] if args.quick else args.copies
    rows = []
    with tempfile.TemporaryDirectory(prefix="mrdamper-bench-mem-") as tmp:
        cache = args.cache or Path(tmp)
        cache.mkdir(parents=True, exist_ok=True)
        doe = _ensure_doe(cache, scale)
        for k in copies:
            folder = _campaign(doe, k)
            for mode in MODES:
                rows.append({"copies": k, **_run(folder, mode, models, args.workers)})
    print(f"Table II at scale {scale:g} (Parquet), models {models}, {args.workers} worker(s)")
    head = f"{'copies':>6}{'records':>9}{'samples [M]':>13}{'load':>8}"
    print(head + f"{'study RSS [MB]':>16}{'worker RSS [MB]':>17}{'wall [s]':>10}")
    for r in rows:
        print(
            f"{r['copies']:>6}{r['records']:>9}{int(r['samples']) / 1e6:>13.2f}{r['mode']!s:>8}"  # type: ignore[call-overload]
            f"{float(r['rss_mb']):>16.0f}{float(r['child_rss_mb']):>17.0f}"  # type: ignore[arg-type]
            f"{float(r['wall_s']):>10.1f}"  # type: ignore[arg-type]
        )
    ok = True
    for k in copies:
        par, wrk = (r for r in rows if r["copies"] == k)
        ratio = float(wrk["rss_mb"]) / float(par["rss_mb"])  # type: ignore[arg-type]
        same = par["digest"] == wrk["digest"]
        ok = ok and same
        print(
            f"{k} cop{'y' if k == 1 else 'ies'}: study RSS worker / parent {ratio:.2f}; "
            f"identical results: {same}"
        )
    if len(copies) > 1:
        lo, hi = copies[0], copies[-1]
        for mode in MODES:
            a, b = (
                float(r["rss_mb"]) for r in rows if r["mode"] == mode and r["copies"] in (lo, hi)
            )  # type: ignore[arg-type]
            print(f"{mode}: study RSS grows by {b - a:.0f} MB from {lo} to {hi} copies")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
