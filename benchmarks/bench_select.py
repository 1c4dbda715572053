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

Every row is also written, with the load average (``os.getloadavg``) before and after each run,
the UTC date, each side's per-kind table (``select --csv``: mean fit time ``fit_s``, ``rank_esr``,
status) and the command, to a JSON file (``--json``, default ``bench_select.json`` in the working
folder; written atomically, rewritten after every row), so that the numbers can be rendered
later without parsing the printout.
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
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


def _table(path: Path) -> list[dict[str, str]]:
    """The rows of a ``select --csv`` table (empty when the side wrote none)."""
    if not path.exists():
        return []
    with path.open(newline="") as fh:
        return [
            {k: row[k] for k in ("model", "fit_s", "rank_esr", "status") if k in row}
            for row in csv.DictReader(fh)
        ]


def _run(src: Path, data: Path, kind: str, workdir: Path) -> dict[str, object]:
    """One select in a fresh process: ``wall`` [s], ``cpu`` [s] (process and workers),
    ``recommended``, the load averages before and after, and the per-kind ``table``."""
    env = {**os.environ, "PYTHONPATH": str(src), "OPENBLAS_NUM_THREADS": "1"}
    table = workdir / "bench-select-table.csv"
    table.unlink(missing_ok=True)
    cmd = [sys.executable, "-m", "mrdamper", "select", str(data), "--no-progress"]
    cmd += ["--csv", str(table), "--force"]
    if kind != "all":
        cmd += [arg for k in kind.split(",") for arg in ("-m", k)]
    load_before = os.getloadavg()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, check=False, env=env, cwd=workdir, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rec = [ln for ln in proc.stdout.splitlines() if ln.startswith("recommended:")]
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "recommended": rec[0].split(":")[1].strip() if rec else "-",
        "load_before": list(load_before),
        "load_after": list(os.getloadavg()),
        "table": _table(table),
    }


def _write_json(path: Path, doc: dict[str, object]) -> None:
    """Write ``doc`` to ``path`` atomically (a temporary file beside it, then a rename)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    os.replace(tmp, path)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sets", nargs="+", default=list(SETS), choices=list(SETS))
    ap.add_argument("--kinds", nargs="+", default=["all"], help="kinds, or 'all' (every kind)")
    ap.add_argument("--previous", type=Path, help="checkout of the previous release")
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--reduce", action="store_true", help="every third record, 7 s of Dyke")
    ap.add_argument("--no-warm", action="store_true", help="no untimed compilation first")
    ap.add_argument("--json", type=Path, default=Path("bench_select.json"), help="JSON record")
    args = ap.parse_args(argv)
    doc: dict[str, object] = {
        "benchmark": "bench_select",
        "command": " ".join(["python", "benchmarks/bench_select.py", *(argv or sys.argv[1:])]),
        "date_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "cpus": os.cpu_count(),
        "rows": [],
    }
    rows: list[dict[str, object]] = doc["rows"]  # type: ignore[assignment]
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
                runs: dict[str, list[dict[str, object]]] = {s: [] for s in sides}
                for _ in range(args.repeat):
                    for side, src in sides.items():
                        run = _run(src, data, kind, Path(tmp))
                        walls[side].append(float(run["wall_s"]))  # type: ignore[arg-type]
                        cpus[side].append(float(run["cpu_s"]))  # type: ignore[arg-type]
                        recs[side] = str(run["recommended"])
                        runs[side].append(run)
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
                rows.append(
                    {
                        "set": name,
                        "data": SETS[name] + (" (reduced)" if args.reduce else ""),
                        "kinds": kind,
                        "median_wall_s": med,
                        "median_cpu_s": {s: statistics.median(v) for s, v in cpus.items()},
                        "ratio": ratio,
                        "recommended": recs,
                        "runs": runs,
                    }
                )
                _write_json(args.json, doc)


if __name__ == "__main__":
    main()
