"""The quarter-car loops compiled ahead of their first use.

The stand-alone quarter-car loop (:func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car`)
and the closed loop (:func:`~mrdamper.control.loop.closed_loop.simulate_closed_loop`) are compiled
kernels whose arguments are named tuples (the controller's form, the packed step forms of the
models); every kind's controller reaches each with one argument type (the forms' arrays are
read-only, :func:`~mrdamper.control.inverse._forms.frozen`; a model's step form is packed,
:func:`~mrdamper.models.step_dispatch.pack`). Running each loop once on a short road compiles it for
those types, or loads it from numba's on-disk cache: a study starts this in a background process
(:func:`mrdamper.study.executor.loops_ahead`) while its fits run, so that its workers load the loops
instead of each compiling them.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

__all__ = ["compile_loops", "loops_cached"]


def compile_loops() -> int:
    """Run each quarter-car loop once on a 0.05 s bump road (a linear damper in the stand-alone
    loop; the shipped reference damper as the model and the plant of the closed loop).

    Returns
    -------
    int
        The number of loops run. A loop that fails here is skipped: it then compiles at its
        first use, where the error shows with its context.
    """
    from mrdamper.control.loop.car import LinearDamper, QuarterCar, bump_road
    from mrdamper.control.loop.closed_loop import simulate_closed_loop
    from mrdamper.control.loop.quarter_car import simulate_quarter_car
    from mrdamper.rig.reference import reference_damper

    road = bump_road(duration=0.05, fs=1000.0)
    runs: list[Callable[[], object]] = [
        lambda: simulate_quarter_car(LinearDamper(1500.0), road, "skyhook", QuarterCar()),
        lambda: simulate_closed_loop(
            reference_damper(), road, "skyhook", QuarterCar(), plant=reference_damper()
        ),
    ]
    done = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for run in runs:
            try:
                run()
                done += 1
            except Exception:  # noqa: BLE001, S112 - see the docstring
                continue
    return done


def loops_cached() -> bool:
    """True when numba's on-disk cache holds machine code of both quarter-car loops (then there
    is nothing to compile ahead; False when unsure)."""
    from mrdamper.control.loop import _closed_loop_kernels as CK
    from mrdamper.control.loop import _quarter_car_kernels as QK

    kernels: tuple[Any, ...] = (QK.simulate, CK.run_loop_packed)
    try:
        return all(bool(d._cache._cache_file._load_index()) for d in kernels)
    except Exception:  # noqa: BLE001 - numba internals; unsure means "compile them"
        return False
