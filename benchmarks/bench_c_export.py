"""Time per sample of the exported C code against the compiled Python (numba) kernels, one run.

For an LPV model (n_m = 3, n_rho = 2, zone-law-free input u = v) and an SP-1 map, both with
synthetic coefficients, on a random-velocity record:

* forward model: C ``<name>_run`` (the per-sample ``<name>_step`` in a loop) against the numba
  record kernel the library uses (``simulate_record`` for LPV, ``sp_force`` for SP-1);
* regularised inverse: C ``<name>_inverse_run`` against the numba kernel (``lpv_inverse_reg_hys``,
  ``static_inverse_reg``), same weight and grid (32 intervals).

The C code is compiled with ``gcc -std=c99 -O2``; both are called once per record through their
array entry points (ctypes / numba dispatch overhead included once). Times are the minimum over
interleaved repeats; the table gives ns per sample and the ratio C / numba. Needs gcc.

Run::

    python benchmarks/bench_c_export.py            # 3 x 10^5 samples, 5 repeats
    python benchmarks/bench_c_export.py --quick    # 2 x 10^4 samples, 3 repeats
"""

from __future__ import annotations

import argparse
import ctypes
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from _timing import best_time

from mrdamper.control.export.c_export import export_c
from mrdamper.control.inverse import _inverse_kernels as IK
from mrdamper.control.inverse._forms import inverse_form
from mrdamper.control.inverse._inverse_setup import lpv_inverse_fields, static_map_arrays
from mrdamper.models.lpv import LPVModel
from mrdamper.models.lpv import kernels as LK
from mrdamper.models.semiphenomenological import SP1Model
from mrdamper.models.sp.kernels import sp_force

_P = ctypes.POINTER(ctypes.c_double)
ALPHA = np.array([[-1.5, 0.10, 0.01], [0.70, -0.05, 0.0], [-0.10, 0.0, 0.0]])
BETA = np.array([[600.0, 300.0, 60.0], [300.0, 60.0, 0.0], [60.0, 0.0, 0.0]])
S1 = (300.0, 900.0, 50.0, 40.0, 5.0, 0.0, 0.0, 0.0, 0.0, 800.0, 1500.0, 0.0, 1000.0, 0.0, 0.0)
REG = 500.0
N_GRID = 32


def _compile(model: object, folder: Path, name: str) -> ctypes.CDLL:
    _, c = export_c(model, folder, name=name, reg=REG, n_grid=N_GRID)
    lib = folder / f"lib{name}.so"
    subprocess.run(
        ["gcc", "-std=c99", "-O2", "-shared", "-fPIC", str(c), "-o", str(lib), "-lm"], check=True
    )
    return ctypes.CDLL(str(lib))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="2 x 10^4 samples, 3 repeats")
    args = ap.parse_args(argv)
    if shutil.which("gcc") is None:
        print("gcc not found: nothing to compare")
        return 1
    n, repeat = (20_000, 3) if args.quick else (300_000, 5)
    rng = np.random.default_rng(0)
    v = np.ascontiguousarray(
        np.convolve(rng.standard_normal(n), np.ones(20) / 20, mode="same") * 0.5
    )
    x = np.ascontiguousarray(np.cumsum(v) * 1e-3)
    i = np.ascontiguousarray(np.repeat(rng.uniform(0.0, 1.0, n // 50 + 1), 50)[:n])
    lpv = LPVModel(
        alpha=ALPHA,
        beta=BETA,
        fs=1000.0,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )
    sp1 = SP1Model(S=S1, input_range=(0.0, 1.0))
    F_lpv = LK.simulate_record(v, i, lpv.alpha, lpv.beta, 1e12)[0]
    comp, power, theta, f0 = static_map_arrays(sp1)
    F_sp = sp_force(x, v, i, comp, power, theta, f0)
    inv_lpv = inverse_form(lam=REG, n_grid=N_GRID, **lpv_inverse_fields(lpv))
    z_static = np.zeros(n)  # the static input: no Dahl state
    out = [np.zeros(n) for _ in range(2)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        libs = {"lpv": _compile(lpv, Path(tmp), "b_lpv"), "sp1": _compile(sp1, Path(tmp), "b_sp1")}
        cases = {
            ("lpv", "forward"): (
                lambda: libs["lpv"].b_lpv_run(
                    ctypes.c_long(n),
                    x.ctypes.data_as(_P),
                    v.ctypes.data_as(_P),
                    i.ctypes.data_as(_P),
                    out[0].ctypes.data_as(_P),
                ),
                lambda: LK.simulate_record(v, i, lpv.alpha, lpv.beta, 1e12),
            ),
            ("lpv", "inverse"): (
                lambda: libs["lpv"].b_lpv_inverse_run(
                    ctypes.c_long(n),
                    x.ctypes.data_as(_P),
                    v.ctypes.data_as(_P),
                    F_lpv.ctypes.data_as(_P),
                    out[0].ctypes.data_as(_P),
                    out[1].ctypes.data_as(_P),
                ),
                lambda: IK.lpv_inverse_reg_hys(v, F_lpv, inv_lpv, 0.0, 1.0, 0.0, np.inf, z_static),
            ),
            ("sp1", "forward"): (
                lambda: libs["sp1"].b_sp1_run(
                    ctypes.c_long(n),
                    x.ctypes.data_as(_P),
                    v.ctypes.data_as(_P),
                    i.ctypes.data_as(_P),
                    out[0].ctypes.data_as(_P),
                ),
                lambda: sp_force(x, v, i, comp, power, theta, f0),
            ),
            ("sp1", "inverse"): (
                lambda: libs["sp1"].b_sp1_inverse_run(
                    ctypes.c_long(n),
                    x.ctypes.data_as(_P),
                    v.ctypes.data_as(_P),
                    F_sp.ctypes.data_as(_P),
                    out[0].ctypes.data_as(_P),
                    out[1].ctypes.data_as(_P),
                ),
                lambda: IK.static_inverse_reg(
                    x, v, F_sp, comp, power, theta, f0, 0.0, 1.0, 0.0, N_GRID, REG, np.inf, -1.0
                ),
            ),
        }
        for (kind, what), (fc, fp) in cases.items():
            fc()
            fp()  # compile / warm up
            tc, tp = np.inf, np.inf
            for _ in range(repeat):  # interleaved
                tc = min(tc, best_time(fc, 1))
                tp = min(tp, best_time(fp, 1))
            rows.append((kind, what, 1e9 * tc / n, 1e9 * tp / n, tc / tp))
    print(f"{n} samples, minimum of {repeat} interleaved repeats")
    print(
        f"{'model':6s} {'part':8s} {'C [ns/sample]':>14s} {'numba [ns/sample]':>18s} "
        f"{'C / numba':>10s}"
    )
    for kind, what, c_ns, p_ns, ratio in rows:
        print(f"{kind:6s} {what:8s} {c_ns:14.1f} {p_ns:18.1f} {ratio:10.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
