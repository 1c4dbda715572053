"""Where the time of ``mrdamper select`` goes: every fit task timed, per kind and per fold.

Usage::

    python benchmarks/select_tasks.py ../shared/data/dyke1996_nees/ranran_50.csv
    python benchmarks/select_tasks.py ../shared/data/labcontrol2021_utfpr/train -- -m sp1 -m tanh
    python benchmarks/select_tasks.py --from-log select_tasks.jsonl     # summarise a log again

Runs ``mrdamper select DATA [OPTIONS after --]`` in this process (its workers forked from it) with
the runner's two task functions (:func:`mrdamper.study._select_run.fold_task`, one fold's fit
and scoring; :func:`~mrdamper.study._select_run.stress_task`, the fit on every record and its
stress test) wrapped so that each appends one line to a JSON-lines log (``--log``, default
``select_tasks.jsonl``): kind, task (fold label or ``stress``), worker process, start and end
[s from the start] and the task's own CPU time [s] (``resource.getrusage`` in the worker, so it
holds on a loaded machine, where wall times do not). Then it prints, per kind, the CPU time of
its tasks (round one, the first in-envelope and beyond-envelope fold, apart) and its share of
the total, and per worker its busy time against the run's span (a worker that waits shows a
low share), with the load average; the summary is also written as JSON (``--json``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _wrap(log: Path, t0: float) -> None:
    """Replace the runner's task functions by timed ones (forked workers inherit them)."""
    import mrdamper.study._select_run as sr

    fold_task, stress_task = sr.fold_task, sr.stress_task

    def write(kind: str, task: str, start: float, cpu: float, extra: dict[str, Any]) -> None:
        row = {"kind": kind, "task": task, "pid": os.getpid(), "start": start - t0}
        row.update(end=time.time() - t0, cpu=_cpu() - cpu, **extra)
        with log.open("a") as fh:
            fh.write(json.dumps(row) + "\n")

    def timed_fold(kind: str, options: Any, fold: Any, train: Any, test: Any, where: str) -> Any:
        start, cpu = time.time(), _cpu()
        out = fold_task(kind, options, fold, train, test, where)
        write(kind, str(fold[0]), start, cpu, {"esr": [r["esr"] for r in out[0]]})
        return out

    def timed_stress(kind: str, options: Any, records: Any, where: str, seed: int) -> Any:
        start, cpu = time.time(), _cpu()
        out = stress_task(kind, options, records, where, seed)
        write(kind, "stress", start, cpu, {})
        return out

    for fn in (timed_fold, timed_stress):  # picklable by name, as module-level functions
        fn.__module__, fn.__qualname__ = __name__, fn.__name__
    globals()["timed_fold"], globals()["timed_stress"] = timed_fold, timed_stress
    sr.fold_task, sr.stress_task = timed_fold, timed_stress  # type: ignore[assignment]


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per-kind CPU time (round one apart), per-worker busy share, totals."""
    kinds: dict[str, dict[str, float]] = defaultdict(lambda: {"cpu_s": 0.0, "round_one_cpu_s": 0.0})
    firsts: dict[str, set[str]] = defaultdict(set)
    for r in sorted(rows, key=lambda r: r["start"]):
        k = kinds[r["kind"]]
        k["cpu_s"] += r["cpu"]
        k["tasks"] = k.get("tasks", 0) + 1
        beyond = r["task"].startswith("beyond")
        tag = "beyond" if beyond else ("stress" if r["task"] == "stress" else "inside")
        if tag != "stress" and tag not in firsts[r["kind"]]:
            firsts[r["kind"]].add(tag)
            k["round_one_cpu_s"] += r["cpu"]
    total = sum(k["cpu_s"] for k in kinds.values())
    span = max(r["end"] for r in rows) - min(r["start"] for r in rows) if rows else 0.0
    workers: dict[int, float] = defaultdict(float)
    for r in rows:
        workers[r["pid"]] += r["end"] - r["start"]
    return {
        "total_task_cpu_s": total,
        "span_s": span,
        "kinds": {k: dict(v, share=v["cpu_s"] / total if total else 0.0) for k, v in kinds.items()},
        "worker_busy_share": {str(p): b / span if span else 0.0 for p, b in workers.items()},
    }


def _print(summary: dict[str, Any]) -> None:
    print(f"{'kind':<9} {'tasks':>5} {'CPU [s]':>8} {'share':>6} {'round one CPU [s]':>18}")
    order = sorted(summary["kinds"].items(), key=lambda kv: -kv[1]["cpu_s"])
    for kind, k in order:
        print(
            f"{kind:<9} {int(k['tasks']):>5} {k['cpu_s']:>8.1f} {k['share']:>6.1%} "
            f"{k['round_one_cpu_s']:>18.1f}"
        )
    total, span = summary["total_task_cpu_s"], summary["span_s"]
    print(f"total task CPU {total:.1f} s over a span of {span:.1f} s")
    for pid, share in summary["worker_busy_share"].items():
        print(f"worker {pid}: busy {share:.1%} of the span")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", nargs="?", help="records, as given to mrdamper select")
    ap.add_argument("select_args", nargs="*", help="further select options (after --)")
    ap.add_argument("--log", type=Path, default=Path("select_tasks.jsonl"))
    ap.add_argument("--json", type=Path, default=Path("select_tasks.json"))
    ap.add_argument("--from-log", type=Path, help="summarise this log; run nothing")
    args = ap.parse_args(argv)
    load = [os.getloadavg()]
    if args.from_log is None:
        if not args.data:
            ap.error("give DATA or --from-log")
        args.log.unlink(missing_ok=True)
        _wrap(args.log, time.time())
        from mrdamper.cli.launch import main as cli

        wall0 = time.perf_counter()
        try:
            cli(["select", args.data, "--no-progress", *args.select_args])
        except SystemExit as done:  # the command's own exit (1: nothing recommended)
            if done.code not in (0, 1, None):
                raise
        wall = time.perf_counter() - wall0
        load.append(os.getloadavg())
        print(f"select: {wall:.1f} s wall; load average {load[0][0]:.1f} -> {load[1][0]:.1f}")
    log = args.from_log or args.log
    rows = [json.loads(line) for line in log.read_text().splitlines() if line.strip()]
    summary = summarise(rows)
    summary.update(command=" ".join(sys.argv), load_average=[list(x) for x in load], log=str(log))
    _print(summary)
    tmp = args.json.with_name(args.json.name + ".tmp")
    tmp.write_text(json.dumps(summary, indent=1) + "\n")
    os.replace(tmp, args.json)


if __name__ == "__main__":
    main()
