"""How many signatures the quarter-car loop kernel compiles for a static map and an LPV model.

Usage::

    python benchmarks/bench_loop_signatures.py                  # this checkout
    python benchmarks/bench_loop_signatures.py --previous DIR   # and a checkout DIR beside it

In a fresh process per side, with an empty kernel cache (``NUMBA_CACHE_DIR`` in a new folder),
the quarter-car kernel (``_quarter_car_kernels.simulate``) runs a 0.05 s bump road twice: with
the controller form of a linear damper (a static map: the form's LPV arrays are the empty ones
it builds) and with the same form holding an LPV model's arrays, read-only as a fitted LPV
model's are. It prints the number of signatures numba compiled and the CPU time the process
spent (compilation: the runs are a few hundred samples). One signature means every kind's
controller reaches the loop kernels with one argument type (``docs/performance.md``, first run).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

_CHILD = r"""
import importlib, resource
import numpy as np

def first(*names):
    for name in names:
        try:
            return importlib.import_module(name)
        except ImportError:
            continue
    raise ImportError(names)

QK = first("mrdamper.control._quarter_car_kernels", "mrdamper.control.loop._quarter_car_kernels")
forms = first("mrdamper.control._forms", "mrdamper.control.inverse._forms")
loop = first("mrdamper.control._loop", "mrdamper.control.loop._loop")
car = first("mrdamper.control.car", "mrdamper.control.loop.car")

def frozen(a):
    out = np.array(a, dtype=float)
    out.flags.writeable = False
    return out

road = car.bump_road(duration=0.05, fs=1000.0)
s = loop.loop_setup(car.LinearDamper(1500.0), road, car.Controller("skyhook"), car.QuarterCar(),
                    reg=None, v_ref=0.3, rate=None, i_range=None, substeps=2)
static = loop.controller_form(s, 8)
lpv = static._replace(inverse=forms.inverse_form(
    lam=1.0, n_grid=8, is_lpv=True, alpha=frozen([[1.0, 0.0]]), beta=frozen([[0.0, 1.0]]),
    gm=frozen(np.zeros((3, 1))), gc=frozen(np.zeros((3, 1))), mu_high=frozen([1.0, 1.0]),
    mu_low=frozen([0.5, 0.5])))
r0 = resource.getrusage(resource.RUSAGE_SELF)
for form in (static, lpv):
    QK.simulate(s.zr, s.h, s.n_sub, s.car_arr, form, 1e3)
r1 = resource.getrusage(resource.RUSAGE_SELF)
cpu = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
print(f"{len(QK.simulate.signatures)} {cpu:.2f}")
"""


def _side(src: Path) -> tuple[int, float]:
    """``(signatures, CPU [s])`` of the checkout ``src`` from an empty kernel cache."""
    with tempfile.TemporaryDirectory(prefix="mrdamper-loop-sigs-") as cache:
        env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_CACHE_DIR": cache}
        out = subprocess.run(
            [sys.executable, "-c", _CHILD], env=env, check=True, capture_output=True, text=True
        ).stdout.split()
    return int(out[0]), float(out[1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--previous", type=Path, help="checkout of the previous release")
    args = ap.parse_args(argv)
    sides = {"this": REPO / "src"}
    if args.previous is not None:
        sides = {"previous": args.previous.resolve() / "src", **sides}
    print(f"{'side':<9} {'signatures':>10} {'CPU [s]':>8}  (static map and LPV form, empty cache)")
    for name, src in sides.items():
        n, cpu = _side(src)
        print(f"{name:<9} {n:>10} {cpu:>8.1f}", flush=True)


if __name__ == "__main__":
    main()
