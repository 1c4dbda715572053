"""Result files: the tables the documentation quotes, stored as data under ``results/``.

Each result is one JSON file ``results/<name>.json``::

    {
      "name": "real-data",
      "measures": "what the table measures, in one or two sentences",
      "command": "the command that produced it, run from the repository root",
      "commit": "the short commit it was measured at (\"+dirty\" when the tree had changes)",
      "date": "UTC date and time of the measurement, ISO 8601",
      "load_avg": [1-, 5-, 15-minute load averages when it was written] or null,
      "cpus": number of cores of the machine or null,
      "carried_over": false, or true when the numbers were copied from an earlier page,
      "notes": ["free text: units, footnotes, what a column means"],
      "columns": ["col", ...],
      "rows": [{"col": value, ...}, ...]
    }

A benchmark writes its table with :func:`write_result` (atomically: a reader never sees half a
file); ``benchmarks/render_results.py`` renders the tables into the pages and
``tests/docs/test_results_data.py`` checks that the pages agree with the files. Imported as
``_results`` by the scripts of this folder (run as ``python benchmarks/<name>.py``, which puts the
folder first on ``sys.path``).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
#: The folder of the result files.
RESULTS = REPO / "results"
#: Keys every result file carries.
REQUIRED = ("name", "measures", "command", "commit", "date", "load_avg", "carried_over", "rows")


def current_commit(repo: Path = REPO) -> str:
    """Short commit of ``repo``'s HEAD, with ``+dirty`` when tracked files differ from it
    (``"unknown"`` outside a git checkout)."""
    try:
        head = subprocess.run(
            ["git", "-C", str(repo), "rev-parse", "--short=12", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(repo), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def _clean(value: Any) -> Any:
    """A JSON-safe copy of ``value``: NumPy scalars as Python numbers, NaN as None."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _rows_of(table: Any) -> tuple[list[str], list[dict[str, Any]]]:
    """Columns and rows of a pandas DataFrame or a sequence of mappings."""
    if hasattr(table, "to_dict") and hasattr(table, "columns"):
        columns = [str(c) for c in table.columns]
        records = table.to_dict(orient="records")
    else:
        records = [dict(r) for r in table]
        columns = []
        for r in records:
            columns += [str(c) for c in r if str(c) not in columns]
    rows = [{str(k): _clean(v) for k, v in r.items()} for r in records]
    return columns, rows


def _dumps(doc: Mapping[str, Any]) -> str:
    """``doc`` as JSON text: metadata indented, one line per row (short diffs when rerun)."""
    head = {k: v for k, v in doc.items() if k != "rows"}
    body = json.dumps(head, indent=1, ensure_ascii=False, allow_nan=False)
    rows = ",\n".join(
        "  " + json.dumps(r, ensure_ascii=False, allow_nan=False) for r in doc["rows"]
    )
    return body[:-2] + ',\n "rows": [\n' + rows + "\n ]\n}\n"


def write_result(
    name: str,
    table: Any,
    *,
    command: str,
    measures: str,
    notes: Sequence[str] = (),
    carried_over: bool = False,
    commit: str | None = None,
    date: str | None = None,
    load_avg: Sequence[float] | None = None,
    extra: Mapping[str, Any] | None = None,
    folder: Path = RESULTS,
) -> Path:
    """Write the table ``table`` as ``folder/<name>.json``, atomically.

    Parameters
    ----------
    name
        File stem: lower-case letters, digits and ``-`` (e.g. ``"real-data"``).
    table
        A pandas DataFrame or a sequence of mappings (one per row); NaN is stored as null.
    command
        The command that produced the numbers, run from the repository root.
    measures
        What the table measures (units included).
    notes
        Free-text notes rendered under the table.
    carried_over
        True when the numbers were copied from an earlier page rather than written by the run;
        ``commit`` and ``date`` then say when they were measured.
    commit, date, load_avg
        Default to the current commit, the current UTC time and ``os.getloadavg()``.
    extra
        Further metadata (JSON-serialisable), stored under ``"extra"``.
    folder
        Where to write (default: the repository's ``results/``).

    Returns
    -------
    Path
        The file written.
    """
    if not name or not all(c.isdigit() or c == "-" or ("a" <= c <= "z") for c in name):
        raise ValueError(f"name: expected lower-case letters, digits and '-', got {name!r}")
    if not command.strip() or not measures.strip():
        raise ValueError("command and measures: expected non-empty text")
    columns, rows = _rows_of(table)
    if load_avg is None and not carried_over:
        load_avg = list(os.getloadavg())
    doc = {
        "name": name,
        "measures": measures,
        "command": command,
        "commit": commit if commit is not None else current_commit(),
        "date": date
        if date is not None
        else _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "load_avg": [round(float(x), 2) for x in load_avg] if load_avg is not None else None,
        "cpus": os.cpu_count() if not carried_over else None,
        "carried_over": carried_over,
        "notes": list(notes),
        "columns": columns,
        "rows": rows,
    }
    if extra:
        doc["extra"] = dict(extra)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.json"
    text = _dumps(doc)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".partial", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_result(name: str, folder: Path = RESULTS) -> dict[str, Any]:
    """The result ``folder/<name>.json`` as a dict (its keys: see the module docstring).

    Raises
    ------
    FileNotFoundError
        When there is no such result.
    ValueError
        When a required key is missing.
    """
    path = folder / f"{name}.json"
    doc: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    missing = [k for k in REQUIRED if k not in doc]
    if missing:
        raise ValueError(f"{path}: missing keys {missing}")
    return doc


def result_names(folder: Path = RESULTS) -> list[str]:
    """Names of every stored result, sorted."""
    return sorted(p.stem for p in folder.glob("*.json"))


def rows_where(doc: Mapping[str, Any], **match: Any) -> list[dict[str, Any]]:
    """The rows of ``doc`` whose columns equal every ``match`` value."""
    return [r for r in doc["rows"] if all(r.get(k) == v for k, v in match.items())]


def stamp(doc: Mapping[str, Any]) -> str:
    """One line naming a result's command, commit and date, for the line under its table."""
    when = str(doc["date"])[:10]
    how = "carried over from the earlier results page; " if doc.get("carried_over") else ""
    load = doc.get("load_avg")
    loadtxt = f", load average {load[0]:.1f}" if load else ""
    return (
        f"Data: `results/{doc['name']}.json` ({how}measured {when} at `{doc['commit']}`"
        f"{loadtxt}); command: `{doc['command']}`."
    )
