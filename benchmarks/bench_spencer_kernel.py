"""Spencer kernel (compiled RK4) versus scipy.integrate.solve_ivp (LSODA) at matched accuracy.

Both integrate the same equations with the same linearly interpolated inputs. Accuracy is the
force RMS error over the standard deviation of a tight reference (LSODA, rtol 1e-11, at most one
step per sample so the piecewise-linear inputs are followed). For the
peer, the loosest rtol in 1e-3 ... 1e-10 whose error is not larger than the kernel's is timed.

Records: the Dyke (1996) random-voltage record (first 2 s) with Spencer's published parameters,
and one Quiroz sine record with the shipped calibration, when ../shared/data is present;
otherwise a synthetic switching-voltage record.

Usage::

    python benchmarks/bench_spencer_kernel.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from _timing import best_time
from scipy.integrate import solve_ivp

from mrdamper.data import Experiment
from mrdamper.models import load_model
from mrdamper.models.spencer import SpencerModel, spencer1997
from mrdamper.models.spencer import kernels as K

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data"


def peer(model: SpencerModel, exp: Experiment, rtol: float, max_step: float = np.inf) -> np.ndarray:
    """Force from solve_ivp(LSODA) with the same interpolated inputs."""
    p = model.parameter_vector()
    e = model.electrical_input(exp)  # same range policy (clipping) as the kernel
    t, x, v = exp.t, exp.x, exp.v
    rhs_scalar = K._rhs.py_func

    def rhs(tt: float, s: np.ndarray) -> list[float]:
        k = min(max(int((tt - t[0]) / exp.dt), 0), exp.n - 2)
        a = (tt - t[k]) / exp.dt
        yd, zd, ud, _ = rhs_scalar(
            x[k] + a * (x[k + 1] - x[k]),
            v[k] + a * (v[k + 1] - v[k]),
            e[k] + a * (e[k + 1] - e[k]),
            s[0],
            s[1],
            s[2],
            p,
        )
        return [yd, zd, ud]

    sol = solve_ivp(
        rhs,
        (t[0], t[-1]),
        [x[0], 0.0, e[0]],
        method="LSODA",
        t_eval=t,
        rtol=rtol,
        atol=1e-12,
        max_step=max_step,
    )
    if not sol.success:
        raise RuntimeError(sol.message)
    y, z, u = sol.y
    c0, c1, al = p[0] + p[1] * u, p[3] + p[4] * u, p[7] + p[8] * u
    yd = (al * z + c0 * v + p[2] * (x - y)) / (c0 + c1)
    return c1 * yd + p[5] * (x - p[6]) + p[14]


def cases() -> list[tuple[str, SpencerModel, Experiment]]:
    out = []
    dyke = SHARED / "dyke1996_nees" / "ranran_50.csv"
    if dyke.exists():
        df = pd.read_csv(dyke, nrows=6010)
        t = np.arange(len(df)) / 3004.8
        exp = Experiment(
            t=t,
            x=df["x"].to_numpy(),
            v=df["v"].to_numpy(),
            F=df["F"].to_numpy(),
            voltage=df["voltage"].to_numpy(),
            name="dyke_ranran_50_2s",
        )
        out.append(("spencer1997 / Dyke 2 s", spencer1997(range_policy="clip"), exp))
    q = SHARED / "quiroz2022_utfsm" / "sine_unfiltered" / "sine_5mm_4Hz_1A.csv"
    if q.exists():
        df = pd.read_csv(q)
        exp = Experiment(
            t=df["t"].to_numpy(),
            x=df["x"].to_numpy(),
            v=df["v"].to_numpy(),
            F=df["F"].to_numpy(),
            i=df["i"].to_numpy(),
            name=q.stem,
        )
        model = load_model(REPO / "src" / "mrdamper" / "rig" / "parameters" / "quiroz2022.json")
        out.append(("quiroz2022 / sine_5mm_4Hz_1A", model, exp))
    if not out:
        rng = np.random.default_rng(0)
        t = np.arange(6000) / 3000.0
        x = 0.004 * np.sin(2 * np.pi * 3 * t) + 0.001 * np.sin(2 * np.pi * 17 * t)
        v = 0.004 * 2 * np.pi * 3 * np.cos(2 * np.pi * 3 * t) + 0.001 * 2 * np.pi * 17 * np.cos(
            2 * np.pi * 17 * t
        )
        volt = 2.25 * (rng.random(300) > 0.5)[(t / 0.01).astype(int)]
        out.append(
            (
                "spencer1997 / synthetic",
                spencer1997(),
                Experiment(t=t, x=x, v=v, F=0 * t, voltage=volt, name="synthetic"),
            )
        )
    return out


def main() -> None:
    rows = []
    for label, model, exp in cases():
        model.predict(exp)  # compile / load cache
        ref = peer(model, exp, 1e-11, max_step=exp.dt)
        sd = float(np.std(ref))
        F = model.predict(exp)
        err_k = float(np.sqrt(np.mean((F - ref) ** 2)) / sd)
        t_k = best_time(lambda m=model, x=exp: m.predict(x))
        chosen = None
        for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
            Fp = peer(model, exp, rtol)
            err_p = float(np.sqrt(np.mean((Fp - ref) ** 2)) / sd)
            if err_p <= err_k:
                chosen = (rtol, err_p)
                break
        if chosen is None:
            chosen = (1e-10, err_p)
        t_p = best_time(lambda m=model, x=exp, r=chosen[0]: peer(m, x, r), repeat=2)
        rows.append(
            {
                "case": label,
                "samples": exp.n,
                "substeps": model.substeps_for(exp),
                "kernel_s": t_k,
                "kernel_err": err_k,
                "lsoda_rtol": chosen[0],
                "lsoda_s": t_p,
                "lsoda_err": chosen[1],
                "speed-up": t_p / t_k,
            }
        )
    table = pd.DataFrame(rows)
    with pd.option_context("display.width", 160):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    print(
        "errors: RMS force error / std of the LSODA rtol=1e-11 reference; times: best of runs [s]"
    )


if __name__ == "__main__":
    main()
