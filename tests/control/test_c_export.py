"""C99 export: compiled with ``gcc -std=c99 -Wall -Wextra -pedantic -Werror`` and compared with
the Python simulation and the Python inverse on real records (skipped without gcc or without the
shared data)."""

from __future__ import annotations

import ctypes
import dataclasses
import math
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper.control import inverse_current
from mrdamper.control.export.c_export import C_KINDS, c_source, export_c
from mrdamper.control.inverse.current import default_reg
from mrdamper.errors import DataValidationError, OutputExistsError
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.protocols import InvertibleModel, StepInvertibleModel
from tests.control.conftest import toy_lti

GCC = shutil.which("gcc")
needs_gcc = pytest.mark.skipif(GCC is None, reason="gcc not found")
#: Warnings every C export compiles clean of (issue: a user's ``-Wextra -pedantic -Werror``).
STRICT = ("-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror")
_P = ctypes.POINTER(ctypes.c_double)


def _build(model: Any, folder: Path, name: str, **kw: Any) -> ctypes.CDLL:
    _, c = export_c(model, folder, name=name, **kw)
    lib = folder / f"lib{name}.so"
    subprocess.run(
        [
            str(GCC),
            *STRICT,
            "-O2",
            "-shared",
            "-fPIC",
            str(c),
            "-o",
            str(lib),
            "-lm",
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    return ctypes.CDLL(str(lib))


def _arr(a: Any) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _forward(lib: ctypes.CDLL, name: str, x: Any, v: Any, inp: Any) -> np.ndarray:
    x, v, inp = _arr(x), _arr(v), _arr(inp)
    F = np.zeros(x.size)
    getattr(lib, f"{name}_run")(
        ctypes.c_long(x.size),
        x.ctypes.data_as(_P),
        v.ctypes.data_as(_P),
        inp.ctypes.data_as(_P),
        F.ctypes.data_as(_P),
    )
    return F


def _inverse(lib: ctypes.CDLL, name: str, x: Any, v: Any, Fd: Any) -> tuple[np.ndarray, np.ndarray]:
    x, v, Fd = _arr(x), _arr(v), _arr(Fd)
    i, F = np.zeros(x.size), np.zeros(x.size)
    getattr(lib, f"{name}_inverse_run")(
        ctypes.c_long(x.size),
        x.ctypes.data_as(_P),
        v.ctypes.data_as(_P),
        Fd.ctypes.data_as(_P),
        i.ctypes.data_as(_P),
        F.ctypes.data_as(_P),
    )
    return i, F


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@needs_gcc
@pytest.mark.slow  # C parity on fitted real-data models (the synthetic parity tests stay quick)
@pytest.mark.parametrize("kind", ["lpv", "sp1"])
def test_c_matches_python_on_a_quiroz_record(
    tmp_path: Path, quiroz_models: dict[str, Any], quiroz_records: list[Any], kind: str
) -> None:
    model = quiroz_models[kind]
    rec = next(
        e for e in quiroz_records if e.name == "sine_25mm_0.5Hz_0.5A"
    )  # 200 Hz: the LPV model rate
    lib = _build(model, tmp_path, f"q_{kind}", reg=800.0, n_grid=32)
    assert _rel(_forward(lib, f"q_{kind}", rec.x, rec.v, rec.i), model.predict(rec)) < 1e-9
    i_c, F_c = _inverse(lib, f"q_{kind}", rec.x, rec.v, rec.F)
    res = inverse_current(model, rec, rec.F, reg=800.0)
    assert _rel(i_c, res.rho) < 1e-9
    assert _rel(F_c, res.F_achieved) < 1e-9


@needs_gcc
@pytest.mark.slow  # C parity with a drive lag on a model fitted to the Dyke record
def test_c_with_drive_lag_on_dyke(
    tmp_path: Path, dyke_models: dict[str, Any], dyke_record: Any
) -> None:
    model = dyke_models["lpv"]  # voltage input through the drive lag eta = 250 1/s
    rec = dyke_record.slice(0, 6000)
    lib = _build(model, tmp_path, "d_lpv", n_grid=32)
    F_py = model.with_range_policy("ignore").predict(rec)  # the C input is not clipped
    assert _rel(_forward(lib, "d_lpv", rec.x, rec.v, rec.voltage), F_py) < 1e-9
    rho_c, _ = _inverse(lib, "d_lpv", rec.x, rec.v, rec.F)
    res = inverse_current(
        model, rec, rec.F, reg=default_reg(model, 0.3, 1.0 / model.fs)
    )  # the C default
    assert _rel(rho_c, res.rho) < 1e-9


@needs_gcc
def test_c_bingham_and_lti(tmp_path: Path) -> None:
    n = 1500
    t = np.arange(n) / 1000.0
    x, v = 0.01 * np.sin(2 * np.pi * 2 * t), 0.01 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t)
    i = np.clip(0.5 + 0.4 * np.sin(2 * np.pi * 0.7 * t), 0.0, 1.0)
    from mrdamper.data import Experiment

    e = Experiment(t=t, x=x, v=v, F=0 * t, i=i)
    bing = BinghamModel(
        fc=(100.0, 500.0, -50.0), c0=(1000.0, 2000.0), v_eps=0.02, f0=3.0, input_range=(0.0, 1.0)
    )
    lib = _build(bing, tmp_path, "bing")
    assert _rel(_forward(lib, "bing", x, v, i), bing.predict(e)) < 1e-9
    lti = toy_lti()
    lib = _build(lti, tmp_path, "lti")
    assert _rel(_forward(lib, "lti", x, v, i), lti.predict(e)) < 1e-9
    assert not hasattr(
        lib, "lti_inverse_run"
    )  # no inverse: the LTI force does not depend on the input


def _sub_sample_record(n: int, dt: float, input: str) -> Any:
    """Synthetic record: a 3 Hz, 10 mm sine and a slowly varying input inside [0, 2]."""
    from mrdamper.data import Experiment

    t = np.arange(n) * dt
    x, v = 0.01 * np.sin(2 * np.pi * 3 * t), 0.01 * 2 * np.pi * 3 * np.cos(2 * np.pi * 3 * t)
    e = np.clip(1.0 + 0.9 * np.sin(2 * np.pi * 0.7 * t), 0.0, 2.0)
    return Experiment(t=t, x=x, v=v, F=0 * t, **{input: e})


def spencer_predicting_like_its_step(model: Any, dt: float) -> Any:
    """The model with the sub-step count its step takes at ``dt``, so that ``predict`` runs the
    same RK4 steps as the step (the automatic count of ``predict`` follows the record)."""
    form = model.step(dt=dt).form
    return dataclasses.replace(model, substeps=math.ceil(dt / form.max_h * (1.0 - 1e-12)))


@needs_gcc
def test_c_spencer_step_matches_run_step_and_predict(tmp_path: Path) -> None:
    from mrdamper.models.spencer import spencer1997
    from mrdamper.models.step import run_step

    model, dt = spencer1997(), 1e-3
    rec = _sub_sample_record(3000, dt, "voltage")
    lib = _build(model, tmp_path, "sp", dt=dt)
    F_c = _forward(lib, "sp", rec.x, rec.v, rec.voltage)
    F_step, status, _ = run_step(model.step(dt=dt), rec.x, rec.v, rec.voltage, dt)
    assert status == 0
    assert _rel(F_c, F_step) < 1e-9
    assert _rel(F_c, spencer_predicting_like_its_step(model, dt).predict(rec)) < 1e-9
    assert not hasattr(lib, "sp_inverse_run")


@needs_gcc
def test_c_spencer_on_a_quiroz_record(tmp_path: Path, quiroz_records: list[Any]) -> None:
    """A published Spencer model in current units, driven by a measured record (2 kHz)."""
    from mrdamper.models.spencer import spencer1997

    rec = next(e for e in quiroz_records if e.name == "sine_25mm_0.5Hz_0.5A")
    model = dataclasses.replace(spencer1997(), input="i", input_range=(0.0, 2.25))
    lib = _build(model, tmp_path, "qsp", dt=rec.dt)
    F_c = _forward(lib, "qsp", rec.x, rec.v, rec.i)
    assert _rel(F_c, spencer_predicting_like_its_step(model, rec.dt).predict(rec)) < 1e-9


@needs_gcc
def test_c_spencer_divergence_returns_nan(tmp_path: Path) -> None:
    from mrdamper.models.spencer import spencer1997

    bad = dataclasses.replace(spencer1997(), c0a=-1e5)  # non-positive damping
    lib = _build(bad, tmp_path, "bad", dt=1e-3)
    rec = _sub_sample_record(10, 1e-3, "voltage")
    F = _forward(lib, "bad", rec.x, rec.v, rec.voltage)
    assert np.isfinite(F[0]) and np.isnan(F[1:]).all()


def test_refusals(tmp_path: Path) -> None:
    from mrdamper.models.phenomenological import P15Model
    from mrdamper.models.spencer import spencer1997

    toy = dataclasses.make_dataclass("Toy", [("kind", str)])("toy")
    with pytest.raises(DataValidationError, match="C export handles kinds"):
        c_source(toy)
    with pytest.raises(DataValidationError, match="dt: the spencer C step"):
        c_source(spencer1997())
    with pytest.raises(DataValidationError, match="dt: the p15 C step"):
        c_source(P15Model(input_range=(0.0, 1.0)))
    bing = BinghamModel(fc=(100.0, 500.0), c0=(1000.0, 2000.0), input_range=(0.0, 1.0))
    with pytest.raises(DataValidationError, match="C identifier"):
        c_source(bing, "1bad-name")
    from mrdamper.models.semiphenomenological import SP3Model

    lagged = SP3Model(
        S=(800.0, 200.0, 60.0, 0.0, 900.0, 0.0),
        input_range=(0.0, 2.0),
        eta=30.0,
        rho_range=(0.0, 2.0),
    )
    with pytest.raises(DataValidationError, match="drive lag"):
        c_source(lagged)
    export_c(bing, tmp_path, name="b")
    with pytest.raises(OutputExistsError):
        export_c(bing, tmp_path, name="b")
    export_c(bing, tmp_path, name="b", force=True)


# ------------------------------------------------------------------ every kind, from its step
def _step_lib(model: Any, folder: Path, name: str, dt: float) -> ctypes.CDLL:
    lib = _build(model, folder, name, dt=dt)
    d, vp = ctypes.c_double, ctypes.c_void_p
    getattr(lib, f"{name}_step_init").argtypes = [vp, d, d, d]
    getattr(lib, f"{name}_step_force").argtypes = [vp, d, d, d]
    getattr(lib, f"{name}_step_force").restype = d
    getattr(lib, f"{name}_step_advance").argtypes = [vp, d, d, d, d, d, d, d]
    return lib


@needs_gcc
@pytest.mark.parametrize("kind", C_KINDS)
@pytest.mark.slow
def test_c_step_of_every_kind_matches_run_step(
    tmp_path: Path, kind: str, kind_models: dict[str, Any], kind_probe: Any
) -> None:
    """``<name>_run`` (one call of ``<name>_step`` a sample) and the step functions
    (``<name>_step_init`` / ``_step_force`` / ``_step_advance`` on the Python step's state
    layout) against :func:`run_step`, sample by sample, to 1e-9 of the force scale."""
    from mrdamper.models.step import run_step

    model, rec = kind_models[kind], kind_probe
    e = np.ascontiguousarray(model.electrical_input(rec))
    step = model.step(dt=rec.dt)
    F_py, status, _ = run_step(step, rec.x, rec.v, e, rec.dt)
    assert status == 0
    lib = _step_lib(model, tmp_path, f"k_{kind}", rec.dt)
    assert _rel(_forward(lib, f"k_{kind}", rec.x, rec.v, e), F_py) < 1e-9
    s_py = step.initial_state(rec.x[0], rec.v[0], e[0])
    s_c = np.zeros(getattr(lib, f"k_{kind}_step_size")())
    assert s_c.size == s_py.size
    getattr(lib, f"k_{kind}_step_init")(s_c.ctypes.data, rec.x[0], rec.v[0], e[0])
    F_c = np.zeros(rec.n)
    for k in range(rec.n):
        F_c[k] = getattr(lib, f"k_{kind}_step_force")(s_c.ctypes.data, rec.x[k], rec.v[k], e[k])
        if k + 1 < rec.n:
            args = (rec.x[k], rec.v[k], e[k], rec.x[k + 1], rec.v[k + 1], e[k + 1], rec.dt)
            assert getattr(lib, f"k_{kind}_step_advance")(s_c.ctypes.data, *args) == 0
            assert step.advance(step.form, s_py, *args) == 0
    assert _rel(F_c, F_py) < 1e-9
    np.testing.assert_allclose(s_c, s_py, rtol=1e-9, atol=1e-9 * float(np.max(np.abs(s_py))))
    invertible = isinstance(model, InvertibleModel) or (
        isinstance(model, StepInvertibleModel) and step.feedthrough
    )
    assert hasattr(lib, f"k_{kind}_inverse_run") == invertible


def test_lpv_and_static_renderings_read_their_step_forms(kind_models: dict[str, Any]) -> None:
    """The step forms hold the arrays the model's law and map methods give (so the C constants,
    now read from the forms, are those the renderers formerly rebuilt from the model)."""
    from mrdamper.control.inverse.current import lpv_hysteresis, lpv_law_arrays, static_map_arrays

    lpv = kind_models["lpv"]
    form = lpv.step().form
    mode, gm, gc, mu_h, mu_l = lpv_law_arrays(lpv)
    assert form.mode == mode and (form.blend, form.stroke) == lpv_hysteresis(lpv)
    for a, b in ((form.gamma_m, gm), (form.gamma_c, gc), (form.mu_high, mu_h), (form.mu_low, mu_l)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(form.alpha, lpv.alpha)
    for kind in ("sp1", "bingham"):
        comp, power, theta, f0 = static_map_arrays(kind_models[kind])
        sform = kind_models[kind].step().form
        np.testing.assert_array_equal(sform.theta, theta)
        np.testing.assert_array_equal(sform.comp, comp)
        np.testing.assert_array_equal(sform.power, power)
        assert sform.f0 == f0


# ------------------------------------------------------------ the one-state hysteresis families
def _hysteresis_truths() -> dict[str, dict[str, float]]:
    """Each family's known-answer parameters (``tests/models/test_<kind>.py``)."""
    from tests.models import test_boucwen, test_dahl, test_lugre, test_tanh

    return {
        m.__name__.rsplit("_", 1)[1]: dict(m.TRUE)
        for m in (test_tanh, test_boucwen, test_dahl, test_lugre)
    }


def _c_vs_step(model: Any, folder: Path, name: str, x: Any, v: Any, e: Any, dt: float) -> float:
    from mrdamper.models.step import run_step

    F_py, status, _ = run_step(model.step(dt=dt), x, v, e, dt)
    assert status == 0
    lib = _build(model, folder, name, dt=dt)
    assert hasattr(lib, f"{name}_inverse_run")  # with or without a drive lag
    return _rel(_forward(lib, name, x, v, e), F_py)


@needs_gcc
@pytest.mark.parametrize("kind", ["tanh", "boucwen", "dahl", "lugre"])
def test_c_hysteresis_step_with_and_without_lag(tmp_path: Path, kind: str) -> None:
    """The C step of each one-state family equals its Python step (and so ``predict``) on a
    multi-sine record with a stepped current: without a lag, with a drive lag of 60 1/s, and
    (Bouc-Wen) with ``n = 1.5``, whose ``|z|**n`` takes ``pow``."""
    from mrdamper.models import model_class
    from tests.models.hysteresis_cases import record

    params = _hysteresis_truths()[kind]
    rec = record(5, duration=1.0)
    variants = [(params, 0.0), (params, 60.0)]
    if kind == "boucwen":
        variants.append(({**params, "n": 1.5}, 60.0))
    for j, (p, eta) in enumerate(variants):
        model = model_class(kind)(**p, eta=eta, input="i", input_range=(0.0, 1.0))
        assert _c_vs_step(model, tmp_path, f"h{j}_{kind}", rec.x, rec.v, rec.i, rec.dt) < 1e-9


@needs_gcc
def test_c_hysteresis_on_a_quiroz_record(tmp_path: Path, quiroz_records: list[Any]) -> None:
    """The four families with the known-answer parameters, driven by a measured record."""
    from mrdamper.models import model_class

    rec = next(e for e in quiroz_records if e.name == "sine_25mm_0.5Hz_0.5A")
    for kind, params in _hysteresis_truths().items():
        model = model_class(kind)(**params, eta=40.0, input="i", input_range=(0.0, 2.25))
        assert _c_vs_step(model, tmp_path, f"q_{kind}", rec.x, rec.v, rec.i, rec.dt) < 1e-9


@needs_gcc
@pytest.mark.parametrize("kind", ["tanh", "boucwen", "dahl", "lugre"])
def test_c_hysteresis_inverse_matches_inverse_current(tmp_path: Path, kind: str) -> None:
    """The C inverse (closed form per sample through the step) against ``inverse_current`` on a
    record the model simulated, exact (``reg=0``) and regularised with a rate bound: the input
    and the achieved force to 1e-9 (the model's sub-steps fixed, so that ``predict``, which gives
    ``F_achieved``, takes the step's). With a drive lag of 80 1/s the C inverse returns the lagged
    input, ``rho`` of ``inverse_current`` (to 1e-9), and its force is the desired one (exact)."""
    from mrdamper.models import model_class
    from tests.models.hysteresis_cases import record

    rec = record(5, duration=1.0)
    for eta in (0.0, 80.0):
        model = model_class(kind)(
            **_hysteresis_truths()[kind], eta=eta, input="i", input_range=(0.0, 1.0)
        )
        model = dataclasses.replace(model, substeps=model.substeps_for(rec))
        F = model.predict(rec)
        for j, (reg, rate) in enumerate(((0.0, None), (300.0, 20.0))):
            name = f"hi{j}_{kind}_{int(eta)}"
            lib = _build(model, tmp_path, name, dt=rec.dt, reg=reg, rate=rate)
            i_c, F_c = _inverse(lib, name, rec.x, rec.v, F)
            res = inverse_current(model, rec, F, reg=reg, rate=rate)
            assert _rel(i_c, res.rho) < 1e-9
            if eta == 0.0:
                assert _rel(F_c, res.F_achieved) < 1e-9
            if j == 0:
                assert _rel(F_c, F) < 1e-9  # the exact inverse reaches every force of the record
            if j == 0 and eta == 0.0:
                assert _rel(i_c, rec.i) < 1e-9  # and gives the record's current back
