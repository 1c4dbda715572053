"""Would a Dahl stroke scale that grows with the current reach Quiroz at 5 Hz? A diagnosis.

The hysteretic LPV input's Dahl state has one stroke scale ``x_y`` for every current
(:mod:`mrdamper.analysis.hysteretic`). On Quiroz's 2 mm / 5 Hz records the model's force at 1 A
rises within a few tenths of a millimetre to 800 N on the ramps, where the damper gives 300 N
(``benchmarks/quiroz_5hz.py``): a pre-yield stiffness that does not grow with the yield force
would make ``x_y`` grow with the current. This script replaces the input's Dahl state, for the
run only, by one with ``x_y(rho) = x_y (1 + k rho)`` [m] (``rho`` in A) and fits the LPV model
(stroke ``x_y`` and blend held) on scenario (a) of ``generalisation.py``: the Quiroz conditions
up to 3 Hz, scored on 5 mm / 4 Hz and 2 mm / 5 Hz. ``k = 0`` is the project's input.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/scheduled_stroke.py              # k = 0, 2, 5, 10
    OPENBLAS_NUM_THREADS=1 python benchmarks/scheduled_stroke.py --k 0 2      # a subset
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mrdamper.analysis import hysteretic
from mrdamper.analysis.laws import in_blocks
from mrdamper.models.lpv import inputs as lpv_inputs

#: Stroke scales [m] and blends [-] of the grid.
STROKES = (5e-5, 1e-4, 2e-4)
BLENDS = (0.25, 0.5, 0.75)


@njit(cache=True)
def dahl_scheduled(v, dt, strokes):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """The Dahl state [-] from rest with a stroke scale [m] per sample (exact steps, as
    :func:`mrdamper.analysis.hysteretic.dahl_step` with ``strokes[k]``)."""
    z = np.zeros(v.size)
    for k in range(1, v.size):
        z[k] = hysteretic.dahl_step(z[k - 1], v[k - 1], v[k], dt, strokes[k])
    return z


def scheduled_signal(k: float) -> Any:
    """``HystereticInput.signal`` with ``x_y(rho) = stroke (1 + k max(rho, 0))``."""

    def signal(self: Any, v: np.ndarray, rho: np.ndarray, dt: float) -> np.ndarray:
        v = np.ascontiguousarray(v, dtype=np.float64)
        rho = np.broadcast_to(np.asarray(rho, dtype=np.float64), v.shape)
        strokes = np.ascontiguousarray(self.stroke * (1.0 + k * np.clip(rho, 0.0, None)))
        z = dahl_scheduled(v, float(dt), strokes)
        return np.asarray(
            in_blocks(
                lambda vb, rb, zb: hysteretic._blend(self.laws, vb, rb, zb, self.blend), v, rho, z
            )
        )

    return signal


def main(argv: list[str] | None = None) -> pd.DataFrame:
    import generalisation as G

    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--k", type=float, nargs="+", default=[0.0, 2.0, 5.0, 10.0], help="[1/A]")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    sc = G.scenario_quiroz_frequency(quick=True)
    project_signal = lpv_inputs.HystereticInput.signal
    rows = []
    try:
        for k in args.k:
            lpv_inputs.HystereticInput.signal = scheduled_signal(k)  # type: ignore[method-assign]
            for stroke in STROKES:
                for blend in BLENDS:
                    model, _, err = G.fit_model("lpv", {"stroke": stroke, "blend": blend}, sc.train)
                    row: dict[str, Any] = {"k [1/A]": k, "stroke [mm]": 1e3 * stroke}
                    row["blend"] = blend
                    if model is None:
                        rows.append({**row, "error": err})
                        continue
                    row["train"] = G.mean_esr(model, sc.train)[0]
                    for condition, records in sc.tests.items():
                        row[condition] = G.mean_esr(model, records)[0]
                    rows.append(row)
                    print(pd.DataFrame([row]).to_string(index=False, header=len(rows) == 1))
    finally:
        lpv_inputs.HystereticInput.signal = project_signal  # type: ignore[method-assign]
    table = pd.DataFrame(rows)
    best = table.loc[table["2mm_5Hz"].idxmin()]
    print(f"\nbest at 2 mm / 5 Hz:\n{best.to_string()}\n{time.perf_counter() - t0:.0f} s")
    return table


if __name__ == "__main__":
    main()
