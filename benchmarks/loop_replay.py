"""Why a model's loop differs from the true damper's: the loop's motion replayed open loop.

The default LPV model is fitted on the virtual rig's Table II DoE (``quiroz2022``), or with
``--extension`` on Table II and the control extension (stroke and blend chosen on a held-out
extension, as ``closed_loop.py --extension`` does). The quarter car runs each controller (passive
soft and passive hard by default) with the true damper as the plant (ISO 8608 class C at 20 m/s,
20 s, the default car); the damper motion of each run is then replayed open loop through the
model with the run's current, and the model's force is compared with the true damper's, per
frequency band (Welch cross-spectra against the velocity: the magnitude ``|F/v|`` [N s/m] and the
phase of the force to the velocity [deg]) and per velocity band (mean ``|F|`` [N]). Last, the
model's frozen transfer function at three currents: gain (relative to its DC gain) and phase at
1, 5, 10 and 20 Hz.

Run::

    python benchmarks/loop_replay.py                 # full-length DoE
    python benchmarks/loop_replay.py --scale 0.1     # the tenth-length DoE of the tables
    python benchmarks/loop_replay.py --extension --controllers soft,skyhook
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import scipy.signal as sps

sys.path.insert(0, str(Path(__file__).resolve().parent))
import closed_loop as CL

from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.quarter_car import iso_road
from mrdamper.data import Experiment
from mrdamper.models.registry import get_estimator
from mrdamper.rig.doe import table_ii
from mrdamper.rig.doe_control import HIGHPASS
from mrdamper.rig.reference import reference_damper

#: Frequency bands [Hz] of the cross-spectral comparison.
BANDS = ((0.0, 1.0), (1.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0))
#: Velocity bands [m/s] of the force comparison.
V_BANDS = ((0.0, 0.02), (0.02, 0.1), (0.1, 0.4), (0.4, np.inf))
#: Frequencies [Hz] of the frozen transfer function.
FREQS = (1.0, 5.0, 10.0, 20.0)


def spectra(v: np.ndarray, F: np.ndarray, fs: float) -> list[tuple[float, float]]:
    """``(|F/v| [N s/m], phase [deg])`` of ``F`` against ``v`` in each of :data:`BANDS`."""
    f, p_vv = sps.welch(v, fs=fs, nperseg=4096)
    _, p_vf = sps.csd(v, F, fs=fs, nperseg=4096)
    out = []
    for lo, hi in BANDS:
        k = (f >= lo) & (f < hi)
        out.append(
            (
                float(np.mean(np.abs(p_vf[k]) / p_vv[k])),
                float(np.degrees(np.angle(np.mean(p_vf[k])))),
            )
        )
    return out


def frozen_response(model: Any, currents: tuple[float, ...]) -> pd.DataFrame:
    """Gain (over the DC gain) and phase [deg] of the LPV model's frozen transfer function."""
    rows = []
    for rho in currents:
        a = np.asarray(model.a(rho)).ravel()
        b = np.asarray(model.b(rho)).ravel()
        num, den = np.r_[0.0, b], np.r_[1.0, a]
        _, h = sps.freqz(num, den, worN=[0.0, *FREQS], fs=model.fs)
        for f, hk in zip(FREQS, h[1:]):
            rows.append(
                {
                    "current_A": rho,
                    "f_Hz": f,
                    "gain": abs(hk) / abs(h[0]),
                    "phase_deg": float(np.degrees(np.angle(hk))),
                }
            )
    return pd.DataFrame(rows)


def main(argv: list[str] | None = None) -> pd.DataFrame:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="DoE duration factor [-]")
    ap.add_argument("--seed", type=int, default=0, help="road profile seed")
    ap.add_argument(
        "--extension", action="store_true", help="train on Table II and the control extension"
    )
    ap.add_argument(
        "--highpass",
        type=float,
        default=HIGHPASS,
        help="high-pass corner of the extension's replayed travel [Hz] (default: the extension's)",
    )
    ap.add_argument(
        "--controllers",
        default="soft,hard",
        help="comma-separated controllers (default: soft,hard)",
    )
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    truth = reference_damper("quiroz2022")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if args.extension:
            doe, ext, held_out = CL.training_records(truth, args.scale, highpass=args.highpass)
            est = get_estimator("lpv", input=truth.input, choose_on="held-out")
            model = est.fit(doe + ext, choice_records=held_out)
        else:
            doe = list(table_ii(seed=0, scale=args.scale, damper=truth))
            model = get_estimator("lpv", input=truth.input).fit(doe)
    print(f"lpv: {model.provenance.get('hysteretic_note', '')}")
    road = iso_road("C", speed=20.0, duration=20.0, fs=1000.0, seed=args.seed)
    rows = []
    for controller in args.controllers.split(","):
        r = simulate_closed_loop(model, road, controller, plant=truth)
        t = np.arange(r.t.size) / r.fs
        x, v = r.z_s - r.z_u, r.v_s - r.v_u
        rec = Experiment(t=t, x=x - x.mean(), v=v, F=r.F, i=r.i, name=controller)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            F_model = np.asarray(model.with_range_policy("clip").predict(rec)) - model.offset
        for (lo, hi), (mt, pt), (mm, pm) in zip(
            BANDS, spectra(v, r.F, r.fs), spectra(v, F_model, r.fs)
        ):
            rows.append(
                {
                    "controller": controller,
                    "band": f"{lo:g}-{hi:g} Hz",
                    "|F/v| true": mt,
                    "|F/v| model": mm,
                    "phase true": pt,
                    "phase model": pm,
                }
            )
        for lo, hi in V_BANDS:
            k = (np.abs(v) >= lo) & (np.abs(v) < hi)
            if k.sum() < 10:
                continue
            rows.append(
                {
                    "controller": controller,
                    "band": f"|v| {lo:g}-{hi:g} m/s",
                    "|F| true": float(np.mean(np.abs(r.F[k]))),
                    "|F| model": float(np.mean(np.abs(F_model[k]))),
                }
            )
    table = pd.DataFrame(rows)
    pd.set_option("display.width", 200)
    print(table.to_string(index=False, float_format=lambda z: f"{z:.0f}", na_rep=""))
    print("\nfrozen transfer function (gain relative to DC, phase [deg])")
    print(
        frozen_response(model, (0.0, 0.5, 1.0)).to_string(index=False, float_format="{:.3g}".format)
    )
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return table


if __name__ == "__main__":
    main()
