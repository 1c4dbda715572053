"""Compile time of the generic closed loop (any damper as the plant) per controller/plant pair.

Each pair runs in a fresh process: the first :func:`~mrdamper.control.loop.closed_loop.
simulate_closed_loop` call on a 2 s road (kernels compiled or loaded from the on-disk cache) and
a second identical call (already compiled); the difference is what the process paid to get the
loop compiled (wall time, and CPU time of the process, which a loaded machine does not
inflate). The pairs are run twice in order, so the second pass shows a warm disk cache (as a
user's second session does). The models are fitted once on a small Table II DoE (sequence 2 at
``--scale 0.1``) of the reference damper and saved to a temporary folder.

Usage::

    PYTHONPATH=src python3 benchmarks/bench_closed_loop_compile.py
    PYTHONPATH=src python3 benchmarks/bench_closed_loop_compile.py --pairs rig:rig:hybrid

``--models DIR`` keeps the fitted models in DIR (fitted only where missing), so two versions of
the package can be compared on the same models.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

_CHILD = r"""
import sys, time, warnings
warnings.simplefilter("ignore")
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.quarter_car import iso_road
from mrdamper.models.registry import load_model
from mrdamper.rig.reference import reference_damper
folder, model_name, plant_name, ctrl = sys.argv[1:5]
def get(name):
    return reference_damper("quiroz2022") if name == "rig" else load_model(f"{folder}/{name}.json")
model, plant = get(model_name), get(plant_name)
road = iso_road("C", duration=2.0, fs=1000.0, seed=1)
t0, c0 = time.perf_counter(), time.process_time()
simulate_closed_loop(model, road, ctrl, plant=plant)
t1, c1 = time.perf_counter(), time.process_time()
simulate_closed_loop(model, road, ctrl, plant=plant)
t2, c2 = time.perf_counter(), time.process_time()
print(f"{t1 - t0:.3f} {t2 - t1:.3f} {c1 - c0:.3f} {c2 - c1:.3f}")
"""

#: controller model : plant : controller.
PAIRS = (
    "sp1:rig:skyhook",
    "lpv:rig:skyhook",
    "rig:rig:skyhook",
    "p15:rig:skyhook",
    "spencer:rig:skyhook",
    "lti:lti:soft",
    "narx:narx:soft",
    "sp1:p15:skyhook",
)


def fit_models(folder: Path, kinds: set[str]) -> None:
    """Fit ``kinds`` with defaults on a small DoE of the reference damper into ``folder``."""
    from mrdamper.models.registry import get_estimator
    from mrdamper.rig.doe import table_ii
    from mrdamper.rig.reference import reference_damper

    truth = reference_damper("quiroz2022")
    doe = table_ii(seed=0, scale=0.1, damper=truth, experiments=[2])
    for kind in sorted(kinds):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            get_estimator(kind, input=truth.input).fit(doe).save(folder / f"{kind}.json")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", default=",".join(PAIRS), help="MODEL:PLANT:CONTROLLER,...")
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--models", type=Path, help="folder of fitted models to reuse (or fill)")
    a = ap.parse_args()
    pairs = [p.split(":") for p in a.pairs.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) if a.models is None else a.models
        folder.mkdir(parents=True, exist_ok=True)
        wanted = {n for p in pairs for n in p[:2] if n != "rig"}
        fit_models(folder, {k for k in wanted if not (folder / f"{k}.json").is_file()})
        env = dict(os.environ, MPLBACKEND="Agg")
        print(
            "pass  model    plant    controller  first call [s]  second call [s]  compile [s]  "
            "compile CPU [s]"
        )
        for k in range(a.passes):
            for m, p, c in pairs:
                out = subprocess.run(
                    [sys.executable, "-c", _CHILD, str(folder), m, p, c],
                    env=env,
                    capture_output=True,
                    text=True,
                    check=False,
                )
                if out.returncode != 0:
                    print(f"{k + 1:<5} {m:<8} {p:<8} {c:<11} failed: {out.stderr.strip()[-200:]}")
                    continue
                first, second, cpu1, cpu2 = (float(s) for s in out.stdout.split())
                print(
                    f"{k + 1:<5} {m:<8} {p:<8} {c:<11} {first:>14.2f}  {second:>15.3f}  "
                    f"{first - second:>11.2f}  {cpu1 - cpu2:>15.2f}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
