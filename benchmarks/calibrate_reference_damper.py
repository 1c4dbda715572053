"""Calibrate the shipped Spencer reference damper on the Quiroz (2022) unfiltered sine records.

Writes ``src/mrdamper/rig/parameters/quiroz2022.json`` (identified on all 30 records of
``../shared/data/quiroz2022_utfsm/sine_unfiltered``, 0-1 A, sampling rates as recorded: 200 Hz and
1 kHz) and ``src/mrdamper/rig/parameters/spencer1997.json`` (published values, not identified),
then prints the per-record free-run ESR table used in ``docs/calibration.md``.

Usage::

    python benchmarks/calibrate_reference_damper.py [--data DIR] [--force] [--dry-run]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import pandas as pd

from mrdamper.data import ExperimentSet, read_directory
from mrdamper.models.spencer import SpencerEstimator, SpencerModel, spencer1997

REPO = Path(__file__).resolve().parents[1]
DEFAULT_DATA = REPO.parent / "shared" / "data" / "quiroz2022_utfsm" / "sine_unfiltered"
OUT_DIR = REPO / "src" / "mrdamper" / "rig" / "parameters"

#: Estimator settings of the shipped calibration (documented in docs/calibration.md).
CALIBRATION_SETTINGS = {"input": "i", "n_starts": 3, "seed": 0, "weighting": "record"}


def read_quiroz(folder: str | Path) -> ExperimentSet:
    """Read the Quiroz sine CSVs with metadata (amplitude, frequency, current, condition) from
    the file names, through :func:`mrdamper.data.readers.read_directory`."""
    data = read_directory(folder)
    if len(data) == 0:
        raise FileNotFoundError(f"{folder}: no sine_*.csv records found")
    return data


def esr_table(model: SpencerModel, data: ExperimentSet) -> pd.DataFrame:
    """Per-record free-run ESR, SSSE [N] and sub-steps of ``model`` on ``data``."""
    rows = []
    for e in data:
        s = model.score(e)
        rows.append(
            {
                "record": e.name,
                "fs_Hz": e.fs,
                "current_A": e.metadata.get("current"),
                "esr": s.esr,
                "ssse_N": s.ssse,
                "substeps": model.substeps_for(e),
            }
        )
    return pd.DataFrame(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DEFAULT_DATA), help="folder of the unfiltered records")
    ap.add_argument("--force", action="store_true", help="overwrite the shipped JSON files")
    ap.add_argument("--dry-run", action="store_true", help="identify and print, write nothing")
    args = ap.parse_args(argv)

    data = read_quiroz(args.data)
    print(f"{len(data)} records, {sum(e.n for e in data)} samples from {args.data}")
    est = SpencerEstimator(**CALIBRATION_SETTINGS)
    t0 = time.perf_counter()
    model = est.fit(data)
    elapsed = time.perf_counter() - t0
    prov = model.provenance
    print(
        f"identification: {elapsed:.1f} s, cost {prov['cost']:.6g}, status {prov['status']} "
        f"({prov['message']}), cond(J^T J) {prov['cond_JTJ']:.3g}, at bounds {prov['at_bounds']}"
    )
    print("starts:", prov["starts"])
    for name, value in model.parameters.items():
        print(f"  {name:8s} = {value!r}")
    table = esr_table(model, data)
    with pd.option_context("display.width", 120, "display.max_rows", 100):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4f}"))
    print(f"mean per-record ESR {table.esr.mean():.4f}, max {table.esr.max():.4f}")
    if args.dry_run:
        return 0
    model = model.with_range_policy("error")
    out = model.save(OUT_DIR / "quiroz2022.json", force=args.force)
    print(f"wrote {out}")
    ref = spencer1997()
    out = ref.save(OUT_DIR / "spencer1997.json", force=args.force)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
