"""The exported C inverse inside the quarter-car loop: with every default of the C export, the loop
driven by the compiled library's ``<name>_inverse_step`` gives the Python inverse's metrics and
input to 1e-9; another C default moves them; libraries that are not the model's export are refused
in one line (skipped without gcc)."""

from __future__ import annotations

import dataclasses
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper.control.export.c_export import export_c
from mrdamper.control.export.c_inverse import CInverse
from mrdamper.control.inverse.current import default_reg
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.fidelity import loop_metrics
from mrdamper.control.loop.quarter_car import QuarterCarResult, iso_road
from mrdamper.errors import DataValidationError
from tests.control.conftest import toy_lti
from tests.control.test_c_export import GCC, needs_gcc

METRICS = ("rms_acc", "a_w", "rms_tyre_load", "rms_travel", "rms_tracking", "mean_current")


def _library(model: Any, folder: Path, name: str, **kw: Any) -> Path:
    """``lib<name>.so`` compiled from the C export of ``model`` (``kw``: export options)."""
    _, c = export_c(model, folder, name=name, **kw)
    lib = folder / f"lib{name}.so"
    cmd = [str(GCC), "-std=c99", "-Wall", "-Werror", "-O2", "-shared", "-fPIC", str(c)]
    subprocess.run([*cmd, "-o", str(lib), "-lm"], check=True, capture_output=True, text=True)
    return lib


def _model(kind: str, kind_models: dict[str, Any]) -> Any:
    """``sp1``, ``lpv`` (hysteretic input) and ``lpv_lag``: the LPV model with a drive lag of
    250 1/s (its inverse leads over a horizon)."""
    if kind == "lpv_lag":
        return dataclasses.replace(kind_models["lpv"], eta=250.0)
    return kind_models[kind]


def _rel_changes(a: QuarterCarResult, b: QuarterCarResult) -> dict[str, float]:
    ma, mb = loop_metrics(a), loop_metrics(b)
    out = {k: abs(mb[k] - ma[k]) / abs(ma[k]) for k in METRICS}
    out["i"] = float(np.max(np.abs(b.i - a.i)) / np.max(np.abs(a.i)))
    return out


@needs_gcc
@pytest.mark.parametrize("kind", ["sp1", "lpv", "lpv_lag"])
def test_exported_c_inverse_in_the_loop_gives_the_python_metrics(
    tmp_path: Path, kind: str, kind_models: dict[str, Any]
) -> None:
    """Every default of the export (no option but the name) is the quarter car's: the loop run
    with the compiled inverse gives every metric, the input and the saturation flags of the loop
    run with the Python inverse (skyhook and hybrid, ISO class C, 2 s); the same library with
    another plant (the rig's reference damper, the generic-plant loop) too."""
    model = _model(kind, kind_models)
    lib = CInverse(_library(model, tmp_path, f"c_{kind}"))
    assert lib.kind == model.kind and lib.name == f"c_{kind}"
    road = iso_road("C", duration=2.0)
    runs = [("skyhook", None), ("hybrid", None)] + ([("skyhook", "rig")] if kind == "sp1" else [])
    for ctrl, plant in runs:
        py = simulate_closed_loop(model, road, ctrl, plant=plant)
        c = simulate_closed_loop(model, road, ctrl, plant=plant, c_inverse=lib)
        assert py.i.max() > py.i.min()  # the inverse moves the input
        changes = _rel_changes(py, c)
        assert max(changes.values()) < 1e-9, (ctrl, plant, changes)
        np.testing.assert_array_equal(c.saturated, py.saturated)


@needs_gcc
@pytest.mark.parametrize("kind", ["sp1", "lpv"])
def test_another_c_default_moves_the_metrics(
    tmp_path: Path, kind: str, kind_models: dict[str, Any]
) -> None:
    """The loop reads the library: an export whose inverse weight is 1 % off the default, or
    with an input rate bound, gives other metrics, far beyond the 1e-9 of the test above."""
    model = _model(kind, kind_models)
    dt = 1.0 / model.fs if kind == "lpv" else 1e-3  # the quarter car's control sample
    road = iso_road("C", duration=2.0)
    py = simulate_closed_loop(model, road, "skyhook")
    other: list[dict[str, Any]] = [{"reg": 1.01 * default_reg(model, 0.3, dt)}, {"rate": 5.0}]
    if kind == "sp1":
        other[1]["dt"] = dt  # the interval of a static map's rate bound
    for j, kw in enumerate(other):
        lib = _library(model, tmp_path, f"o{j}_{kind}", **kw)
        changes = _rel_changes(py, simulate_closed_loop(model, road, "skyhook", c_inverse=lib))
        assert max(changes[k] for k in METRICS) > 1e-6, (kw, changes)


@needs_gcc
def test_libraries_that_are_not_the_models_export_are_refused(
    tmp_path: Path, kind_models: dict[str, Any]
) -> None:
    sp1, lpv = kind_models["sp1"], kind_models["lpv"]
    road = iso_road("C", duration=2.0)
    with pytest.raises(DataValidationError, match="no such library"):
        simulate_closed_loop(sp1, road, "skyhook", c_inverse=tmp_path / "libnone.so")
    (tmp_path / "junk.so").write_text("not a library", encoding="utf-8")
    with pytest.raises(DataValidationError, match="not a loadable shared library"):
        CInverse(tmp_path / "junk.so")
    other = tmp_path / "other.c"
    other.write_text("double other(double x) { return x; }\n", encoding="utf-8")
    so = tmp_path / "libother.so"
    subprocess.run([str(GCC), "-shared", "-fPIC", str(other), "-o", str(so)], check=True)
    with pytest.raises(DataValidationError, match="not the inverse of an mrdamper C export"):
        CInverse(so)
    lib = _library(sp1, tmp_path, "s1")
    with pytest.raises(DataValidationError, match="not the inverse .* named 'wrong'"):
        CInverse(lib, name="wrong")
    with pytest.raises(DataValidationError, match="inverts a sp1 model, the model is lpv"):
        simulate_closed_loop(lpv, road, "skyhook", c_inverse=lib)
    lti = toy_lti()
    with pytest.raises(DataValidationError, match="no lti_inverse_step"):
        CInverse(_library(lti, tmp_path, "lti"))  # an export without an inverse
    from mrdamper.models import model_class
    from tests.models.test_tanh import TRUE

    tanh = model_class("tanh")(**TRUE, input="i", input_range=(0.0, 1.0))
    with pytest.raises(DataValidationError, match="inverts a tanh model through its step"):
        simulate_closed_loop(
            tanh, road, "skyhook", c_inverse=_library(tanh, tmp_path, "th", dt=1e-3)
        )


@needs_gcc
def test_the_export_of_another_model_of_the_same_kind_is_refused(
    tmp_path: Path, kind_models: dict[str, Any]
) -> None:
    sp1 = kind_models["sp1"]
    lib = CInverse(_library(sp1, tmp_path, "s1"))
    lib.check(sp1)
    other = dataclasses.replace(sp1, S=tuple(1.01 * np.asarray(sp1.S)))
    with pytest.raises(DataValidationError, match="the export of another sp1 model"):
        simulate_closed_loop(other, iso_road("C", duration=2.0), "skyhook", c_inverse=lib)


@needs_gcc
@pytest.mark.slow  # two loops compiled with the FMU's functions (about 20 s)
def test_exported_controller_on_the_exported_plant(
    tmp_path: Path, kind_models: dict[str, Any]
) -> None:
    """The C inverse drives the model's FMU as the plant (a family added at run time: the loop
    compiled with the FMU's step functions) and gives the Python inverse's metrics there too."""
    from mrdamper.control.export.fmu import export_fmu

    sp1 = kind_models["sp1"]
    fmu = export_fmu(sp1, tmp_path / "sp1.fmu")
    lib = _library(sp1, tmp_path, "f_sp1")
    road = iso_road("C", duration=2.0)
    py = simulate_closed_loop(sp1, road, "skyhook", plant=fmu)
    c = simulate_closed_loop(sp1, road, "skyhook", plant=fmu, c_inverse=lib)
    assert max(_rel_changes(py, c).values()) < 1e-9
