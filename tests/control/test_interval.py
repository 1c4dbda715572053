"""The inverse's allowed interval, written once: the rule by hand, and its C twin against it."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mrdamper.control.export.c_render._common import COMMON, INTERVAL_C
from mrdamper.models.kernels import allowed_interval, held_input, lag_command

GCC = shutil.which("gcc")


def test_the_interval_by_hand() -> None:
    inf = np.inf
    assert allowed_interval(0, 0.0, 1.0, 0.5, 0.3, 0.3, 0.01) == (0.0, 1.0)  # sample 0 is free
    assert allowed_interval(1, 0.0, 1.0, 0.5, 0.3, 0.3, inf) == (0.3, 0.3)  # the lag at rest
    assert allowed_interval(2, 0.0, 1.0, 0.5, 0.4, 0.4, inf) == (0.2, 0.7)  # the lag's reach
    assert allowed_interval(2, 0.0, 1.0, -1.0, 0.4, 0.4, 0.1) == pytest.approx((0.3, 0.5))
    assert allowed_interval(2, 0.0, 1.0, 0.5, 0.4, 0.4, 0.1) == pytest.approx((0.3, 0.5))
    # a rate window that misses the interval: its nearest point to prev
    assert allowed_interval(3, 0.0, 1.0, -1.0, 1.5, 1.5, 0.1) == (1.0, 1.0)
    assert held_input(1, 0.5, 0.4, 0.9, 0.0, 1.0) == 0.4  # no held command before sample 2
    assert held_input(2, 0.5, 0.4, 0.8, 0.0, 1.0) == pytest.approx(0.6)
    assert held_input(2, 0.5, 0.4, 0.8, 0.0, 0.5) == 0.5  # within [a, b]
    assert held_input(2, -1.0, 0.4, 0.8, 0.0, 1.0) == 0.4  # no lag
    assert lag_command(1, 0.5, 0.3, 0.3, 0.0, 1.0, 0.0) == 0.3
    assert lag_command(2, 0.5, 0.6, 0.4, 0.0, 1.0, 0.0) == pytest.approx(0.8)
    assert lag_command(2, -1.0, 0.6, 0.4, 0.0, 1.0, 0.25) == 0.25


@pytest.mark.skipif(GCC is None, reason="gcc not found")
def test_the_c_interval_is_the_python_one(tmp_path: Path) -> None:
    lo, hi, rate = 0.1, 0.9, 0.05
    consts = (
        f"static const double T_LO = {lo.hex()};\nstatic const double T_HI = {hi.hex()};\n"
        f"static const double T_RATE_STEP = {rate.hex()};\n"
    )
    src = (
        COMMON.format(p="t", P="T")
        + consts
        + INTERVAL_C.format(p="t", P="T")
        + "void t_run(long k, double lag, double rho_prev, double prev, double *ab)\n"
        "{\n    t_allowed(k, lag, rho_prev, prev, &ab[0], &ab[1]);\n}\n"
    )
    c = tmp_path / "interval.c"
    c.write_text(src, encoding="utf-8")
    lib = tmp_path / "libinterval.so"
    flags = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2", "-shared", "-fPIC"]
    subprocess.run([GCC, *flags, str(c), "-o", str(lib)], check=True)  # type: ignore[list-item]
    run = ctypes.CDLL(str(lib)).t_run
    run.restype = None
    dbl = ctypes.c_double
    run.argtypes = [ctypes.c_long, dbl, dbl, dbl, ctypes.POINTER(dbl)]
    rng = np.random.default_rng(3)
    ab = (dbl * 2)()
    for _ in range(2000):
        k = int(rng.integers(0, 4))
        lag = float(rng.choice([-1.0, 0.0, rng.uniform(0, 1)]))
        rho_prev, prev = (float(x) for x in rng.uniform(-0.2, 1.2, 2))
        run(k, lag, rho_prev, prev, ab)
        want = allowed_interval(k, lo, hi, lag, rho_prev, prev, rate)
        assert (ab[0], ab[1]) == want, (k, lag, rho_prev, prev)
