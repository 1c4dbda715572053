"""Time per sample of the FMU against the C export and Python's step and ``predict``, one run.

For the Spencer et al. (1997) model (``spencer1997``, fixed step 1 ms: 107 RK4 sub-steps per
sample at the step's default velocity bound), an SP-1 map (the coefficients of
``bench_c_export.py``) and a small NARX model (two terms, 1 kHz), on a random-velocity record, per
sample:

* ``FMU (fmpy)``: the FMU driven by fmpy's ``FMU2Slave`` from Python, ``setReal`` / ``getReal`` /
  ``doStep`` at every sample (what a Python co-simulation pays);
* ``FMU (C calls)``: the same FMU functions called from a small C driver linked with the FMU's
  sources (the wrapper's own cost, as a tool importing the FMU would call it);
* ``C step``: the C export's ``<name>_run`` (``<name>_step`` in a loop) from the same driver;
* ``Python step``: :func:`mrdamper.models.step.run_step` (the numba loop over the step);
* ``predict``: the model's ``predict`` (the fused record kernel; Spencer with the step's sub-step
  count, so all columns compute the same values).

Everything is compiled with ``gcc -O2``; times are the minimum over repeats (fmpy: fewer samples,
the loop is Python). Needs gcc and fmpy (``pip install "mrdamper[fmu]"``).

Run::

    python benchmarks/bench_fmu.py            # 10^5 samples (fmpy: 10^4), 5 repeats
    python benchmarks/bench_fmu.py --quick    # 10^4 samples (fmpy: 2 x 10^3), 3 repeats
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from _timing import best_time
from bench_c_export import S1

from mrdamper.control.export.fmu import export_fmu
from mrdamper.data import Experiment
from mrdamper.models.narx import NARXModel
from mrdamper.models.semiphenomenological import SP1Model
from mrdamper.models.spencer import spencer1997
from mrdamper.models.step import run_step

DT = 1e-3

_DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "{p}.h"
#include "{p}_fmi2.h"

fmi2Component fmi2Instantiate(fmi2String, fmi2Type, fmi2String, fmi2String,
                              const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
fmi2Status fmi2SetReal(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
fmi2Status fmi2GetReal(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
fmi2Status fmi2DoStep(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
void fmi2FreeInstance(fmi2Component);

static double now(void)
{{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}}

int main(int argc, char **argv)
{{
    long n = atol(argv[2]), k;
    int r, repeat = atoi(argv[4]);
    double *u = malloc(3 * n * sizeof(double)), *F = malloc(n * sizeof(double));
    double best_c = 1e30, best_f = 1e30, sum = 0.0, t0;
    const fmi2ValueReference vin[3] = {{0, 1, 2}}, vout[1] = {{3}};
    fmi2CallbackFunctions cb = {{NULL, NULL, NULL, NULL, NULL}};
    FILE *f = fopen(argv[1], "rb");
    if (!f || fread(u, sizeof(double), 3 * n, f) != (size_t)(3 * n)) return 1;
    fclose(f);
    for (r = 0; r < repeat; ++r) {{
        t0 = now();
        {p}_run(n, u, u + n, u + 2 * n, F);
        if (now() - t0 < best_c) best_c = now() - t0;
        sum += F[n - 1];
        t0 = now();
        {{
            fmi2Component c = fmi2Instantiate("b", fmi2CoSimulation, argv[3], "", &cb, 0, 0);
            for (k = 0; k < n; ++k) {{
                double in[3] = {{u[k], u[n + k], u[2 * n + k]}};
                fmi2SetReal(c, vin, 3, in);
                fmi2GetReal(c, vout, 1, &F[k]);
                fmi2DoStep(c, k * {dt}, {dt}, 1);
            }}
            fmi2FreeInstance(c);
        }}
        if (now() - t0 < best_f) best_f = now() - t0;
        sum += F[n - 1];
    }}
    printf("%.6e %.6e %.17g\n", best_c / n, best_f / n, sum);
    return 0;
}}
"""


def _record(n: int) -> Experiment:
    rng = np.random.default_rng(0)
    v = np.convolve(rng.standard_normal(n), np.ones(20) / 20, mode="same") * 0.5
    x = np.cumsum(v) * DT
    e = np.repeat(rng.uniform(0.0, 1.0, n // 50 + 1), 50)[:n]
    return Experiment(t=np.arange(n) * DT, x=x, v=v, F=0 * x, i=e)


def _fmpy_loop(fmu: Path, rec: Experiment) -> np.ndarray:
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmu)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="b",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    F = np.zeros(rec.n)
    for k in range(rec.n):
        slave.setReal([0, 1, 2], [rec.x[k], rec.v[k], rec.i[k]])
        F[k] = slave.getReal([3])[0]
        slave.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
    slave.terminate()
    slave.freeInstance()
    return F


def _c_driver(fmu: Path, name: str, rec: Experiment, repeat: int, folder: Path) -> list[float]:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
        desc = z.read("modelDescription.xml").decode()
    guid = desc.split('guid="', 1)[1].split('"', 1)[0]
    src = folder / "sources"
    (src / "driver.c").write_text(_DRIVER.format(p=name, dt=float(DT).hex()))
    exe = folder / "driver"
    subprocess.run(
        ["gcc", "-std=c99", "-O2", "-o", str(exe)]
        + [str(src / f) for f in ("driver.c", f"{name}.c", f"{name}_fmu.c")]
        + ["-lm"],
        check=True,
    )
    data = folder / "u.bin"
    np.concatenate([rec.x, rec.v, rec.i]).astype("<f8").tofile(data)
    out = subprocess.run(
        [str(exe), str(data), str(rec.n), guid, str(repeat)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split()
    return [float(out[0]), float(out[1])]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="10^4 samples, 3 repeats")
    args = ap.parse_args(argv)
    if shutil.which("gcc") is None:
        print("gcc not found: nothing to compare")
        return 1
    n, n_fmpy, repeat = (10_000, 2_000, 3) if args.quick else (100_000, 10_000, 5)
    rec = _record(n)
    spencer = dataclasses.replace(spencer1997(), input="i", input_range=(0.0, 1.0))
    step = spencer.step(dt=DT)
    nsub = math.ceil(DT / step.form.max_h * (1.0 - 1e-12))
    models = {
        "spencer": (spencer, dataclasses.replace(spencer, substeps=nsub)),
        "sp1": (SP1Model(S=S1, input_range=(0.0, 1.0)), None),
        "narx": (
            NARXModel(
                fs=1.0 / DT,
                base=[[0, 1], [2, 0]],
                terms=[[0], [1]],
                theta=[0.5, 1.0],
                scales=[1000.0, 1.0, 0.1, 1.0, 1.0],
                v0=0.01,
                input_range=(0.0, 1.0),
            ),
            None,
        ),
    }
    print(f"{n} samples (fmpy {n_fmpy}), minimum of {repeat} repeats; times in us per sample")
    heads = ("FMU (fmpy)", "FMU (C)", "C step", "Py step", "predict")
    print(f"{'model':8} " + " ".join(f"{h:>9}" for h in heads))
    short = rec.slice(0, n_fmpy)
    with tempfile.TemporaryDirectory() as tmp:
        for kind, (model, like_step) in models.items():
            folder = Path(tmp) / kind
            fmu = export_fmu(model, folder / f"{kind}.fmu", name=kind, dt=DT)
            _fmpy_loop(fmu, short)  # load once
            t_fmpy = best_time(lambda f=fmu: _fmpy_loop(f, short), max(1, repeat - 2)) / n_fmpy
            t_c, t_fmu_c = _c_driver(fmu, kind, rec, repeat, folder)
            st = model.step(dt=DT)
            run_step(st, rec.x[:10], rec.v[:10], rec.i[:10], DT)  # compile
            t_step = best_time(lambda s=st: run_step(s, rec.x, rec.v, rec.i, DT), repeat) / n
            predictor = like_step or model
            predictor.predict(rec)
            t_pred = best_time(lambda p=predictor: p.predict(rec), repeat) / n
            times = [t_fmpy, t_fmu_c, t_c, t_step, t_pred]
            print(f"{kind:8} " + " ".join(f"{1e6 * t:>9.3f}" for t in times))
            print(
                f"{'':8} ratios to the C step: FMU (fmpy) {t_fmpy / t_c:.0f}, FMU (C) "
                f"{t_fmu_c / t_c:.2f}, Python step {t_step / t_c:.2f}, predict {t_pred / t_c:.2f}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
