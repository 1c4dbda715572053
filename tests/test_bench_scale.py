"""``benchmarks/bench_scale.py --quick`` runs end to end (two kinds, short records).

The benchmark's numbers are not checked here (timings are not test material); the test checks
that every fit ran in its own process and reported its time, peak memory and the log-log slope.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_scale.py"


def _run(tmp_path: Path, *args: str) -> tuple[subprocess.CompletedProcess[str], list[dict]]:
    """Run the benchmark with ``args`` (cache and JSON output in ``tmp_path``); its rows."""
    if not BENCH.is_file():
        pytest.skip(f"{BENCH} not found (tests not run from a source checkout)")
    out = tmp_path / "rows.json"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, str(BENCH), *args, "--cache", str(tmp_path / "cache"), "--json", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc, json.loads(out.read_text())


@pytest.mark.slow
def test_bench_scale_quick(tmp_path: Path) -> None:
    proc, rows = _run(tmp_path, "--quick", "--kinds", "bingham", "lti")
    assert [(r["kind"], r["length_s"]) for r in rows] == [
        ("bingham", 12.0),
        ("bingham", 120.0),
        ("lti", 12.0),
        ("lti", 120.0),
    ]
    for r in rows:
        assert r["status"] == "ok", r
        assert r["n"] == round(r["length_s"] * 1000)
        assert r["fit_s"] > 0 and r["rss_gb"] >= r["rss_before_gb"] > 0
    assert (
        "| bingham |" in proc.stdout and "| lti |" in proc.stdout and "log-log slope" in proc.stdout
    )


@pytest.mark.slow
@pytest.mark.parametrize("source", ["parquet-file", "csv-folder"])
def test_bench_scale_reads_files_as_the_cli_does(tmp_path: Path, source: str) -> None:
    pytest.importorskip("pyarrow")
    _, rows = _run(
        tmp_path, "--lengths", "12", "30", "--record", "20", "--kinds", "sp1", "--source", source
    )
    assert [(r["kind"], r["length_s"], r["source"]) for r in rows] == [
        ("sp1", 12.0, source),
        ("sp1", 30.0, source),
    ]
    for r in rows:
        assert r["status"] == "ok", r
        assert r["n"] == round(r["length_s"] * 1000)  # every sample came through the reader
        assert r["read_s"] > 0
    folder = next((tmp_path / "cache").glob(f"*/{source}-30s"))
    files = sorted(p.name for p in folder.rglob("*") if p.is_file() and p.name != "done")
    # 30 s of 20 s records: one file for the whole length, or one file per record
    assert files == (
        ["campaign.parquet"] if source == "parquet-file" else ["rec00.csv", "rec01.csv"]
    )
