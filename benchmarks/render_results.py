"""Render the result files of ``results/`` into the pages and the figures.

A page holds a rendered table between two markers::

    <!-- results:NAME -->
    (the table, rendered; never edited by hand)
    <!-- /results:NAME -->

``NAME`` is one of :data:`RENDERERS`. This script replaces every such block of ``README.md`` and
of every page under ``docs/`` with the table rendered from the result files, and draws the
figures of :data:`FIGURES` under ``docs/figures/results/``::

    python benchmarks/render_results.py            # rewrite the pages' blocks and the figures
    python benchmarks/render_results.py --check    # exit 1 if a page differs from its data

The documentation site renders the blocks again when it is built (this file is a MkDocs hook,
``hooks:`` in ``mkdocs.yml``), and ``tests/docs/test_results_data.py`` fails when a page's block
differs from what its data give.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import REPO, RESULTS, read_result, result_names, stamp

#: Display names of the model kinds (and of the benchmarks' variants).
LABELS = {
    "lpv": "LPV",
    "lpv-paper": "LPV, static input (paper)",
    "lpv-u": "LPV, static input `u`",
    "lpv-aug": "LPV + reference-model records",
    "lti": "LTI",
    "p15": "P-15",
    "sp1": "SP-1",
    "sp2": "SP-2",
    "sp3": "SP-3",
    "sp4": "SP-4",
    "spencer": "Spencer",
    "bingham": "Bingham",
    "narx": "NARX",
    "tanh": "tanh",
    "boucwen": "Bouc-Wen",
    "dahl": "Dahl",
    "lugre": "LuGre",
}
#: The kinds in the order the tables list them.
ORDER = list(LABELS)
#: The measured data sets of the held-out table: protocol, column title, select scenario.
DAMPERS = (
    ("quiroz", "Quiroz (leave one condition out, 30 records)", "(b) quiroz-cross"),
    ("dyke", "Dyke (last 30 %)", "(d) dyke"),
    ("labcontrol", "Labcontrol (`test/`, 15 records)", "(e) labcontrol"),
)
#: Closed-loop metrics: column, title.
LOOP_METRICS = (
    ("a_w", "`a_w`"),
    ("rms_acc", "RMS acc."),
    ("rms_tyre_load", "RMS tyre load"),
    ("rms_travel", "RMS travel"),
    ("rms_tracking", "RMS tracking"),
    ("mean_current", "mean current"),
)
#: Notes under the tables.
HELD_OUT_NOTE = (
    "Mean free-run test ESR over the test records (lower is better); **bold**: the lowest of "
    "the column; ✓: the kind `mrdamper select` recommends from the data set's training "
    "records (Quiroz: all 30)."
)
EXTRAPOLATION_NOTE = (
    "Mean free-run test ESR; **bold**: the lowest of the row; ✓: the kind `mrdamper select` "
    "recommends from the scenario's training records. Variants of the LPV model that were "
    "tried and dropped: `docs/notes/results-history.md`."
)
LOOP_NOTE = (
    "Worst |100 (predicted − achieved) / achieved| [%] over the cells (controller, ISO 8608 "
    "class B, C or D, 10 or 25 m/s, road seed 0, 1 or 2) whose damper stroke lies within the "
    "stroke of the model's training records, and in brackets over the cells beyond it "
    "(`outside_stroke` of `closed_loop.csv`; no rig record covers them); `-`: no such cell or "
    "no such metric. The documented recipe at a tenth of the DoE's length: `mrdamper rig doe "
    "--scale 0.1 --extension control`, `mrdamper fit KIND` with defaults, `mrdamper quartercar "
    "KIND.json --plant rig`."
)
#: The scenarios of the extrapolation table: the others, (d) Dyke and (e) Labcontrol, are the
#: held-out table's protocols (shown there, from the real-data files).
EXTRAPOLATING = ("(a)", "(b)", "(c)")
#: Lowest error drawn in the closed-loop chart [%] (a log axis; smaller errors are drawn there).
FLOOR_PCT = 0.05
FIGURES_DIR = REPO / "docs" / "figures" / "results"
_BLOCK = re.compile(
    r"(<!-- results:(?P<name>[a-z0-9-]+) -->\n)(?P<body>.*?)(<!-- /results:(?P=name) -->)",
    re.DOTALL,
)


def label(kind: str) -> str:
    """Display name of a kind."""
    return LABELS.get(kind, kind)


def fmt(x: float | None, digits: int = 3) -> str:
    """``x`` with ``digits`` significant digits (``-`` for a missing value)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:.{digits}g}"


def seconds(x: float | None) -> str:
    """A time in s: two significant digits below 10 s, whole seconds above."""
    if x is None:
        return "-"
    return f"{x:.2g}" if x < 10 else f"{x:.0f}"


def table(head: list[str], rows: Iterable[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _sorted_kinds(kinds: Iterable[str]) -> list[str]:
    seen = list(dict.fromkeys(kinds))
    return sorted(seen, key=lambda k: (ORDER.index(k) if k in ORDER else len(ORDER), k))


def real_data_docs(folder: Path = RESULTS) -> list[dict[str, Any]]:
    """The result files of ``benchmarks/accuracy_real_data.py``: ``results/real-data*.json``
    (one run may hold some of the Quiroz folds or one data set)."""
    return [read_result(n, folder) for n in result_names(folder) if n.startswith("real-data")]


def real_data_summary(folder: Path = RESULTS) -> dict[str, dict[str, dict[str, Any]]]:
    """Per protocol and kind of :func:`real_data_docs`: mean test ESR and SSSE over the test
    records, records scored, failures and fit time [s] (Quiroz: the sum over the six folds)."""
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for r in (r for d in real_data_docs(folder) for r in d["rows"]):
        cell = out.setdefault(r["protocol"], {}).setdefault(
            r["model"],
            {"esr": [], "ssse": [], "fit": {}, "cpu": {}, "failed": 0, "eta": r.get("eta")},
        )
        if r.get("error"):
            cell["failed"] += 1
        else:
            cell["esr"].append(r["esr"])
            cell["ssse"].append(r["ssse"])
        cell["fit"][r.get("fold") or "all"] = r["fit_s"]
        cell["cpu"][r.get("fold") or "all"] = r.get("fit_cpu_s")
    for cells in out.values():
        for c in cells.values():
            n = len(c["esr"])
            c["n"] = n
            c["esr"] = sum(c["esr"]) / n if n else None
            c["ssse"] = sum(c["ssse"]) / n if n else None
            c["fit_s"] = sum(v for v in c["fit"].values() if v is not None)
            cpu = list(c["cpu"].values())
            c["fit_cpu_s"] = None if None in cpu else sum(cpu)
    return out


def _recommended(folder: Path) -> dict[str, str]:
    """The kind ``select`` recommends on each held-out table's training set, by protocol."""
    sel = read_result("extrapolation-select", folder)
    by_scenario = {r["scenario"]: r["select"] for r in sel["rows"]}
    return {proto: by_scenario[sc] for proto, _, sc in DAMPERS if sc in by_scenario}


def render_held_out(folder: Path = RESULTS) -> str:
    """Held-out ESR of every kind on the three measured dampers (best bold, recommended marked)."""
    s = real_data_summary(folder)
    rec = _recommended(folder)
    protos = [p for p, _, _ in DAMPERS]
    kinds = _sorted_kinds(k for p in protos for k in s.get(p, {}))
    best = {
        p: min((c["esr"] for c in s.get(p, {}).values() if c["esr"] is not None), default=None)
        for p in protos
    }
    rows = []
    for k in kinds:
        row = [label(k)]
        for p in protos:
            c = s.get(p, {}).get(k)
            if c is None:
                row.append("-")
                continue
            txt = fmt(c["esr"]) if c["esr"] is not None else "failed"
            if c["failed"] and c["esr"] is not None:
                txt += f" ({c['failed']} failed)"
            if c["esr"] is not None and c["esr"] == best[p]:
                txt = f"**{txt}**"
            if rec.get(p) == k:
                txt += " ✓"
            row.append(txt)
        rows.append(row)
    head = ["kind"] + [title for _, title, _ in DAMPERS]
    return "\n".join(
        [
            table(head, rows),
            "",
            HELD_OUT_NOTE,
            "",
        ]
        + [stamp(d) for d in real_data_docs(folder)]
        + [stamp(read_result("extrapolation-select", folder))]
    )


def render_fit_time(folder: Path = RESULTS) -> str:
    """Fit time of every kind on the three measured dampers."""
    s = real_data_summary(folder)
    protos = [p for p, _, _ in DAMPERS]
    kinds = _sorted_kinds(k for p in protos for k in s.get(p, {}))
    rows = [
        [label(k)]
        + [
            seconds(s[p][k]["fit_cpu_s"]) if k in s.get(p, {}) and s[p][k]["n"] else "-"
            for p in protos
        ]
        for k in kinds
    ]
    return "\n".join(
        [
            table(["kind", "Quiroz, 6 fits [s]", "Dyke [s]", "Labcontrol [s]"], rows),
            "",
            (
                "CPU time of the fits of the held-out table (Quiroz: the sum over its six folds; "
                "Dyke: the drive-lag search included), one process, one BLAS thread; CPU time, "
                "not wall time, because the runs shared the machine (their load average is in the "
                "data line; the files also hold each fit's wall time)."
            ),
            "",
        ]
        + [stamp(d) for d in real_data_docs(folder)]
    )


def render_extrapolation(folder: Path = RESULTS) -> str:
    """Test ESR of every kind on excitations it was not trained on."""
    docs = [read_result(n, folder) for n in ("extrapolation", "extrapolation-standard-kinds")]
    picks = read_result("extrapolation-select", folder)["rows"]
    sel = {(r["scenario"], r["test"]): r for r in picks}
    cells: dict[tuple[str, str], dict[str, float]] = {}
    for d in docs:
        for r in d["rows"]:
            if r["scenario"].startswith(EXTRAPOLATING):
                cells.setdefault((r["scenario"], r["test"]), {})[r["model"]] = r["esr"]
    kinds = _sorted_kinds(k for c in cells.values() for k in c if k not in ("lpv-aug", "lpv-u"))
    rows = []
    for (sc, test), c in cells.items():
        best = min((c[k] for k in kinds if c.get(k) is not None), default=None)
        row = [sc, test]
        for k in kinds:
            v = c.get(k)
            txt = fmt(v)
            if v is not None and v == best:
                txt = f"**{txt}**"
            if (sc, test) in sel and sel[(sc, test)]["select"] == k:
                txt += " ✓"
            row.append(txt)
        rows.append(row)
    return "\n".join(
        [
            table(["scenario", "test"] + [label(k) for k in kinds], rows),
            "",
            EXTRAPOLATION_NOTE,
            "",
        ]
        + [stamp(d) for d in docs]
    )


def render_select(folder: Path = RESULTS) -> str:
    """What ``select`` recommends on each scenario, against the best kind."""
    doc = read_result("extrapolation-select", folder)
    rows = [
        [
            r["scenario"],
            r["test"],
            label(r["best"]),
            label(r["select"]),
            f"{r['select_over_best']:.2f}",
        ]
        for r in doc["rows"]
    ]
    return "\n".join(
        [
            table(["scenario", "test", "best kind", "recommended", "its ESR / best ESR"], rows),
            "",
            stamp(doc),
        ]
    )


#: The closed-loop files of the documented command-line recipe (``closed_loop_cli.py``):
#: the default LPV's, then one per further kind (``--kind``).
LOOP_FILES = ("closed_loop_tenth.csv", "closed_loop_tenth_{kind}.csv")
LOOP_KIND_ORDER = ("lpv", "sp1", "p15", "spencer")


def _csv_header(path: Path) -> dict[str, str]:
    """The ``# key: value`` lines heading a CSV written by ``closed_loop_cli.py``."""
    head: dict[str, str] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.startswith("#"):
            break
        key, _, value = line[1:].partition(":")
        head.setdefault(key.strip(), value.strip())
    return head


def loop_files(folder: Path = RESULTS) -> list[tuple[str, Path]]:
    """(kind, file) of every stored run of the command-line recipe, LPV first."""
    found = [("lpv", folder / LOOP_FILES[0])] if (folder / LOOP_FILES[0]).is_file() else []
    for path in sorted(folder.glob(LOOP_FILES[1].format(kind="*"))):
        kind = path.stem.removeprefix("closed_loop_tenth_")
        if kind != "table2":
            found.append((kind, path))
    order = {k: i for i, k in enumerate(LOOP_KIND_ORDER)}
    return sorted(found, key=lambda kp: (order.get(kp[0], len(order)), kp[0]))


def loop_worst(folder: Path = RESULTS) -> list[dict[str, Any]]:
    """Per kind and controller, the worst |error| [%] of every metric over the cells within the
    training stroke (``within``) and over those beyond it (``beyond``; None: no such cell)."""
    import pandas as pd

    rows = []
    for kind, path in loop_files(folder):
        t = pd.read_csv(path, comment="#")
        for ctrl in dict.fromkeys(t["controller"]):
            row: dict[str, Any] = {"model": kind, "controller": ctrl}
            for m, _ in LOOP_METRICS:
                sel = t[(t["controller"] == ctrl) & (t["metric"] == m)]
                for side, mask in (
                    ("within", ~sel["outside_stroke"]),
                    ("beyond", sel["outside_stroke"]),
                ):
                    err = sel.loc[mask, "error_pct"].abs().dropna()
                    row[f"{m}:{side}"] = float(err.max()) if len(err) else None
            rows.append(row)
    return rows


def render_closed_loop(folder: Path = RESULTS) -> str:
    """Closed-loop fidelity per kind and controller, from the command-line recipe's files."""

    def cell(r: dict[str, Any], m: str) -> str:
        a, b = r[f"{m}:within"], r[f"{m}:beyond"]
        if a is None and b is None:
            return "-"
        return f"{'-' if a is None else f'{a:.1f}'} ({'-' if b is None else f'{b:.1f}'})"

    rows = [
        [label(r["model"]), r["controller"]] + [cell(r, m) for m, _ in LOOP_METRICS]
        for r in loop_worst(folder)
    ]
    stamps = []
    for kind, path in loop_files(folder):
        h = _csv_header(path)
        stamps.append(
            f"`results/{path.name}` ({label(kind)}: measured {h.get('date', '?')[:10]} at "
            f"`{h.get('commit', '?')}`, load average {h.get('load_avg', '?').split()[0]})"
        )
    command = _csv_header(loop_files(folder)[0][1]).get("command", "")
    return "\n".join(
        [
            table(["kind", "controller"] + [t for _, t in LOOP_METRICS], rows),
            "",
            LOOP_NOTE,
            "",
            "Data: "
            + "; ".join(stamps)
            + f". Command: `{command}` (`--kind KIND` for the others).",
        ]
    )


def _table2_rows(doc: dict[str, Any]) -> list[list[str]]:
    return [
        [
            label(r["model"]),
            f"{r['n_ok']} / {r['n_failed']}",
            fmt(r["esr_mean"], 4),
            fmt(r["esr_median"], 4),
            fmt(r["ssse_mean"], 4),
        ]
        for r in doc["rows"]
    ]


def render_table2(folder: Path = RESULTS) -> str:
    """The virtual Table II comparison (full length and quick)."""
    head = ["model", "ok / failed", "ESR mean", "ESR median", "SSSE mean [N]"]
    out = []
    for name, title in (("table2", "Full length"), ("table2-quick", "`--quick` (durations x 0.1)")):
        path = folder / f"{name}.json"
        if not path.is_file():
            continue
        doc = read_result(name, folder)
        out += [f"{title}:", "", table(head, _table2_rows(doc)), "", stamp(doc), ""]
    return "\n".join(out).rstrip("\n")


def render_readme(folder: Path = RESULTS) -> str:
    """The README's summary: the best kind per data set, LPV and the classical models."""
    s = real_data_summary(folder)
    rec = _recommended(folder)
    cols = ["lpv", "p15", "sp1", "spencer", "narx"]
    rows = []
    names = {p: title.split(" (")[0] for p, title, _ in DAMPERS}
    for p, _, _ in DAMPERS:
        cells = {k: c["esr"] for k, c in s.get(p, {}).items() if c["esr"] is not None}
        best = min(cells, key=lambda k: cells[k])
        rows.append(
            [names[p], f"{label(best)} ({fmt(cells[best])})", label(rec.get(p, "-"))]
            + [fmt(cells.get(k)) for k in cols]
        )
    t2 = folder / "table2.json"
    if t2.is_file():
        d = read_result("table2", folder)
        cells = {r["model"]: r["esr_mean"] for r in d["rows"]}
        best = min(cells, key=lambda k: cells[k])
        rows.append(
            ["virtual rig, Table II", f"{label(best)} ({fmt(cells[best])})", "-"]
            + [fmt(cells.get(k)) for k in cols]
        )
    head = ["data (held-out records)", "lowest ESR", "`select` recommends"]
    lines = [table(head + [label(k) for k in cols], rows), ""]
    lines.append(
        "Mean free-run test ESR (lower is better), every kind and the other questions "
        "(extrapolation, closed loop, time): `docs/results.md`; data: `results/`."
    )
    return "\n".join(lines)


def _minutes(s: float) -> str:
    """A wall time as ``M min S s``."""
    m, sec = divmod(round(s), 60)
    return f"{m} min {sec} s" if m else f"{sec} s"


def render_suite(folder: Path = RESULTS) -> str:
    """The README's sentence on the test suite's size and time (``test-suite.json``)."""
    doc = read_result("test-suite", folder)
    parts = []
    for r in doc["rows"]:
        where = f" ({r['note']})" if r.get("note") else ""
        what = "the whole suite" if r["scope"] == "full" else 'the quick loop (`-m "not slow"`)'
        parts.append(
            f"{what}: {r['tests']} tests, {_minutes(r['wall_s'])} of wall-clock time{where}, "
            f"at `{r['commit']}` with the 1-minute load average at {r['load_avg_1min']:.1f}"
        )
    return (
        "Measured: "
        + "; ".join(parts)
        + f". Data: `results/{doc['name']}.json`; command: `{doc['command']}`."
    )


#: Block renderers by name: each returns the Markdown between the block's markers.
RENDERERS: dict[str, Callable[[Path], str]] = {
    "held-out": render_held_out,
    "fit-time": render_fit_time,
    "extrapolation": render_extrapolation,
    "select": render_select,
    "closed-loop": render_closed_loop,
    "table2": render_table2,
    "readme": render_readme,
    "suite": render_suite,
}


def render_text(text: str, folder: Path = RESULTS) -> str:
    """``text`` with every results block re-rendered from the data in ``folder``.

    Raises
    ------
    KeyError
        For a block whose name has no renderer.
    """

    def one(m: re.Match[str]) -> str:
        name = m.group("name")
        if name not in RENDERERS:
            raise KeyError(f"results block {name!r}: no renderer (known: {sorted(RENDERERS)})")
        return m.group(1) + "\n" + RENDERERS[name](folder) + "\n\n" + m.group(4)

    return _BLOCK.sub(one, text)


def blocks_in(text: str) -> list[str]:
    """Names of the results blocks of ``text``, in order."""
    return [m.group("name") for m in _BLOCK.finditer(text)]


def pages() -> list[Path]:
    """README.md and every Markdown page under docs/."""
    return [REPO / "README.md"] + sorted((REPO / "docs").rglob("*.md"))


def draw_held_out(path: Path, folder: Path = RESULTS) -> None:
    """Grouped bar chart: held-out ESR per kind on the three measured dampers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = real_data_summary(folder)
    protos = [p for p, _, _ in DAMPERS]
    kinds = _sorted_kinds(k for p in protos for k in s.get(p, {}))
    fig, ax = plt.subplots(figsize=(9, 3.8))
    width = 0.8 / len(protos)
    for j, (p, title, _) in enumerate(DAMPERS):
        ys = [
            (s[p][k]["esr"] if k in s.get(p, {}) and s[p][k]["esr"] is not None else math.nan)
            for k in kinds
        ]
        xs = [i + (j - 1) * width for i in range(len(kinds))]
        ax.bar(xs, ys, width, label=title.split(" (")[0])
    ax.set_yscale("log")
    ax.set_xticks(range(len(kinds)), [label(k) for k in kinds], rotation=30, ha="right")
    ax.set_ylabel("mean test ESR (log)")
    ax.set_title("Held-out error of every kind on the three measured dampers")
    ax.legend(fontsize=8)
    ax.grid(axis="y", which="both", alpha=0.3)
    _save(fig, path)


def draw_closed_loop(path: Path, folder: Path = RESULTS) -> None:
    """Bar chart: worst closed-loop error over comfort, road holding and travel, per controller."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = loop_worst(folder)
    kinds = list(dict.fromkeys(r["model"] for r in rows))
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    metrics = ("a_w", "rms_acc", "rms_tyre_load", "rms_travel")
    worst = {
        (r["model"], r["controller"]): max(
            [r[f"{m}:within"] for m in metrics if r[f"{m}:within"] is not None] or [0.0]
        )
        for r in rows
    }
    fig, ax = plt.subplots(figsize=(9, 3.8))
    width = 0.8 / len(kinds)
    for j, k in enumerate(kinds):
        xs = [i + (j - (len(kinds) - 1) / 2) * width for i in range(len(controllers))]
        ys = [max(worst[(k, c)], FLOOR_PCT) for c in controllers]
        ax.bar(xs, ys, width, label=label(k))
    ax.axhline(5.0, color="k", lw=0.8, ls="--", label="5 %")
    ax.set_yscale("log")
    ax.set_xticks(range(len(controllers)), controllers)
    ax.set_ylim(bottom=FLOOR_PCT)
    ax.set_ylabel(f"worst |error| [%] (log; below {FLOOR_PCT} at {FLOOR_PCT})")
    ax.set_title(
        "Closed loop, cells within the training stroke: predicted against achieved, "
        "worst of a_w, acc., tyre, travel"
    )
    ax.legend(fontsize=8, ncol=len(kinds) + 1)
    ax.grid(axis="y", which="both", alpha=0.3)
    _save(fig, path)


def _save(fig: Any, path: Path) -> None:
    import matplotlib
    import matplotlib.pyplot as plt

    matplotlib.rcParams["svg.hashsalt"] = "mrdamper"
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.partial")
    fig.savefig(tmp, format="svg", metadata={"Date": None})
    plt.close(fig)
    tmp.replace(path)


#: Figures: file name under ``docs/figures/results/``, drawing function.
FIGURES: dict[str, Callable[[Path, Path], None]] = {
    "held-out.svg": draw_held_out,
    "closed-loop.svg": draw_closed_loop,
}


def _write(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.partial")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if a page differs from its data")
    args = ap.parse_args(argv)
    stale = []
    for page in pages():
        text = page.read_text(encoding="utf-8")
        new = render_text(text)
        if new != text:
            stale.append(page.relative_to(REPO))
            if not args.check:
                _write(page, new)
    if args.check:
        for p in stale:
            print(f"{p}: a results block differs from its data", file=sys.stderr)
        return 1 if stale else 0
    for name, draw in FIGURES.items():
        draw(FIGURES_DIR / name, RESULTS)
    print(f"rendered {len(stale)} page(s); figures in {FIGURES_DIR.relative_to(REPO)}")
    return 0


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """MkDocs hook: the page with its results blocks rendered from the data."""
    return render_text(markdown)


if __name__ == "__main__":
    raise SystemExit(main())
