"""An exported FMU as the damper of the quarter car: its binary's step, called from compiled code.

An FMU written by :func:`mrdamper.control.export.fmu.export_fmu` holds, besides the FMI 2.0
interface,
the model's per-sample step as C functions (``<id>_step_init``, ``<id>_step_force`` and
``<id>_step_advance`` over a ``double[<id>_step_size()]`` state, the layout of the Python step,
:mod:`mrdamper.models.step`). :class:`FMUPlant` loads the FMU's linux64 binary with ``ctypes``
and offers it as a :class:`~mrdamper.models.step.Step` whose ``force`` and ``advance`` are
numba-compiled functions calling those C functions (held in the step's form), so the quarter car's
compiled loop (:func:`mrdamper.control.loop.closed_loop.simulate_closed_loop`, ``--plant
damper.fmu``) runs the FMU's binary at every plant step and Runge-Kutta stage exactly as it runs
the model's own step: the same calls, in the same order, with the same arguments.

The FMI functions (``fmi2SetReal`` / ``fmi2GetReal`` / ``fmi2DoStep``) are not used on this path:
they take one sample per fixed communication step, while the car's Runge-Kutta stages ask the
damper's force at the motion of each stage with its state held. The FMI path of the same binary
is checked against the Python step by :func:`mrdamper.control.export.fmu.run_fmu`.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import struct
import sys
import tempfile
import weakref
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from mrdamper.errors import DataValidationError
from mrdamper.models.step import Step

__all__ = ["DISCRETE_KINDS", "FMUForm", "FMUPlant", "is_fmu", "step_advance", "step_force"]

#: Kinds whose step runs at its own sample time (``Step.dt`` set), for FMUs that do not say.
DISCRETE_KINDS = ("lpv", "lti", "narx")


def is_fmu(spec: Any) -> bool:
    """Whether ``spec`` names a ``.fmu`` file."""
    return isinstance(spec, (str, Path)) and str(spec).lower().endswith(".fmu")


def _read(path: Path) -> tuple[str, dict[str, str], bytes]:
    """modelIdentifier, mrdamper's model annotation and the linux64 binary of the FMU."""
    try:
        with zipfile.ZipFile(path) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
            cs = root.find("CoSimulation")
            if cs is None:
                raise DataValidationError("--plant", f"{path.name}: not a co-simulation FMU")
            ident = _identifier(cs.attrib["modelIdentifier"], path)
            ann = root.find("VendorAnnotations/Tool[@name='mrdamper']/Model")
            if ann is None:
                raise DataValidationError(
                    "--plant", f"{path.name}: not an FMU written by mrdamper (no model annotation)"
                )
            binary = z.read(f"binaries/linux64/{ident}.so")
    except (zipfile.BadZipFile, KeyError, ET.ParseError) as exc:
        raise DataValidationError("--plant", f"{path.name}: not a readable FMU ({exc})") from None
    return ident, dict(ann.attrib), binary


#: Reserved words of C99 (not identifiers).
# fmt: off
_C_KEYWORDS = frozenset((
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else",
    "enum", "extern", "float", "for", "goto", "if", "inline", "int", "long", "register",
    "restrict", "return", "short", "signed", "sizeof", "static", "struct", "switch", "typedef",
    "union", "unsigned", "void", "volatile", "while", "_Bool", "_Complex", "_Imaginary",
))
# fmt: on


def _identifier(ident: str, path: Path) -> str:
    """``modelIdentifier`` checked against FMI 2.0's rule (a C identifier: it names the binary
    ``binaries/linux64/<id>.so`` and prefixes its functions), so it can never name a path."""
    if not (
        ident.isascii() and ident.isidentifier() and ident not in _C_KEYWORDS and len(ident) <= 200
    ):
        raise DataValidationError(
            "--plant",
            f"{path.name}: modelIdentifier {ident[:80]!r} is not a C identifier (FMI 2.0: letters, "
            "digits and '_', not starting with a digit); the FMU is refused",
        )
    return ident


def _private_binary(folder: Path, ident: str, binary: bytes) -> Path:
    """Write ``binary`` as ``folder/<ident>.so``, a new file that must resolve inside ``folder``
    (created exclusively: nothing existing is ever written through)."""
    so = (folder / f"{ident}.so").resolve()
    if so.parent != folder.resolve():  # pragma: no cover - excluded by _identifier
        raise DataValidationError("--plant", f"modelIdentifier {ident!r} leaves the FMU's folder")
    fd = os.open(so, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(binary)
    return so


def _functions(lib: ctypes.CDLL, ident: str, path: Path) -> tuple[Any, Any, Any, int]:
    try:
        init = getattr(lib, f"{ident}_step_init")
        force = getattr(lib, f"{ident}_step_force")
        advance = getattr(lib, f"{ident}_step_advance")
        size = getattr(lib, f"{ident}_step_size")
    except AttributeError:
        raise DataValidationError(
            "--plant", f"{path.name}: its binary has no step functions; export it again"
        ) from None
    d, vp = ctypes.c_double, ctypes.c_void_p
    init.restype, init.argtypes = None, [vp, d, d, d]
    force.restype, force.argtypes = d, [vp, d, d, d]
    advance.restype, advance.argtypes = ctypes.c_int, [vp, d, d, d, d, d, d, d]
    size.restype, size.argtypes = ctypes.c_long, []
    return init, force, advance, int(size())


class FMUForm(NamedTuple):
    """The FMU's step as the compiled loop reads it: its C functions (``ctypes`` function objects,
    typed by signature, so the loop is compiled once per process for every FMU)."""

    force: Any
    advance: Any


@njit(cache=False)
def step_force(form: Any, s: Any, x: float, v: float, e: float) -> float:  # pragma: no cover
    """``<id>_step_force(s, x, v, e)``: force [N] at the state ``s``."""
    f: float = form.force(s.ctypes, x, v, e)
    return f


@njit(cache=False)
def step_advance(  # pragma: no cover - numba
    form: Any, s: Any, x0: float, v0: float, e0: float, x1: float, v1: float, e1: float, dt: float
) -> int:
    """``<id>_step_advance(s, ...)``: advance ``s`` in place over ``dt`` [s]; its status."""
    status: int = form.advance(s.ctypes, x0, v0, e0, x1, v1, e1, dt)
    return status


class FMUPlant:
    """A damper FMU written by mrdamper, usable wherever a model's step is (the quarter car).

    Parameters
    ----------
    path : str or Path
        The ``.fmu`` file (a forward FMU; an inverse FMU is refused).

    Attributes
    ----------
    kind : str
        The exported model's kind.
    input : str
        Its electrical input channel (``"i"`` or ``"voltage"``).
    input_range : (float, float)
        Its identified input range [A] or [V].
    sample_time : float
        The FMU's communication step [s].
    path : Path
        The file.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise DataValidationError("--plant", f"{self.path}: no such FMU")
        if not sys.platform.startswith("linux") or struct.calcsize("P") != 8:
            raise DataValidationError("--plant", "an FMU plant needs its linux64 binary")
        ident, ann, binary = _read(self.path)
        if ann.get("inverse") == "true":
            raise DataValidationError(
                "--plant", f"{self.path.name} is the FMU of an inverse, not of a damper"
            )
        self.kind = ann["kind"]
        self.input = ann["input"]
        self.input_range = (float(ann["inputMin"]), float(ann["inputMax"]))
        self.sample_time = float(ann["sampleTime"])
        own = ann.get("ownSampleTime")
        self._discrete = own == "true" if own is not None else self.kind in DISCRETE_KINDS
        feed = ann.get("feedthrough")  # FMUs written before it was recorded: by kind
        self._feedthrough = (
            feed == "true" if feed is not None else self.kind not in ("spencer", "p15", "lti")
        )
        tmp = Path(tempfile.mkdtemp(prefix="mrdamper-fmu-plant-"))
        self._finalizer = weakref.finalize(self, shutil.rmtree, tmp, True)
        so = _private_binary(tmp, ident, binary)
        try:
            self._lib = ctypes.CDLL(str(so))
        except OSError as exc:
            raise DataValidationError(
                "--plant", f"{self.path.name}: its linux64 binary cannot be loaded ({exc})"
            ) from None
        self._init, cforce, cadvance, self._n = _functions(self._lib, ident, self.path)
        self._form = FMUForm(cforce, cadvance)

    def initial_state(self, x0: float, v0: float, e0: float) -> np.ndarray:
        """The C step's rest state at the first sample (a new float64 array)."""
        s = np.zeros(self._n)
        self._init(s.ctypes.data, float(x0), float(v0), float(e0))
        return s

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The FMU's per-sample step (``dt``, ``vmax`` unused: the step was fixed at export)."""
        return Step(
            self.kind,
            self._form,
            step_force,
            step_advance,
            self.initial_state,
            dt=self.sample_time if self._discrete else None,
            feedthrough=self._feedthrough,
        )

    def __repr__(self) -> str:
        return f"FMUPlant({str(self.path)!r}, kind={self.kind!r})"
