"""Spencer identification on the 30 Quiroz unfiltered records: sensitivity Jacobian vs finite
differences.

Both runs use the same estimator, data, starts (3, seed 0), scaling and bounds; only the Jacobian
differs (forward sensitivities integrated with the state vs SciPy's 2-point finite differences).
The finite-difference peer runs on the full set with ``--full-peer``; by default it runs on a
subset (the five currents of the 5 mm / 4 Hz condition) together with the sensitivity version on
the same subset, so the ratio compares like with like.

Wall time depends on the machine's load; CPU time of this process is printed beside it.

Usage::

    python benchmarks/bench_spencer_identification.py [--full-peer] [--data DIR]
"""

from __future__ import annotations

import argparse
import time
import warnings

import pandas as pd
from calibrate_reference_damper import CALIBRATION_SETTINGS, DEFAULT_DATA, read_quiroz

from mrdamper.data import ExperimentSet
from mrdamper.models.spencer import SpencerEstimator


def run(label: str, data: ExperimentSet, jacobian: str) -> dict:
    est = SpencerEstimator(**{**CALIBRATION_SETTINGS, "jacobian": jacobian})
    t0, c0 = time.perf_counter(), time.process_time()
    model = est.fit(data)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    esr = [model.score(e).esr for e in data]
    prov = model.provenance
    return {
        "run": label,
        "records": len(data),
        "jacobian": jacobian,
        "wall_s": wall,
        "cpu_s": cpu,
        "nfev": prov["nfev_total"],
        "njev": prov["njev_total"],
        "mean_esr": sum(esr) / len(esr),
        "max_esr": max(esr),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument(
        "--full-peer", action="store_true", help="run finite differences on all 30 records"
    )
    args = ap.parse_args()
    data = read_quiroz(args.data)
    # compile / load the kernels outside the timed runs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        SpencerEstimator(n_starts=1, max_nfev=2).fit(data[:2])
    rows = [run("all records", data, "sensitivity")]
    if args.full_peer:
        rows.append(run("all records", data, "2-point"))
    else:
        subset = data.filter(condition="5mm_4Hz")
        rows.append(run("5mm_4Hz subset", subset, "sensitivity"))
        rows.append(run("5mm_4Hz subset", subset, "2-point"))
    table = pd.DataFrame(rows)
    with pd.option_context("display.width", 160):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    sens = table[table.jacobian == "sensitivity"].iloc[-1]
    fd = table[table.jacobian == "2-point"].iloc[-1]
    print(
        "finite differences / sensitivities on the same records: "
        f"wall x{fd.wall_s / sens.wall_s:.2f}, "
        f"cpu x{fd.cpu_s / sens.cpu_s:.2f}; mean ESR {fd.mean_esr:.4f} vs {sens.mean_esr:.4f}"
    )


if __name__ == "__main__":
    main()
