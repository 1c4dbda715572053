"""Where the skyhook mean current's gap comes from, and what does not close it.

The default LPV model is fitted on the virtual rig's Table II DoE with the control extension
(``quiroz2022``; stroke and blend chosen on a held-out extension, as ``closed_loop.py
--extension`` does). The quarter car runs skyhook at its default gain on ISO 8608 class C at
20 m/s (20 s, the default car) with the model and with the true damper as the plant, and the
script prints what the controller saw in each: the RMS body and damper velocities [m/s], the
mean desired force [N], the share of control samples whose desired force is out of reach and
the mean current [mA]; and the same for the model in a car whose spring is stiffer by the true
damper's accumulator stiffness ``k1`` [N/m] (the Spencer model's ``k1 (x - x0)``, a force in
phase with the travel that the LPV model has no term for). Then each variant of the fit is run
through :func:`~mrdamper.control.loop.fidelity.closed_loop_fidelity` (five controllers): the skyhook
mean current's error and the worst error of every other metric and controller [%].

Variants: ``default``; ``ext-x2`` and ``ext-x20`` (the extension's records weighted 2 and 20
times); ``n_m=4`` and ``n_rho=3`` (model orders); ``slopes-x0.95`` and ``slopes-x0.9`` (the zone
laws' post-yield slopes ``m1``, ``m3`` scaled, the central slope kept); ``eta=identify`` (the
current's lag identified, :mod:`mrdamper.models.lag`).

Run::

    python benchmarks/skyhook_current.py                       # full length, every variant
    python benchmarks/skyhook_current.py --variants default    # the decomposition only
    python benchmarks/skyhook_current.py --variants default --stiffness-seeds 0,1,2
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
import closed_loop as CL

from mrdamper.control.loop.car import QuarterCar
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.fidelity import closed_loop_fidelity, loop_metrics
from mrdamper.control.loop.quarter_car import CONTROLLERS, iso_road
from mrdamper.models.registry import get_estimator
from mrdamper.rig.reference import reference_damper

#: Every variant of the fit: name -> (estimator settings, extension weight, slope scale).
VARIANTS: dict[str, tuple[dict[str, Any], float, float]] = {
    "default": ({}, 1.0, 1.0),
    "ext-x2": ({}, 2.0, 1.0),
    "ext-x20": ({}, 20.0, 1.0),
    "n_m=4": ({"n_m": 4}, 1.0, 1.0),
    "n_rho=3": ({"n_rho": 3}, 1.0, 1.0),
    "slopes-x0.95": ({}, 1.0, 0.95),
    "slopes-x0.9": ({}, 1.0, 0.9),
    "eta=identify": ({"eta": "identify"}, 1.0, 1.0),
}


def scaled_outer_slopes(laws: Any, factor: float) -> Any:
    """The zone laws with the post-yield slopes ``m1``, ``m3`` scaled by ``factor`` [-]."""
    gamma_m = np.array(laws.gamma_m, dtype=np.float64)
    gamma_m[[0, 2]] *= factor
    return dataclasses.replace(laws, gamma_m=gamma_m)


def demand(result: Any) -> dict[str, float]:
    """What a semi-active controller saw in one run (a ``QuarterCarResult``).

    Returns the RMS body velocity and damper velocity [m/s], the mean desired force [N] (zero
    where the controller asks for none), the share of samples whose desired force is out of
    reach [-] and the mean input [mA for a current].
    """
    desired = np.nan_to_num(np.asarray(result.F_desired, dtype=np.float64))
    return {
        "rms_v_body": float(np.sqrt(np.mean(np.square(result.v_s)))),
        "rms_v_damper": float(np.sqrt(np.mean(np.square(result.v_s - result.v_u)))),
        "mean_F_desired": float(np.mean(np.abs(desired))),
        "out_of_reach": float(np.mean(result.saturated)),
        "mean_input_milli": 1e3 * float(np.mean(result.i)),
    }


def stiffened(car: QuarterCar, stiffness: float) -> QuarterCar:
    """``car`` with its suspension spring stiffer by ``stiffness`` [N/m]."""
    return dataclasses.replace(car, k_s=car.k_s + stiffness)


def stiffness_table(
    model: Any,
    truth: Any,
    stiffness: float,
    seeds: list[int],
    duration: float = 20.0,
    substeps: int = 32,
) -> pd.DataFrame:
    """Every controller's metrics with ``model`` as the damper, in the default car and in a car
    stiffer by ``stiffness`` [N/m], against ``truth`` as the damper in the default car.

    One row per seed, controller and metric (:func:`~mrdamper.control.loop.fidelity.loop_metrics`):
    ``achieved``, ``error_pct`` (default car) and ``error_pct_stiffened`` [%]. ISO 8608 class C
    at 20 m/s; ``substeps`` plant steps per road sample (no halving check).
    """
    rows = []
    for seed in seeds:
        road = iso_road("C", speed=20.0, duration=duration, fs=1000.0, seed=seed)
        for controller in CONTROLLERS:
            runs = [
                loop_metrics(
                    simulate_closed_loop(
                        model, road, controller, car=car, plant=plant, substeps=substeps
                    )
                )
                for plant, car in (
                    (truth, QuarterCar()),
                    (model, QuarterCar()),
                    (model, stiffened(QuarterCar(), stiffness)),
                )
            ]
            for metric, achieved in runs[0].items():
                err = [
                    100.0 * (r[metric] - achieved) / achieved if achieved else np.nan
                    for r in runs[1:]
                ]
                rows.append(
                    {
                        "seed": seed,
                        "controller": controller,
                        "metric": metric,
                        "achieved": achieved,
                        "error_pct": err[0],
                        "error_pct_stiffened": err[1],
                    }
                )
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame) -> dict[str, float]:
    """Skyhook's mean-current error and the worst |error| [%] of everything else."""
    sky = (table.controller == "skyhook") & (table.metric == "mean_current")
    rest = table[~sky & table.error_pct.notna()]
    return {
        "skyhook mean current [%]": float(table[sky].error_pct.iloc[0]),
        "worst other [%]": float(rest.error_pct.abs().max()),
        "where": str(rest.loc[rest.error_pct.abs().idxmax(), ["controller", "metric"]].tolist()),
    }


def main(argv: list[str] | None = None) -> pd.DataFrame:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="DoE duration factor [-]")
    ap.add_argument("--seed", type=int, default=0, help="road profile seed")
    ap.add_argument(
        "--variants",
        default=",".join(VARIANTS),
        help=f"comma-separated variants of the fit (default: all of {', '.join(VARIANTS)})",
    )
    ap.add_argument(
        "--stiffness-seeds",
        default="",
        help="comma-separated road seeds of the stiffened-car table over every controller "
        "(first variant's model; default: none)",
    )
    args = ap.parse_args(argv)
    names = args.variants.split(",")
    unknown = sorted(set(names) - set(VARIANTS))
    if unknown:
        ap.error(f"--variants: unknown {unknown}; expected some of {list(VARIANTS)}")
    t0 = time.perf_counter()
    truth = reference_damper("quiroz2022")
    doe, ext, held_out = CL.training_records(truth, args.scale)
    print(f"DoE and extension {time.perf_counter() - t0:.0f} s")
    road = iso_road("C", speed=20.0, duration=20.0, fs=1000.0, seed=args.seed)
    laws = None
    rows = []
    for name in names:
        settings, weight, slope = VARIANTS[name]
        t1 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if slope != 1.0:
                if laws is None:  # the default fit's laws, scaled
                    base = get_estimator("lpv", input=truth.input, choose_on="held-out")
                    laws = base.fit(doe + ext, choice_records=held_out).lpv_input.laws
                settings = {**settings, "zone_laws": scaled_outer_slopes(laws, slope)}
            est = get_estimator("lpv", input=truth.input, choose_on="held-out", **settings)
            model = est.fit(
                doe + ext,
                record_weights=[1.0] * len(doe) + [weight] * len(ext),
                choice_records=held_out,
            )
            if laws is None:
                laws = model.lpv_input.laws
            table = closed_loop_fidelity(model, truth, seed=args.seed).table()
        if name == names[0]:
            k1 = float(truth.parameters["k1"])
            for plant_name, plant, car in (
                ("model", model, QuarterCar()),
                ("true damper", truth, QuarterCar()),
                (f"model, car spring + k1 = {k1:.0f} N/m", model, stiffened(QuarterCar(), k1)),
            ):
                run = simulate_closed_loop(
                    model, road, "skyhook", car=car, plant=plant, substeps=32
                )
                seen = demand(run)
                print(
                    f"{name}, skyhook with the {plant_name} as plant: "
                    + ", ".join(f"{k} {v:.4g}" for k, v in seen.items())
                )
            if args.stiffness_seeds:
                seeds = [int(s) for s in args.stiffness_seeds.split(",")]
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    stiff = stiffness_table(model, truth, k1, seeds)
                worst = stiff.assign(
                    default_car=stiff.error_pct.abs(), stiffened_car=stiff.error_pct_stiffened.abs()
                ).pivot_table(
                    index="controller",
                    columns="metric",
                    values=["default_car", "stiffened_car"],
                    aggfunc="max",
                )
                print(
                    f"worst |error| [%] over seeds {seeds}, model in the default / stiffened car:"
                )
                print(worst.round(1).to_string())
        rows.append({"variant": name, **summary(table), "fit+loop [s]": time.perf_counter() - t1})
        print(pd.DataFrame(rows[-1:]).to_string(index=False, float_format="{:.2f}".format))
    out = pd.DataFrame(rows)
    print()
    print(out.to_string(index=False, float_format="{:.2f}".format))
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return out


if __name__ == "__main__":
    main()
