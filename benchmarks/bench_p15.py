"""P-15 identification on the 30 Quiroz unfiltered records: sensitivity Jacobian vs finite
differences.

Both runs use the default output-error estimator (multiple shooting, then free run) on the same
records with the same evaluation budgets; only the Jacobian differs: the exact discrete
sensitivities integrated with the state by the compiled kernel (default) against SciPy's 2-point
finite differences (16 extra simulations per Jacobian). Both run in the same process, one after
the other, so their ratio is meaningful on a loaded machine; the absolute times are not.

Usage::

    python benchmarks/bench_p15.py          # default budgets (shoot_nfev=30, max_nfev=20), ~2-4 min
    python benchmarks/bench_p15.py --quick  # budgets 4 and 2 (a smoke run of the same comparison)
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path
from typing import Any

import pandas as pd

from mrdamper.data import ExperimentSet
from mrdamper.data.readers import read_directory
from mrdamper.models.phenomenological import P15Estimator

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MRDAMPER_SHARED_DATA", REPO.parent / "shared" / "data"))


def run(data: ExperimentSet, jacobian: str, budgets: dict[str, int]) -> dict[str, Any]:
    """Fit the 30 records once; wall and CPU time, evaluation counts and the training ESR."""
    est = P15Estimator(jacobian=jacobian, **budgets)  # type: ignore[arg-type]
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        model = est.fit(data)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    oe = model.provenance["output_error"]
    esr = list(model.provenance["training_esr"].values())
    return {
        "jacobian": jacobian,
        "records": len(data),
        "wall_s": wall,
        "cpu_s": cpu,
        "nfev": oe["nfev_total"],
        "njev": oe["njev_total"],
        "training_mean_esr": sum(esr) / len(esr),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DATA / "quiroz2022_utfsm" / "sine_unfiltered")
    ap.add_argument("--quick", action="store_true", help="small evaluation budgets (smoke run)")
    args = ap.parse_args(argv)
    data = read_directory(args.data)
    budgets = {"shoot_nfev": 4, "max_nfev": 2} if args.quick else {}
    # compile / load the kernels outside the timed runs
    run(data[:5], "sensitivity", {"shoot_nfev": 1, "max_nfev": 1})
    rows = [run(data, "sensitivity", budgets), run(data, "2-point", budgets)]
    table = pd.DataFrame(rows)
    pd.set_option("display.width", 200)
    print(f"P-15 fit of {len(data)} Quiroz records, budgets {budgets or 'default'}")
    print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    ratio = rows[1]["wall_s"] / rows[0]["wall_s"]
    print(
        f"\nfinite differences / sensitivities, wall time: {ratio:.1f}x "
        f"(CPU {rows[1]['cpu_s'] / rows[0]['cpu_s']:.1f}x)"
    )


if __name__ == "__main__":
    main()
