"""The parts of writing a study that keep outputs safe and reproducible.

* :func:`prepare_out` checks the output folder before anything is written (never an input, a
  folder holding one, the working folder or an ancestor; see :func:`mrdamper._io.check_output`)
  and returns its absolute path (``.`` and ``..`` have no name to swap with).
* :func:`write_tables` writes the tables and ``study.json`` without wall-clock times, and the
  times into ``timings.csv`` / ``timings.json``: the same inputs and seed give byte-identical
  ``results.csv``, ``summary.csv``, ``fits.csv`` and ``study.json``.
* :func:`naming_output` turns an operating-system error raised while writing into the temporary
  folder into one that names the output folder.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any

import pandas as pd

from mrdamper._io import atomic_write_text, check_output
from mrdamper.errors import OutputExistsError
from mrdamper.study.result import StudyResult
from mrdamper.study.tables import TIMING_COLUMNS

__all__ = ["TIMING_INFO", "naming_output", "prepare_out", "slug", "write_tables"]

#: Entries of ``StudyResult.info`` that are wall-clock times (``timings.json``, not ``study.json``).
TIMING_INFO: tuple[str, ...] = ("wall_time_s", "control_time_s")


def prepare_out(res: StudyResult, out_dir: str | os.PathLike[str], force: bool) -> Path:
    """Check the output folder of ``res`` (see the module docstring); return its absolute path."""
    sources = sorted({str(s) for s in res.info.get("sources", ())})
    check_output(out_dir, force=force, folder=True, inputs=sources)
    return Path(os.path.abspath(out_dir))


def write_tables(res: StudyResult, d: Path, summary: pd.DataFrame) -> None:
    """Write ``results.csv``, ``summary.csv``, ``fits.csv``, ``roles.csv``, ``protocol.json``,
    ``study.json`` (no times), ``control.csv`` and ``control_fronts/<model>.csv`` (when the
    control step ran) and ``timings.csv``, ``timings.json`` (the times) into ``d``."""
    timing = [c for c in TIMING_COLUMNS if c in res.results.columns]
    atomic_write_text(d / "results.csv", res.results.drop(columns=timing).to_csv(index=False))
    keys = [c for c in ("fold", "model", "record") if c in res.results.columns]
    atomic_write_text(d / "timings.csv", res.results[keys + timing].to_csv(index=False))
    atomic_write_text(
        d / "summary.csv", summary.drop(columns=timing, errors="ignore").to_csv(index=False)
    )
    atomic_write_text(
        d / "fits.csv", res.fits.drop(columns=timing, errors="ignore").to_csv(index=False)
    )
    atomic_write_text(d / "roles.csv", res.roles.to_csv(index=False))
    if res.control is not None:
        atomic_write_text(d / "control.csv", res.control.table.to_csv(index=False))
        for label, fr in res.control.fronts.items():
            if not isinstance(fr, str):
                text = fr.table().to_csv(index=False)
                atomic_write_text(d / "control_fronts" / f"{slug(label, 'model')}.csv", text)
    atomic_write_text(d / "protocol.json", res.protocol.to_json() + "\n")
    info: dict[str, Any] = {k: v for k, v in res.info.items() if k not in TIMING_INFO}
    info["headline"] = dict(res.headline())
    info["headlines"] = [dict(h) for h in res.headlines()]
    atomic_write_text(d / "study.json", json.dumps(info, indent=2, default=str) + "\n")
    timings: dict[str, Any] = {k: res.info[k] for k in TIMING_INFO if k in res.info}
    timings["per_model"] = {
        str(row["model"]): {c: float(row[c]) for c in timing if c in summary.columns}
        for row in summary.to_dict("records")
    }
    atomic_write_text(d / "timings.json", json.dumps(timings, indent=2, default=str) + "\n")


def slug(text: str, default: str = "fold") -> str:
    """``text`` as a file name (runs of other characters than letters, digits, ``_.-`` -> ``_``)."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or default


def naming_output(exc: OSError, out: Path) -> OSError:
    """``exc`` itself, or the same error naming ``out`` instead of a temporary file inside it."""
    if isinstance(exc, OutputExistsError) or exc.errno is None:
        return exc
    new = OSError(exc.errno, exc.strerror, str(out))
    new.__cause__ = exc
    return new
