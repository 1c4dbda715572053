"""The quarter-car loops compiled ahead: the types they are compiled for are the ones every kind's
controller reaches them with, so the study's workers load them instead of compiling again."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

from mrdamper.control.loop import _closed_loop_kernels as CK
from mrdamper.control.loop import _quarter_car_kernels as QK
from mrdamper.control.loop.ahead import compile_loops, loops_cached
from mrdamper.control.loop.car import QuarterCar, bump_road
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.quarter_car import simulate_quarter_car
from mrdamper.models.lpv import LPVModel
from mrdamper.models.semiphenomenological import SP3Model
from mrdamper.rig.reference import reference_damper


def _models() -> list[Any]:
    lpv = LPVModel(
        alpha=np.array([[-1.2, 0.10, -0.02], [0.40, -0.05, 0.01]]),
        beta=np.array([[300.0, 500.0, -40.0], [-200.0, -300.0, 30.0]]),
        offset=5.0,
        fs=1000.0,
        input_signal="v",
        rho_range=(0.0, 2.0),
        input_range=(0.0, 2.0),
    )
    sp3 = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), input_range=(0.0, 2.0))
    return [lpv, sp3]


def test_the_loops_compiled_ahead_serve_an_lpv_model_and_a_static_map() -> None:
    assert compile_loops() == 2
    ahead = (set(QK.simulate.signatures), set(CK.run_loop_packed.signatures))
    assert ahead[0] and ahead[1]
    road = bump_road(duration=0.05, fs=1000.0)
    plant = reference_damper()
    for model in _models():  # an LPV model's arrays are read-only, a static map's are built
        simulate_quarter_car(model, road, "skyhook", QuarterCar())
        simulate_closed_loop(model, road, "skyhook", QuarterCar(), plant=plant)
    # no new signature: the kernels compiled ahead are the ones these runs use
    assert (set(QK.simulate.signatures), set(CK.run_loop_packed.signatures)) == ahead


def test_loops_cached_says_whether_there_is_anything_to_compile(tmp_path: Path) -> None:
    compile_loops()  # compiled or loaded: in the on-disk cache now
    assert loops_cached()
    code = "from mrdamper.control.loop.ahead import loops_cached; print(loops_cached())"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # an empty cache
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.split() == ["False"]
