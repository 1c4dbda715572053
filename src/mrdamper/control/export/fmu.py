"""FMI 2.0 co-simulation FMU of an identified damper model or of its inverse.

:func:`export_fmu` writes one ``.fmu`` file (a zip archive) holding

* ``modelDescription.xml``: FMI 2.0, co-simulation only, a fixed communication step (the model's
  sample time; ``canHandleVariableCommunicationStepSize="false"``), the model kind, the mrdamper
  version and the identified input range in the description and under ``VendorAnnotations``;
* ``sources/``: the model's C step (:mod:`mrdamper.control.export.c_export`, the same code as
  ``--format c``), the FMI 2.0 wrapper (:mod:`mrdamper.control.export._fmi2_c`) and a header
  declaring
  the FMI 2.0 types it uses;
* ``binaries/linux64/<name>.so``: those sources compiled with ``gcc -shared -fPIC -std=c99 -O2``
  when the FMU is written.

Variables (value references in brackets): the forward FMU has the inputs ``x`` [0] displacement
[m], ``v`` [1] velocity [m/s], the electrical input [2] named after the model's channel (``i``
[A] or ``voltage`` [V]) and the output ``F`` [3] force [N]. The inverse FMU (``inverse=True``, for
kinds whose C export has an inverse) has the inputs ``x``, ``v`` and ``F_desired`` [2] [N] and the
outputs: the electrical input [3] (for a model with a drive lag, the lagged input ``rho``, as
``<name>_inverse_step``) and ``F_achieved`` [4], the model's force with it [N].

FMI 2.0 rather than 3.0: the FMU importers of Simulink, OpenModelica, Dymola and Simcenter
Amesim read FMI 2.0 co-simulation FMUs, while FMI 3.0 import is newer and not in every release
of these tools.

Call order per communication point ``t_k``: set the inputs at ``t_k``, read the outputs at
``t_k`` (the force has direct feedthrough: it depends on the inputs just set), then
``fmi2DoStep(t_k, dt)``. Reading the outputs does not change the model's state; ``fmi2DoStep``
takes the sample at the inputs set at ``t_k``. Driven this way the FMU of every kind gives the C
step's values, which equal the model's per-sample step (:func:`mrdamper.models.step.run_step`)
and ``predict`` on a record at the FMU's rate. Read before the inputs of ``t_(k+1)`` are set
(right after ``fmi2DoStep``, as fmpy's ``simulate_fmu`` does), the outputs are those of sample
``k``: one communication step late, the same for every kind.
"""

from __future__ import annotations

import hashlib
import math
import shutil
import struct
import subprocess
import sys
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Any

from mrdamper._io import FileKind, atomic_write_with, check_writable
from mrdamper.control.export._fmi2_c import FMI2_TYPES, WRAPPER
from mrdamper.control.export.c_export import C_KINDS, assemble, render
from mrdamper.control.export.c_render import renderer_of
from mrdamper.control.export.c_render._common import rates_hint
from mrdamper.errors import DataValidationError, MrDamperError
from mrdamper.models.base import FittedModel
from mrdamper.version import __version__

__all__ = [
    "FMU_FILE",
    "FMU_KINDS",
    "GCC_FLAGS",
    "export_fmu",
    "fmu_sources",
    "run_fmu",
    "training_dt",
]


def _is_mrdamper_fmu(path: Path) -> bool:
    """True for an FMU (zip) whose model description names mrdamper as its generation tool."""
    try:
        with zipfile.ZipFile(path) as z:
            head = z.read("modelDescription.xml")[:4096].decode("utf-8", errors="replace")
    except (OSError, KeyError, zipfile.BadZipFile):
        return False
    return 'generationTool="mrdamper ' in head


#: The kind of file the FMU export writes (``--force`` replaces only such files).
FMU_FILE = FileKind("FMU exported by mrdamper", _is_mrdamper_fmu)

#: Model kinds with an FMU (every kind with a C step).
FMU_KINDS = C_KINDS
#: Flags of the binary's compilation (besides the files, ``-o`` and ``-lm``).
GCC_FLAGS = ("-shared", "-fPIC", "-std=c99", "-O2")


def training_dt(model: FittedModel) -> float | None:
    """The sampling interval [s] the model was fitted at, or None.

    The model's ``sample_time`` (recorded by the fit); for a model file written before it was
    recorded, the training records' interval when they had one (``provenance["record_dt"]``);
    None otherwise (a model built by hand).
    """
    recorded = getattr(model, "sample_time", None)
    if recorded is not None:
        return float(recorded)
    values = model.provenance.get("record_dt") if hasattr(model, "provenance") else None
    if isinstance(values, (list, tuple)) and len(values) == 1:
        return float(values[0])
    return None


def _check_dt(dt: float | None) -> None:
    if dt is not None and not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise DataValidationError("dt", f"expected a positive sample time [s], got {dt!r}")


def _variables(model: FittedModel, inverse: bool) -> list[dict[str, str]]:
    unit = "A" if model.input == "i" else "V"
    electrical = {"name": model.input, "unit": unit, "description": "electrical input"}
    motion = [
        {"name": "x", "unit": "m", "description": "damper displacement"},
        {"name": "v", "unit": "m/s", "description": "damper velocity"},
    ]
    if inverse:
        return [
            *motion,
            {"name": "F_desired", "unit": "N", "description": "desired damper force"},
            {**electrical, "causality": "output", "description": "electrical input giving it"},
            {"name": "F_achieved", "unit": "N", "description": "model force with that input"},
        ]
    return [*motion, electrical, {"name": "F", "unit": "N", "description": "damper force"}]


def _model_description(
    model: FittedModel,
    name: str,
    guid: str,
    dt: float,
    inverse: bool,
    sources: list[str],
    own_rate: bool = False,
    feedthrough: bool = True,
) -> str:
    unit = "A" if model.input == "i" else "V"
    lo, hi = (float(b) for b in model.input_range)
    what = "inverse of the " if inverse else ""
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": name,
            "guid": guid,
            "description": (
                f"{what}{model.kind} MR damper model exported by mrdamper {__version__}; "
                f"identified on {model.input} in [{lo!r}, {hi!r}] {unit}; fixed step {dt!r} s"
            ),
            "generationTool": f"mrdamper {__version__}",
            "variableNamingConvention": "flat",
            "numberOfEventIndicators": "0",
        },
    )
    cs = ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": name,
            "canHandleVariableCommunicationStepSize": "false",
            "canInterpolateInputs": "false",
            "canBeInstantiatedOnlyOncePerProcess": "false",
            "canNotUseMemoryManagementFunctions": "true",
            "canGetAndSetFMUstate": "false",
            "canSerializeFMUstate": "false",
            "providesDirectionalDerivative": "false",
        },
    )
    files = ET.SubElement(cs, "SourceFiles")
    for f in sources:
        ET.SubElement(files, "File", {"name": f})
    units = ET.SubElement(root, "UnitDefinitions")
    for u, base in (
        ("m", {"m": "1"}),
        ("m/s", {"m": "1", "s": "-1"}),
        ("N", {"kg": "1", "m": "1", "s": "-2"}),
        ("A", {"A": "1"}),
        ("V", {"kg": "1", "m": "2", "s": "-3", "A": "-1"}),
    ):
        ET.SubElement(ET.SubElement(units, "Unit", {"name": u}), "BaseUnit", base)
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(cats, "Category", {"name": "logStatusError"})
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0.0", "stepSize": repr(dt)})
    tool = ET.SubElement(ET.SubElement(root, "VendorAnnotations"), "Tool", {"name": "mrdamper"})
    ET.SubElement(
        tool,
        "Model",
        {
            "kind": model.kind,
            "version": __version__,
            "inverse": "true" if inverse else "false",
            "input": model.input,
            "inputUnit": unit,
            "inputMin": repr(lo),
            "inputMax": repr(hi),
            "sampleTime": repr(dt),
            "ownSampleTime": "true" if own_rate else "false",
            "feedthrough": "true" if feedthrough else "false",
        },
    )
    mv = ET.SubElement(root, "ModelVariables")
    outputs = []
    for k, var in enumerate(_variables(model, inverse)):
        causality = var.get("causality", "input" if k < 3 else "output")
        attrs = {
            "name": var["name"],
            "valueReference": str(k),
            "description": var["description"],
            "causality": causality,
            "variability": "continuous",
        }
        if causality == "output":
            attrs["initial"] = "calculated"
            outputs.append(str(k + 1))
        sv = ET.SubElement(mv, "ScalarVariable", attrs)
        real = {"unit": var["unit"]}
        if causality == "input":
            real["start"] = "0.0"
        ET.SubElement(sv, "Real", real)
    ms = ET.SubElement(root, "ModelStructure")
    for tag in ("Outputs", "InitialUnknowns"):
        el = ET.SubElement(ms, tag)
        for index in outputs:
            ET.SubElement(el, "Unknown", {"index": index})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def fmu_sources(
    model: FittedModel,
    name: str = "mrd_damper",
    *,
    inverse: bool = False,
    dt: float | None = None,
    reg: float | None = None,
) -> tuple[dict[str, str], float]:
    """The FMU's text files (archive path -> text) and its communication step [s].

    Parameters
    ----------
    model : FittedModel
        A kind in :data:`FMU_KINDS`.
    name : str
        C identifier: the FMU's ``modelIdentifier``, file stem and symbol prefix.
    inverse : bool
        The FMU of the inverse (kinds whose C export has one).
    dt : float, optional
        Communication step [s] of a kind without its own sample time (Spencer, P-15, the static
        maps, tanh, Bouc-Wen, Dahl, LuGre;
        default :func:`training_dt`); an LPV / LTI model runs at its rate ``1 / fs`` and a
        different ``dt`` is refused.
    reg : float, optional
        Regularisation weight of the inverse [N per input unit] (default from the model).

    Raises
    ------
    DataValidationError
        A kind without a C step, an unknown sample time, an inverse the kind has not, bad options.
    """
    kind = getattr(model, "kind", type(model).__name__)
    if renderer_of(model) is None:
        raise DataValidationError(
            "model",
            f"kind {kind!r} has no C step to export; FMU export handles {list(FMU_KINDS)} and "
            "plug-in models with a render_c method",
        )
    _check_dt(dt)
    own = 1.0 / model.fs if hasattr(model, "fs") else None
    if own is not None and dt is not None and not math.isclose(dt, own, rel_tol=1e-9):
        raise DataValidationError(
            "dt", f"the {kind} model runs at its own sample time {own!r} s, got {dt!r} s"
        )
    step = own if own is not None else (dt if dt is not None else training_dt(model))
    if step is None:
        raise DataValidationError(
            "dt",
            f"the {kind} model records no sample time it was fitted at{rates_hint(model)}; give "
            "the FMU's communication step dt [s] (--dt)",
        )
    r = render(model, name, reg=reg, dt=step)
    if inverse and not r.has_inverse:
        raise DataValidationError(
            "inverse", f"the C export of a {kind} model has no inverse; export the forward model"
        )
    header, src = assemble(model, name, r)
    if inverse:
        compute = (
            f"c->out[0] = {name}_inverse_step(&c->next, c->in[0], c->in[1], c->in[2], &c->out[1]);"
        )
    else:
        compute = f"c->out[0] = {name}_step(&c->next, c->in[0], c->in[1], c->in[2]);"
    sources = [f"{name}.c", f"{name}_fmu.c"]
    digest = hashlib.sha256((header + src + compute + repr(step)).encode()).digest()
    guid = "{" + str(uuid.UUID(bytes=digest[:16])) + "}"
    fmt = {
        "p": name,
        "P": name.upper(),
        "n_out": 2 if inverse else 1,
        "guid": guid,
        "dt": float(step).hex(),
        "dt_text": repr(step),
        "compute": compute,
    }
    files = {
        "modelDescription.xml": _model_description(
            model, name, guid, step, inverse, sources, r.step_dt, model.step(dt=step).feedthrough
        ),
        f"sources/{name}.h": header,
        f"sources/{name}.c": src,
        f"sources/{name}_fmi2.h": FMI2_TYPES.format(**fmt),
        f"sources/{name}_fmu.c": WRAPPER.format(**fmt),
    }
    return files, step


def _compile(files: dict[str, str], name: str, gcc: str) -> bytes:
    """Compile the sources into the shared library's bytes."""
    with tempfile.TemporaryDirectory(prefix="mrdamper-fmu-") as tmp:
        d = Path(tmp)
        for path, text in files.items():
            if path.startswith("sources/"):
                (d / Path(path).name).write_text(text, encoding="utf-8")
        lib = d / f"{name}.so"
        cmd = [gcc, *GCC_FLAGS, "-o", str(lib), str(d / f"{name}.c"), str(d / f"{name}_fmu.c")]
        done = subprocess.run([*cmd, "-lm"], capture_output=True, text=True, check=False)
        if done.returncode != 0:
            first = next((ln for ln in done.stderr.splitlines() if "error" in ln), done.stderr)
            raise MrDamperError(f"gcc: compiling the FMU's binary failed: {first.strip()}")
        return lib.read_bytes()


def export_fmu(
    model: FittedModel,
    out: str | Path,
    *,
    name: str = "mrd_damper",
    inverse: bool = False,
    dt: float | None = None,
    reg: float | None = None,
    force: bool = False,
) -> Path:
    """Write the FMI 2.0 co-simulation FMU of ``model`` (or of its inverse) to ``out``.

    The file is written atomically (a temporary file beside ``out``, renamed when complete);
    nothing is written when a check or the compilation fails. See :func:`fmu_sources` for the
    parameters.

    Returns
    -------
    Path
        The FMU.

    Raises
    ------
    OutputExistsError
        ``out`` exists and ``force`` is False.
    DataValidationError
        See :func:`fmu_sources`.
    MrDamperError
        gcc is not found or fails, or the platform is not 64-bit Linux.
    """
    from mrdamper.control.export.matrices import warn_if_unstable

    path = check_writable(out, force, kind=FMU_FILE)
    files, _ = fmu_sources(model, name, inverse=inverse, dt=dt, reg=reg)
    warn_if_unstable(model)  # as the .mat, JSON and C exports say it
    if not sys.platform.startswith("linux") or struct.calcsize("P") != 8:
        raise MrDamperError(
            f"FMU export builds a linux64 binary; this platform is {sys.platform} "
            f"({8 * struct.calcsize('P')}-bit)"
        )
    gcc = shutil.which("gcc")
    if gcc is None:
        raise MrDamperError("gcc: not found; the FMU's binary is compiled with gcc (install gcc)")
    binary = _compile(files, name, gcc)

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            for arc, text in files.items():
                z.writestr(arc, text)
            z.writestr(f"binaries/linux64/{name}.so", binary)

    return atomic_write_with(path, write, force=force)


def run_fmu(path: str | Path, u0: Any, u1: Any, u2: Any) -> Any:
    """Drive an FMU written by :func:`export_fmu` over sampled inputs with fmpy.

    At every communication point the inputs are set, the outputs read, then the FMU steps by its
    fixed communication step (the call order the FMU's outputs are defined for).

    Parameters
    ----------
    path : str or Path
        The ``.fmu`` file.
    u0, u1, u2 : array_like
        The three inputs, in value-reference order (``x`` [m], ``v`` [m/s], then the electrical
        input or, for an inverse FMU, the desired force [N]), one value a communication step.

    Returns
    -------
    ndarray
        The outputs, one row a communication point (forward FMU: ``F``; inverse FMU: the
        electrical input and ``F_achieved``).

    Raises
    ------
    DataValidationError
        fmpy is not installed (``pip install "mrdamper[fmu]"``), the inputs differ in length, or
        the FMU reports an error (e.g. a diverged state).
    """
    import numpy as np

    try:
        from fmpy import extract, read_model_description
        from fmpy.fmi1 import FMICallException
        from fmpy.fmi2 import FMU2Slave
    except ImportError as exc:
        raise DataValidationError(
            "fmpy", 'not installed; install the optional extra: pip install "mrdamper[fmu]"'
        ) from exc
    inputs = [np.asarray(u, dtype=np.float64) for u in (u0, u1, u2)]
    if len({u.shape for u in inputs}) != 1 or inputs[0].ndim != 1:
        raise DataValidationError("inputs", "expected three 1-D arrays of one length")
    md = read_model_description(str(path))
    outs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    dt = float(md.defaultExperiment.stepSize)
    unzipped = extract(str(path))
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="mrdamper",
    )
    result = np.zeros((inputs[0].size, len(outs)))
    try:
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        for k in range(inputs[0].size):
            fmu.setReal([0, 1, 2], [float(u[k]) for u in inputs])
            result[k] = fmu.getReal(outs)
            fmu.doStep(currentCommunicationPoint=k * dt, communicationStepSize=dt)
        fmu.terminate()
    except FMICallException as exc:
        raise DataValidationError("fmu", f"{Path(path).name}: {exc}") from exc
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return result
