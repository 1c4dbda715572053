"""``mrdamper select`` on the three shared sets, per kind and for every kind, side by side with a
previous release, in the same run.

Usage::

    mkdir -p /tmp/mrdamper-prev && git archive abf5e8f src | tar -x -C /tmp/mrdamper-prev
    python benchmarks/bench_select.py --previous /tmp/mrdamper-prev
    # reduced inputs (a few minutes on a shared machine):
    python benchmarks/bench_select.py --previous /tmp/mrdamper-prev --reduce --kinds bingham sp1
    python benchmarks/bench_select.py --sets dyke --kinds all      # every kind at once only
    python benchmarks/bench_select.py --previous /tmp/mrdamper-prev --reduce --kinds sp1,tanh

For every set (``labcontrol``: ``labcontrol2021_utfpr/train``, 23 records; ``quiroz``:
``quiroz2022_utfsm/sine_unfiltered``, 30 records; ``dyke``: ``dyke1996_nees/ranran_50.csv``) and
every entry of ``--kinds`` (a kind; several joined by commas, compared in one command, where
successive halving acts between them; ``all``: the command's default, every kind at once),
``mrdamper select DATA -m KIND`` runs in a fresh process with this checkout's ``src`` on
``PYTHONPATH`` and, with ``--previous``, the same command with that checkout's ``src``, one after
the other, ``--repeat`` times. It prints the median wall time of each side, their ratio
(previous / this), the CPU time of the process and its workers, and the recommendation of each
side. Both sides find their compiled kernels cached: every kind's kernels are compiled first,
untimed (``--no-warm`` skips that). ``--reduce`` takes every third record of a folder and the
first 7 s of the Dyke record (written to a temporary folder), so that a run takes minutes on a
shared machine. The data folder is ``--data`` (default ``../shared/data`` beside the checkout).
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
SETS = {
    "labcontrol": "labcontrol2021_utfpr/train",
    "quiroz": "quiroz2022_utfsm/sine_unfiltered",
    "dyke": "dyke1996_nees/ranran_50.csv",
}


def _reduced(path: Path, tmp: Path) -> Path:
    """Every third record of a folder, or the first 7 s of one record, in ``tmp``."""
    out = tmp / path.stem
    out.mkdir()
    if path.is_dir():
        for f in sorted(path.glob("*.csv"))[::3]:
            (out / f.name).symlink_to(f.resolve())
        return out
    lines = path.read_text().splitlines()
    fs = 1.0 / float(lines[2].split(",")[0])  # the second sample's time [s]
    (out / path.name).write_text("\n".join(lines[: int(7 * fs) + 1]) + "\n")
    return out


_WARM = (
    "import tempfile; from mrdamper import compiled; from mrdamper.models import available_models; "
    "compiled.compile_claimed(available_models(), tempfile.mkdtemp())"
)


def _warm(src: Path) -> None:
    """Compile and cache every kind's kernels for the checkout ``src`` (untimed)."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    subprocess.run([sys.executable, "-c", _WARM], check=True, env=env)


def _run(src: Path, data: Path, kind: str, workdir: Path) -> tuple[float, float, str]:
    """Wall time [s], CPU time [s] (process and workers) and recommendation of one select."""
    env = {**os.environ, "PYTHONPATH": str(src), "OPENBLAS_NUM_THREADS": "1"}
    cmd = [sys.executable, "-m", "mrdamper", "select", str(data), "--no-progress"]
    if kind != "all":
        cmd += [arg for k in kind.split(",") for arg in ("-m", k)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, check=False, env=env, cwd=workdir, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rec = [ln for ln in proc.stdout.splitlines() if ln.startswith("recommended:")]
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return wall, cpu, rec[0].split(":")[1].strip() if rec else "-"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sets", nargs="+", default=list(SETS), choices=list(SETS))
    ap.add_argument("--kinds", nargs="+", default=["all"], help="kinds, or 'all' (every kind)")
    ap.add_argument("--previous", type=Path, help="checkout of the previous release")
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--reduce", action="store_true", help="every third record, 7 s of Dyke")
    ap.add_argument("--no-warm", action="store_true", help="no untimed compilation first")
    args = ap.parse_args(argv)
    sides = {"this": REPO / "src"}
    if args.previous is not None:
        sides = {"previous": args.previous.resolve() / "src", **sides}
    width = max(8, *(len(k) for k in args.kinds))
    print(f"{'set':<11} {'kind':<{width}} " + " ".join(f"{s + ' [s]':>14}" for s in sides), end="")
    print(f" {'ratio':>6} " + " ".join(f"{s + ' cpu':>12}" for s in sides) + "  recommended")
    if not args.no_warm:
        for src in sides.values():
            _warm(src)
    with tempfile.TemporaryDirectory(prefix="mrdamper-bench-select-") as tmp:
        for name in args.sets:
            data = args.data / SETS[name]
            if args.reduce:
                data = _reduced(data, Path(tmp))
            for kind in args.kinds:
                walls: dict[str, list[float]] = {s: [] for s in sides}
                cpus: dict[str, list[float]] = {s: [] for s in sides}
                recs: dict[str, str] = {}
                for _ in range(args.repeat):
                    for side, src in sides.items():
                        wall, cpu, rec = _run(src, data, kind, Path(tmp))
                        walls[side].append(wall)
                        cpus[side].append(cpu)
                        recs[side] = rec
                med = {s: statistics.median(v) for s, v in walls.items()}
                ratio = med["previous"] / med["this"] if "previous" in med else float("nan")
                print(
                    f"{name:<11} {kind:<{width}} "
                    + " ".join(f"{med[s]:>14.1f}" for s in sides)
                    + f" {ratio:>6.2f} "
                    + " ".join(f"{statistics.median(cpus[s]):>12.1f}" for s in sides)
                    + "  "
                    + " / ".join(recs[s] for s in sides),
                    flush=True,
                )


if __name__ == "__main__":
    main()
