"""Where along the rig chirp the LPV error comes from: ESR per frequency segment.

Scenario (c) of ``generalisation.py`` (virtual-rig sines → 1-15 Hz chirp at constant velocity
amplitude 0.1 m/s, so the stroke falls from 16 mm to 1 mm along the sweep). The LPV model with the
paper's static input ``u``, with the default hysteretic input, and the Spencer model are fitted
on the training sines; the ESR (eq. 24) of each chirp is split into five equal-time segments
(2.8 Hz wide each).

Run::

    python benchmarks/chirp_segments.py            # full-length records (as in the tables)
    python benchmarks/chirp_segments.py --quick    # shorter rig records
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generalisation as G

from mrdamper.metrics import esr
from mrdamper.models import get_estimator

N_SEGMENTS = 5
MODELS = {
    "lpv (static u)": ("lpv", {"input_signal": "u"}),
    "lpv (hysteretic, default)": ("lpv", {}),
    "spencer": ("spencer", {}),
}


def main(argv: list[str] | None = None) -> pd.DataFrame:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="shorter rig records")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    sc = G.SCENARIOS["rig"](args.quick)
    chirps = sc.tests["chirp 1-15 Hz, 0/0.5/1 A"]
    rows = []
    for label, (kind, settings) in MODELS.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = get_estimator(kind, **settings).fit(sc.train).with_range_policy("clip")
            for e in chirps:
                F, Fh = np.asarray(e.F), model.predict(e)
                edges = np.linspace(0, e.n, N_SEGMENTS + 1).astype(int)
                for s in range(N_SEGMENTS):
                    a, b = edges[s], edges[s + 1]
                    f_lo, f_hi = 1.0 + 14.0 * s / N_SEGMENTS, 1.0 + 14.0 * (s + 1) / N_SEGMENTS
                    rows.append(
                        {
                            "model": label,
                            "current [A]": e.metadata["current"],
                            "segment [Hz]": f"{f_lo:.1f}-{f_hi:.1f}",
                            "esr": esr(F[a:b], Fh[a:b]),
                        }
                    )
    tab = (
        pd.DataFrame(rows)
        .pivot_table(
            index=["model", "current [A]"], columns="segment [Hz]", values="esr", sort=False
        )
        .round(4)
    )
    print(f"## Rig chirp: ESR per segment ({time.perf_counter() - t0:.0f} s)\n")
    print(tab.to_string())
    return tab


if __name__ == "__main__":
    main()
