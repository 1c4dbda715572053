"""The exported damper is the validated damper: for every kind of the kind table, the C code
and the FMU (driven by fmpy) equal the model's ``predict`` on a short record at 200 Hz and at
1 kHz, at that record's rate, to 1e-9 relative RMS; and every C export compiles clean with
``-std=c99 -Wall -Wextra -pedantic -Werror`` (gcc, and clang where installed).

Models: each kind fitted once on the conformance records (``kind_models``); a discrete-time
kind (LPV, LTI, NARX) runs at the record's rate (its model rate set to it), a continuous-time or
static kind is exported at the record's interval. The record stays within the step's
velocity bound, where ``predict`` and the exported step take the same integration sub-steps
(:meth:`mrdamper.models.base.FittedModel.step_vmax`).
"""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import subprocess
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper import Experiment
from mrdamper.control.export.fmu import FMU_KINDS, export_fmu, fmu_sources, run_fmu
from tests.conftest import package_kinds
from tests.control.test_c_export import STRICT

pytestmark = [
    pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found"),
    pytest.mark.filterwarnings("ignore:.*leaves the model's training envelope"),
]
fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (optional extra [fmu])")

KINDS = package_kinds()
RATES = (200.0, 1000.0)
#: Compilers of the strict check (clang only where installed).
COMPILERS = [c for c in ("gcc", "clang") if shutil.which(c)]
_P = ctypes.POINTER(ctypes.c_double)


def _probe(fs: float) -> Experiment:
    """0.5 s of a 3 Hz sine (peak 57 mm/s, within the step's velocity bound) with the current
    stepping through four levels inside the training range."""
    t = np.arange(round(0.5 * fs)) / fs
    x = 0.003 * np.sin(2 * np.pi * 3.0 * t)
    v = 0.003 * 2 * np.pi * 3.0 * np.cos(2 * np.pi * 3.0 * t)
    i = np.array([0.3, 0.7, 0.4, 0.6])[(np.arange(t.size) * 4) // t.size]
    return Experiment(t=t, x=x, v=v, F=np.zeros_like(t), i=i, name=f"probe{fs:g}")


def _at_rate(model: Any, fs: float) -> Any:
    """A discrete-time model at the rate ``fs`` (its coefficients unchanged); others as they
    are."""
    if hasattr(model, "fs"):
        return dataclasses.replace(model, fs=fs, sample_time=1.0 / fs)
    return model


def _signals(rec: Experiment, name: str, e: np.ndarray) -> np.ndarray:
    """The record's inputs as fmpy's structured input array."""
    dtype = [("time", np.float64), ("x", np.float64), ("v", np.float64), (name, np.float64)]
    out = np.zeros(rec.n, dtype=dtype)
    out["time"], out["x"], out["v"], out[name] = np.arange(rec.n) * rec.dt, rec.x, rec.v, e
    return out


def _rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2)))


def test_probe_is_within_the_velocity_bound(kind_models: dict[str, Any]) -> None:
    for fs in RATES:
        assert np.max(np.abs(_probe(fs).v)) < kind_models["sp1"].step_vmax()


@pytest.mark.parametrize("fs", RATES)
@pytest.mark.parametrize("kind", KINDS)
def test_c_and_fmu_equal_predict(
    tmp_path: Path, kind: str, fs: float, kind_models: dict[str, Any]
) -> None:
    assert kind in FMU_KINDS
    model, rec = _at_rate(kind_models[kind], fs), _probe(fs)
    expected = model.predict(rec)
    assert np.max(np.abs(expected)) > 1.0  # the record moves the damper
    e = model.electrical_input(rec)
    own = hasattr(model, "fs")
    fmu = export_fmu(model, tmp_path / "d.fmu", name="d", dt=None if own else rec.dt)
    assert _rel_rms(run_fmu(fmu, rec.x, rec.v, e)[:, 0], expected) <= 1e-9
    if fs == RATES[-1]:
        # fmpy's validation, and the step's feedthrough recorded in the FMU
        from fmpy.validation import validate_fmu

        from mrdamper.control.export.fmu_plant import FMUPlant

        assert validate_fmu(str(fmu)) == []
        assert FMUPlant(fmu).step().feedthrough == model.step(dt=rec.dt).feedthrough
        # the co-simulation convention with fmpy's own loop, which reads the outputs right after
        # doStep: every kind's force one communication step late, exactly
        sim = fmpy.simulate_fmu(
            str(fmu),
            stop_time=(rec.n - 1) * rec.dt,
            output_interval=rec.dt,
            input=_signals(rec, model.input, e),
            output=["F"],
        )
        assert sim["F"].size == rec.n
        assert sim["F"][0] == pytest.approx(expected[0], rel=1e-12, abs=1e-9)
        assert _rel_rms(sim["F"][1:], expected[:-1]) <= 1e-9
        # a current 5 % beyond the identified range: the input as given, not clipped (as the
        # step; predict with range_policy="ignore")
        beyond = rec.replace(i=rec.i * 1.2)
        assert np.max(beyond.i) > model.input_range[1] * 1.04
        loose = model.with_range_policy("ignore")
        F = run_fmu(fmu, beyond.x, beyond.v, beyond.i)[:, 0]
        assert _rel_rms(F, loose.predict(beyond)) <= 1e-9
    # the C code inside the FMU: <name>_run, one call of <name>_step a sample
    with zipfile.ZipFile(fmu) as z:
        (tmp_path / "d.so").write_bytes(z.read("binaries/linux64/d.so"))
    lib = ctypes.CDLL(str(tmp_path / "d.so"))
    x, v, e = (np.ascontiguousarray(a, dtype=np.float64) for a in (rec.x, rec.v, e))
    F = np.zeros(rec.n)
    lib.d_run(ctypes.c_long(rec.n), *(a.ctypes.data_as(_P) for a in (x, v, e, F)))
    assert _rel_rms(F, expected) <= 1e-9


@pytest.mark.parametrize("compiler", COMPILERS)
@pytest.mark.parametrize("kind", KINDS)
def test_every_c_export_compiles_clean(
    tmp_path: Path, kind: str, compiler: str, kind_models: dict[str, Any]
) -> None:
    """The model's C and the FMU wrapper, forward and (where the kind has one) inverse, with
    every warning an error."""
    model = kind_models[kind]
    dt = None if hasattr(model, "fs") else 1e-3
    files, _ = fmu_sources(model, "d", dt=dt)
    if "d_inverse_step" in files["sources/d.h"]:
        inverse, _ = fmu_sources(model, "i", dt=dt, inverse=True)
        files = {**files, **inverse}
    for path, text in files.items():
        if path.startswith("sources/"):
            (tmp_path / Path(path).name).write_text(text, encoding="utf-8")
    sources = [str(p) for p in sorted(tmp_path.glob("*.c"))]
    done = subprocess.run(
        [compiler, *STRICT, "-c", *sources],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, f"{kind}: {done.stderr}"
    assert len(list(tmp_path.glob("*.o"))) == len(sources) >= 2


def test_export_step_defaults_to_the_fitted_sample_time() -> None:
    """The model's ``sample_time``; for a model file without it (version 1), the training
    records' interval when they had one, else a one-line refusal naming their rates."""
    from mrdamper.control.export.c_export import c_source
    from mrdamper.errors import DataValidationError
    from mrdamper.models.bingham import BinghamModel
    from mrdamper.models.spencer import spencer1997

    bing = BinghamModel(fc=(100.0, 500.0), c0=(1000.0, 2000.0), input_range=(0.0, 1.0))
    assert fmu_sources(dataclasses.replace(bing, sample_time=0.005), "b")[1] == 0.005
    one = dataclasses.replace(bing, provenance={"record_dt": [0.002]})
    assert fmu_sources(one, "b")[1] == 0.002  # a file written before sample_time
    mixed = dataclasses.replace(spencer1997(), provenance={"record_dt": [0.001, 0.005]})
    for call in (lambda: fmu_sources(mixed, "s"), lambda: c_source(mixed, "s")):
        with pytest.raises(DataValidationError, match=r"training records at 1000, 200 Hz\)") as e:
            call()
        assert "\n" not in str(e.value) and "--dt" in str(e.value)
