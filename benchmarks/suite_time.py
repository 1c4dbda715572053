"""The test suite's size and wall-clock time, stored as ``results/test-suite.json``.

Usage::

    python benchmarks/suite_time.py --scope full            # runs the README's test command
    python benchmarks/suite_time.py --scope "not slow"      # the quick loop
    bash .ci/run 2>&1 | tee ci.log                          # or: time a clean clone's CI ...
    python benchmarks/suite_time.py --scope full --log ci.log --wall 640 --command "bash .ci/run"

Without ``--log`` the script runs the README's test command (``python3 -m pytest -n auto --dist
worksteal``, with ``-m "not slow"`` for that scope) from the repository root, measures its
wall-clock time and reads the count of tests from pytest's summary line. With ``--log`` it reads
that summary line from a saved log instead and takes the wall time from ``--wall`` (seconds;
pytest's own ``in N s`` figure when ``--wall`` is not given). Either way it replaces that scope's
row of ``results/test-suite.json`` and keeps the other scope's row, each row with its own commit,
date and load, so that the README's sentence on the suite (``<!-- results:suite -->``) is rendered
from what was measured.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from _results import RESULTS, current_commit, write_result

REPO = Path(__file__).resolve().parents[1]
NAME = "test-suite"
SCOPES = ("full", "not slow")
#: pytest's last line: "1635 passed, 1 skipped, 3 warnings in 631.12s (0:10:31)".
SUMMARY = re.compile(r"(?P<counts>(?:\d+ \w+(?:, )?)+) in (?P<secs>[0-9.]+)s")


def parse_summary(text: str) -> tuple[dict[str, int], float]:
    """Counts by outcome and pytest's own seconds from the last summary line of ``text``.

    Raises
    ------
    ValueError
        When ``text`` holds no pytest summary line.
    """
    found = None
    for line in text.splitlines():
        m = SUMMARY.search(line)
        if m and ("passed" in line or "failed" in line):
            found = m
    if found is None:
        raise ValueError("log: no pytest summary line ('N passed ... in S s') found")
    counts = {}
    for part in found.group("counts").split(", "):
        n, outcome = part.split(" ", 1)
        counts[outcome.strip()] = int(n)
    return counts, float(found.group("secs"))


def command_for(scope: str) -> list[str]:
    """The README's test command for ``scope``."""
    cmd = [sys.executable, "-m", "pytest", "-n", "auto", "--dist", "worksteal"]
    return cmd + (["-m", "not slow"] if scope == "not slow" else [])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scope", choices=SCOPES, required=True)
    ap.add_argument("--log", type=Path, help="read pytest's summary from this log (no run)")
    ap.add_argument("--wall", type=float, help="with --log: the wall-clock time [s]")
    ap.add_argument("--command", help="with --log: the command that wrote the log")
    ap.add_argument("--commit", help="with --log: the commit the log was made at")
    ap.add_argument("--load", type=float, help="with --log: the 1-minute load average then")
    ap.add_argument("--note", default="", help="where it ran (for example: a clean clone)")
    args = ap.parse_args(argv)
    if args.log is None:
        cmd = command_for(args.scope)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, check=False, cwd=REPO, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        text = proc.stdout
        command = " ".join(["python3", *cmd[1:]]).replace("-m not slow", '-m "not slow"')
    else:
        text = args.log.read_text(encoding="utf-8", errors="replace")
        wall = args.wall
        command = args.command or f"python3 -m pytest -n auto --dist worksteal ({args.scope})"
    counts, secs = parse_summary(text)
    row = {
        "scope": args.scope,
        "tests": sum(v for k, v in counts.items() if k in ("passed", "failed", "skipped")),
        "passed": counts.get("passed", 0),
        "failed": counts.get("failed", 0),
        "skipped": counts.get("skipped", 0),
        "wall_s": round(wall if wall is not None else secs, 1),
        "pytest_s": round(secs, 1),
        "commit": args.commit or current_commit(),
        "load_avg_1min": round(args.load if args.load is not None else os.getloadavg()[0], 2),
        "note": args.note,
        "command": command,
    }
    path = RESULTS / f"{NAME}.json"
    rows = []
    if path.is_file():
        rows = [r for r in json.loads(path.read_text())["rows"] if r["scope"] != args.scope]
    rows = sorted([*rows, row], key=lambda r: SCOPES.index(r["scope"]))
    write_result(
        NAME,
        rows,
        folder=RESULTS,
        command="python benchmarks/suite_time.py --scope SCOPE [--log LOG --wall S]",
        measures=(
            "the test suite: tests collected and their outcome, wall-clock time of the test "
            "command [s] (wall_s) and pytest's own figure [s] (pytest_s), per scope; each row "
            "with the commit, load and command it was measured with"
        ),
    )
    print(f"{args.scope}: {row['tests']} tests, {row['wall_s']} s wall, failed {row['failed']}")
    return 0 if row["failed"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
