"""Closed-loop fidelity on the documented command-line path, stored under ``results/``.

Runs, in a temporary folder and each in a fresh process, the recipe of ``docs/control.md``
("The documented recipe"):

    mrdamper rig doe --out doe-ctrl --scale SCALE --extension control --force
    mrdamper fit lpv doe-ctrl --out lpv.json --force
    mrdamper quartercar lpv.json --plant rig --roads B,C,D --speed SPEED --seed SEED \\
        --out cl-SPEED-SEED --force          # for SPEED in 10, 25 and SEED in 0, 1, 2

(``--extension none``: the same on Table II alone) and writes every ``closed_loop.csv`` row
(with its ``seed`` and the ``outside_stroke`` flag the
command writes) to ``OUT``, a CSV whose ``#`` header lines give the command, the commit, the UTC
date, the load average and the recipe. It prints the summary
(:func:`mrdamper.control.loop.stroke_cells.fidelity_summary`): per metric, the worst |error|
over the cells the rig's stroke covers and over those outside it, against the targets.

Run (about 5 min of CPU time at ``--scale 0.1``)::

    PYTHONPATH=src python3 benchmarks/closed_loop_cli.py --scale 0.1 \\
        --out results/closed_loop_tenth.csv
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd
from _results import current_commit

from mrdamper.control.loop.stroke_cells import fidelity_summary

REPO = Path(__file__).resolve().parents[1]
SPEEDS = (10, 25)
SEEDS = (0, 1, 2)
ROADS = "B,C,D"


def recipe(
    scale: float,
    speeds=SPEEDS,
    seeds=SEEDS,
    roads: str = ROADS,
    extension: str = "control",
    kind: str = "lpv",
) -> list[list[str]]:
    """The command lines of the recipe (arguments after ``mrdamper``; ``extension="none"``: the
    same on Table II alone; ``kind``: the model kind fitted with its defaults)."""
    model = f"{kind}.json"
    cmds = [
        ["rig", "doe", "--out", "doe-ctrl", "--scale", f"{scale:g}", "--extension", extension],
        ["fit", kind, "doe-ctrl", "--out", model],
    ]
    for sp in speeds:
        for s in seeds:
            cmds.append(
                ["quartercar", model, "--plant", "rig", "--roads", roads, "--speed", str(sp)]
                + ["--seed", str(s), "--out", f"cl-{sp}-{s}"]
            )
    return [c + ["--force"] for c in cmds]


def run_recipe(
    folder: Path,
    scale: float,
    speeds=SPEEDS,
    seeds=SEEDS,
    roads: str = ROADS,
    extension: str = "control",
    kind: str = "lpv",
) -> pd.DataFrame:
    """Run the recipe in ``folder``; every ``closed_loop.csv`` row, with its ``seed``."""
    # this checkout's package, whatever the folder the commands run in
    path = os.pathsep.join([str(REPO / "src"), os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path.rstrip(os.pathsep))
    for cmd in recipe(scale, speeds, seeds, roads, extension, kind):
        proc = subprocess.run(
            [sys.executable, "-m", "mrdamper", *cmd],
            cwd=folder,
            capture_output=True,
            text=True,
            env=env,
            check=False,
        )
        if proc.returncode != 0:
            raise SystemExit(f"mrdamper {' '.join(cmd)} failed:\n{proc.stderr}")
    tables = [
        pd.read_csv(folder / f"cl-{sp}-{s}" / "closed_loop.csv").assign(seed=s)
        for sp in speeds
        for s in seeds
    ]
    return pd.concat(tables, ignore_index=True)


def write_table(
    table: pd.DataFrame,
    out: Path,
    scale: float,
    command: str,
    extension: str = "control",
    commit: str | None = None,
    kind: str = "lpv",
) -> None:
    """``table`` as CSV with a ``#`` header (command, commit, date, load, recipe), atomically
    (``commit``: the one the run started at; default the present one)."""
    head = [
        f"# command: {command}",
        f"# commit: {commit or current_commit()}",
        f"# date: {dt.datetime.now(dt.UTC).strftime('%Y-%m-%dT%H:%M:%SZ')}",
        "# load_avg: " + " ".join(f"{x:.2f}" for x in os.getloadavg()),
        f"# cpus: {os.cpu_count()}",
        *(
            f"# recipe: mrdamper {' '.join(c)}"
            for c in recipe(scale, extension=extension, kind=kind)
        ),
    ]
    out.parent.mkdir(parents=True, exist_ok=True)
    text = "\n".join(head) + "\n" + table.to_csv(index=False, float_format="%.6g")
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".partial", dir=out.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def read_table(path: Path) -> pd.DataFrame:
    """A table written by :func:`write_table` (the ``#`` lines skipped)."""
    return pd.read_csv(path, comment="#")


#: How the metrics read in the documentation's table.
LABELS = {
    "a_w": "a_w",
    "rms_acc": "RMS acceleration",
    "rms_tyre_load": "RMS tyre load",
    "rms_travel": "RMS travel",
    "rms_tracking": "force tracking",
    "mean_current": "mean current",
}


def summary_markdown(table: pd.DataFrame) -> str:
    """The summary of ``table`` as the Markdown table ``docs/control.md`` quotes."""
    summ = fidelity_summary(table)
    lines = [
        (
            "| metric | target | worst, cells within the stroke | where | worst, cells beyond it "
            "| where | holds |"
        ),
        "|---|---|---|---|---|---|---|",
    ]
    for r in summ.itertuples():
        target = "-" if pd.isna(r.target_pct) else f"{r.target_pct:g} %"
        lines.append(
            f"| {LABELS.get(r.metric, r.metric)} | {target} | {r.worst_covered_pct:.1f} % "
            f"({r.covered_cells} cells) | {r.where_covered} | {r.worst_outside_pct:.1f} % "
            f"({r.outside_cells} cells) | {r.where_outside} | {r.holds or '-'} |"
        )
    return "\n".join(lines)


def coverage_sentence(table: pd.DataFrame) -> str:
    """How many cells lie beyond the training stroke, per road, as ``docs/control.md`` says it."""
    cells = table.drop_duplicates(["controller", "road", "speed_m_s", "seed"])
    per_road = ", ".join(
        f"ISO {road} {int(g['outside_stroke'].sum())} of {len(g)}"
        for road, g in cells.groupby("road")
    )
    return (
        f"{int(cells['outside_stroke'].sum())} of the {len(cells)} cells ({per_road}; at most "
        f"{cells['stroke_ratio'].max():.2g} times the training span)"
    )


def headline_sentence(table: pd.DataFrame) -> str:
    """The README's figures: the worst |error| [%] per metric group, within and beyond it."""
    summ = fidelity_summary(table).set_index("metric")

    def worst(metrics: tuple[str, ...], column: str) -> str:
        return f"{max(float(summ.loc[m, column]) for m in metrics):.1f} %"

    comfort = ("a_w", "rms_acc", "rms_tyre_load")
    loop = ("rms_travel", "rms_tracking")
    return (
        f"within the stroke, comfort and road holding within {worst(comfort, 'worst_covered_pct')}"
        f" (a_w {worst(('a_w',), 'worst_covered_pct')}), travel and tracking within "
        f"{worst(loop, 'worst_covered_pct')}; beyond it, comfort and road holding within "
        f"{worst(comfort, 'worst_outside_pct')}, travel and tracking within "
        f"{worst(loop, 'worst_outside_pct')}"
    )


def overall_sentence(table: pd.DataFrame) -> str:
    """The worst |error| [%] per metric over every cell, with where it lies."""
    parts = []
    for metric in ("a_w", "rms_acc", "rms_tyre_load", "rms_travel", "rms_tracking"):
        rows = table[table["metric"] == metric].reset_index(drop=True)
        err = rows["error_pct"].abs()
        r = rows.loc[err.idxmax()]
        parts.append(
            f"{LABELS[metric]} {err.max():.1f} % ({r['controller']} {r['road']} @ "
            f"{r['speed_m_s']:g} m/s)"
        )
    n = len(table.drop_duplicates(["controller", "road", "speed_m_s", "seed"]))
    return f"worst over the {n} cells: " + ", ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="CSV to write")
    ap.add_argument("--scale", type=float, default=0.1, help="DoE duration factor [-]")
    ap.add_argument(
        "--extension", default="control", choices=("control", "none"), help="rig doe --extension"
    )
    ap.add_argument("--kind", default="lpv", help="the model kind fitted (default lpv)")
    a = ap.parse_args()
    commit = current_commit()  # the code the run starts with (HEAD may move during a long run)
    with tempfile.TemporaryDirectory(prefix="closed-loop-cli-") as tmp:
        table = run_recipe(Path(tmp), a.scale, extension=a.extension, kind=a.kind)
    ext = "" if a.extension == "control" else f" --extension {a.extension}"
    ext += "" if a.kind == "lpv" else f" --kind {a.kind}"
    command = (
        f"PYTHONPATH=src python3 benchmarks/closed_loop_cli.py --scale {a.scale:g}{ext} "
        f"--out {a.out}"
    )
    write_table(table, a.out, a.scale, command, a.extension, commit, kind=a.kind)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(fidelity_summary(table).to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print(coverage_sentence(table))
    print(headline_sentence(table))
    print(overall_sentence(table))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
