"""The summary of ``benchmarks/select_tasks.py``: CPU per kind, round one apart, and how busy
each worker was, from a task log whose answers are known."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import load_benchmark


def _row(kind: str, task: str, pid: int, start: float, end: float, cpu: float) -> dict:
    return {"kind": kind, "task": task, "pid": pid, "start": start, "end": end, "cpu": cpu}


ROWS = [
    _row("boucwen", "block 1/5", 1, 0.0, 60.0, 50.0),
    _row("boucwen", "beyond: later block", 2, 0.0, 30.0, 25.0),
    _row("sp1", "block 1/5", 2, 30.0, 40.0, 5.0),
    _row("sp1", "beyond: later block", 2, 40.0, 50.0, 5.0),
    _row("boucwen", "block 2/5", 2, 50.0, 100.0, 45.0),
    _row("sp1", "block 2/5", 1, 60.0, 70.0, 4.0),
    _row("sp1", "stress", 1, 70.0, 80.0, 6.0),
]


def test_cpu_per_kind_with_round_one_apart_and_worker_shares() -> None:
    bench = load_benchmark("select_tasks")
    s = bench.summarise(ROWS)
    assert s["total_task_cpu_s"] == pytest.approx(140.0)
    bw, sp1 = s["kinds"]["boucwen"], s["kinds"]["sp1"]
    assert (bw["cpu_s"], bw["round_one_cpu_s"], bw["tasks"]) == (120.0, 75.0, 3)
    assert (sp1["cpu_s"], sp1["round_one_cpu_s"], sp1["tasks"]) == (20.0, 10.0, 4)
    assert bw["share"] == pytest.approx(120.0 / 140.0)
    assert s["span_s"] == 100.0
    # worker 1: 60 + 10 + 10 of 100 s; worker 2: 30 + 10 + 10 + 50
    assert s["worker_busy_share"] == {"1": pytest.approx(0.8), "2": pytest.approx(1.0)}


def test_a_log_is_summarised_again_without_running(tmp_path: Path, capsys) -> None:
    bench = load_benchmark("select_tasks")
    log = tmp_path / "tasks.jsonl"
    log.write_text("".join(json.dumps(r) + "\n" for r in ROWS))
    out = tmp_path / "summary.json"
    bench.main(["--from-log", str(log), "--json", str(out)])
    printed = capsys.readouterr().out
    assert "total task CPU 140.0 s over a span of 100.0 s" in printed
    assert printed.index("boucwen") < printed.index("sp1")  # the costliest kind first
    assert json.loads(out.read_text())["kinds"]["sp1"]["cpu_s"] == 20.0
