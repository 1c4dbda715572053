"""An exported C inverse as the quarter car's inverse: its library's per-sample step, called from
compiled code.

A library compiled from the C export (:func:`mrdamper.control.export.c_export.export_c`, for example
``gcc -shared -fPIC -O2 mrd_damper.c -o libmrd_damper.so -lm``) defines
``<name>_inverse_step(s, x, v, F_desired, F_out)``, the model's regularised inverse one sample at
a time with its memory (previous input, drive-lag command, LPV past outputs and inputs, Dahl
state) in a caller-owned ``<name>_state`` of ``<name>_state_size()`` bytes, and
``<name>_kind()``. :class:`CInverse` loads it with ``ctypes`` and the quarter car
(:func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car` and
:func:`~mrdamper.control.loop.closed_loop.simulate_closed_loop`, ``c_inverse=``) calls it at every
control sample in place of its own inverse, through a numba-compiled function holding the C
function in the controller's form, as :mod:`mrdamper.control.export.fmu_plant` calls an FMU's step.
Everything else stays the loop's: the controller's desired force, the input limits and rate
bound the loop applies to passive controllers, the model's force for the chosen input (the LPV
model's recursion, the static map) and the plant. The C inverse uses the settings fixed at its
export (regularisation weight, grid, rate bound): exported with every default, they are the quarter
car's, and the loop gives the Python inverse's numbers to rounding.

Only the inverses the quarter car itself runs per sample can be substituted: a static map
(``sp1``..``sp4``, ``bingham``) or an LPV model. The one-state hysteresis families export a
closed-form inverse, while the quarter car inverts them over a lead through their step
(:mod:`mrdamper.control.loop.closed_loop`): not the same controller, so they are refused.

:meth:`CInverse.check` refuses, in one line, a library of another kind and one exported from
another model of the kind (its forward step, ``<name>_step_*``, against the model's on a probe
motion). ``saturated`` keeps its meaning: the desired force lies outside the model's forces on the
inverse's search grid, which the loop evaluates with the Python model (the C function returns the
input and the force only).
"""

from __future__ import annotations

import ctypes
import types
from pathlib import Path
from typing import Any, NamedTuple, cast

import numpy as np
import numpy.typing as npt
from numba import njit

from mrdamper.control.damper import DamperModel
from mrdamper.control.inverse._forms import ControllerForm, InverseForm
from mrdamper.control.loop import _closed_loop_kernels as CK
from mrdamper.control.loop import _quarter_car_kernels as QK
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.kernels import poly as _poly
from mrdamper.models.kernels import sp_force1
from mrdamper.models.step_dispatch import family_advance, family_force

__all__ = [
    "CControllerForm",
    "CInverse",
    "c_inverse_form",
    "c_kernels",
    "grid_reach",
    "load_c_inverse",
]

#: Kinds whose inverse the quarter car runs per sample (the ones a C inverse can replace).
LOOP_KINDS = ("sp1", "sp2", "sp3", "sp4", "bingham", "lpv")

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


class CControllerForm(NamedTuple):
    """:class:`~mrdamper.control.inverse._forms.ControllerForm` with the C inverse: its function
    (a ``ctypes`` function object, typed by signature), its state and the force it returns."""

    ctrl: int
    gains: FloatArray
    lo: float
    hi: float
    rate_step: float
    dt_c: float
    inverse: InverseForm
    c_step: Any
    c_state: FloatArray
    c_out: FloatArray


@njit(cache=True)
def grid_reach(  # pragma: no cover - numba
    is_lpv: bool,
    cf: FloatArray,
    x: float,
    v: float,
    comp: IntArray,
    power: IntArray,
    theta: FloatArray,
    f0: float,
    target: float,
    a: float,
    b: float,
    hold: float,
    n_grid: int,
) -> bool:
    """Whether ``target`` [N] lies between the least and largest model forces at the inputs the
    inverse's grid visits on ``[a, b]`` (the ``reachable`` flag of
    :func:`~mrdamper.control.inverse._inverse_kernels.reg_solve_poly`,
    ``reg_solve_static`` and ``horizon_step``: ``hold`` clipped, then ``n_grid`` intervals)."""
    r = min(max(hold, a), b)
    f = _poly(cf, r) if is_lpv else sp_force1(x, v, r, comp, power, theta, f0)
    fmin = f
    fmax = f
    if b <= a:
        return fmin == target
    h = (b - a) / n_grid
    for q in range(n_grid + 1):
        r = b if q == n_grid else a + q * h
        f = _poly(cf, r) if is_lpv else sp_force1(x, v, r, comp, power, theta, f0)
        fmin = min(fmin, f)
        fmax = max(fmax, f)
    return fmin <= target <= fmax


@njit(cache=False)
def c_invert(  # pragma: no cover - numba
    form: CControllerForm,
    k: int,
    x_d: float,
    v_d: float,
    target: float,
    a: float,
    b: float,
    prev: float,
    hold: float,
    cf: FloatArray,
    y: FloatArray,
    u: FloatArray,
    yb: FloatArray,
    ub: FloatArray,
    z_d: float,
) -> tuple[float, bool]:
    """``<name>_inverse_step`` at this control sample (the arguments of
    :func:`~mrdamper.control.loop._quarter_car_kernels.invert_model`); ``(r, reachable)``."""
    r = form.c_step(form.c_state.ctypes, x_d, v_d, target, form.c_out.ctypes)
    inv = form.inverse
    if inv.is_lpv:
        target = target - inv.stiffness * x_d  # the polynomial's share (the C step does the same)
    ok = grid_reach(
        inv.is_lpv,
        cf,
        x_d,
        v_d,
        inv.comp,
        inv.power,
        inv.theta,
        inv.f0,
        target,
        a,
        b,
        hold,
        inv.n_grid,
    )
    return r, ok


def _rebound(fn: Any, **names: Any) -> Any:
    """A non-cached compiled copy of the compiled function ``fn`` with globals ``names`` rebound
    (numba freezes globals at compile time)."""
    py = fn.py_func
    copy = types.FunctionType(py.__code__, {**py.__globals__, **names}, py.__name__)
    copy.__defaults__ = py.__defaults__
    copy.__doc__ = py.__doc__
    return njit(cache=False)(copy)


_KERNELS: dict[str, Any] = {}


def c_kernels() -> dict[str, Any]:
    """The quarter car's kernels with the C inverse in place of
    :func:`~mrdamper.control.loop._quarter_car_kernels.invert_model`, compiled once per process (a
    kernel holding ``ctypes`` functions is not cached on disk): ``"sample"`` the controller sample,
    ``"simulate"`` the fused kernel, ``"loop"`` the generic-plant loop of the built-in families
    (a family added at run time: :func:`~mrdamper.control.loop._closed_loop_kernels.run_loop` with
    ``control=c_kernels()["sample"]``)."""
    if not _KERNELS:
        sample = _rebound(QK.control_sample, INVERT=c_invert)
        _KERNELS["sample"] = sample
        _KERNELS["simulate"] = _rebound(QK.simulate, control_sample=sample)
        _KERNELS["loop"] = CK.compile_loop(
            family_force, family_advance, family_force, family_advance, cache=False, control=sample
        )
    return _KERNELS


class CInverse:
    """A compiled C export of a damper model, whose inverse drives the quarter car.

    Parameters
    ----------
    path : str or Path
        The shared library compiled from ``<name>.c``.
    name : str, optional
        The export's prefix (``name`` of :func:`~mrdamper.control.export.c_export.export_c`);
        default
        the file's stem without a leading ``lib`` (``libmrd_damper.so``: ``mrd_damper``).

    Attributes
    ----------
    path : Path
        The library.
    name : str
        The prefix.
    kind : str
        The exported model's kind.
    """

    def __init__(self, path: str | Path, name: str | None = None) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise DataValidationError("c_inverse", f"{self.path}: no such library")
        stem = self.path.name.split(".", 1)[0]
        self.name = name if name is not None else stem.removeprefix("lib")
        try:
            self._lib = ctypes.CDLL(str(self.path.resolve()))
        except OSError as exc:
            why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise DataValidationError(
                "c_inverse", f"{self.path.name}: not a loadable shared library ({why})"
            ) from None
        p = self.name
        d, vp = ctypes.c_double, ctypes.c_void_p
        signatures = {  # restype, argtypes
            "kind": (ctypes.c_char_p, []),
            "state_size": (ctypes.c_long, []),
            "init": (None, [vp]),
            "inverse_step": (d, [vp, d, d, d, vp]),
            "step_init": (None, [vp, d, d, d]),
            "step_force": (d, [vp, d, d, d]),
            "step_advance": (ctypes.c_int, [vp, d, d, d, d, d, d, d]),
        }
        fns: dict[str, Any] = {}
        try:
            for fn, (restype, argtypes) in signatures.items():
                fns[fn] = getattr(self._lib, f"{p}_{fn}")
                fns[fn].restype, fns[fn].argtypes = restype, argtypes
        except AttributeError:
            raise DataValidationError(
                "c_inverse",
                f"{self.path.name}: not the inverse of an mrdamper C export named {p!r} (no "
                f"{p}_{fn}; an export without an inverse, another name or an older export)",
            ) from None
        self.kind = fns["kind"]().decode("ascii")
        self._size = int(fns["state_size"]())
        self._init, self._step = fns["init"], fns["inverse_step"]
        self._forward = [fns["step_init"], fns["step_force"], fns["step_advance"]]

    def check(self, model: DamperModel) -> None:
        """Refuse (one line) a model of another kind than the export's, or one whose inverse the
        quarter car does not run per sample."""
        mk = getattr(model, "kind", type(model).__name__)
        if mk != self.kind:
            raise DataValidationError(
                "c_inverse", f"{self.path.name} inverts a {self.kind} model, the model is {mk}"
            )
        if mk not in LOOP_KINDS:
            raise DataValidationError(
                "c_inverse",
                f"the quarter car inverts a {mk} model through its step, not per sample as the "
                f"C export does: a C inverse runs in the loop for kinds {list(LOOP_KINDS)}",
            )
        rel = self._forward_gap(cast(FittedModel, model))
        if not rel <= 1e-9:
            raise DataValidationError(
                "c_inverse",
                f"{self.path.name} is the export of another {mk} model (its force differs from "
                f"the model's by {rel:.3g} of the force scale on a probe motion)",
            )

    def _forward_gap(self, model: FittedModel) -> float:
        """Largest difference between the library's per-sample step (``<name>_step_*``) and the
        model's, over 20 samples of a probe motion through the input range, relative to the largest
        force (the export's forward step equals the model's to 1e-9)."""
        from mrdamper.control.inverse.current import model_input_limits
        from mrdamper.models.step import run_step

        step = model.step()
        dt = 1e-3 if step.dt is None else float(step.dt)
        t = np.arange(20) * dt
        w = 2.0 * np.pi / (t[-1] + dt)
        x, v = 0.01 * np.sin(w * t), 0.01 * w * np.cos(w * t)
        lo, hi = model_input_limits(model)
        e = lo + (hi - lo) * t / t[-1]
        f_py, status, _ = run_step(step, x, v, e, dt)
        init, force, advance = self._forward
        state = np.zeros(step.initial_state(x[0], v[0], e[0]).size)
        init(state.ctypes.data, x[0], v[0], e[0])
        f_c = np.zeros(t.size)
        for k in range(t.size):
            f_c[k] = force(state.ctypes.data, x[k], v[k], e[k])
            if k + 1 < t.size:
                args = (x[k], v[k], e[k], x[k + 1], v[k + 1], e[k + 1], dt)
                advance(state.ctypes.data, *args)
        scale = float(np.max(np.abs(f_py))) if status == 0 else np.nan
        return float(np.max(np.abs(f_c - f_py)) / scale) if scale > 0 else np.inf

    def form(self, base: ControllerForm) -> CControllerForm:
        """``base`` with the C inverse and a new state from rest (one per run)."""
        state = np.zeros(-(-self._size // 8))
        self._init(state.ctypes.data)
        return CControllerForm(*base, self._step, state, np.zeros(1))

    def __repr__(self) -> str:
        return f"CInverse({str(self.path)!r}, kind={self.kind!r})"


def load_c_inverse(model: DamperModel, spec: Any) -> CInverse:
    """The C inverse ``spec`` (a :class:`CInverse` or the path of its library) checked against
    ``model`` (one-line errors: no such file, not a C export with an inverse, another kind, a kind
    the quarter car does not invert per sample)."""
    inv = spec if isinstance(spec, CInverse) else CInverse(spec)
    inv.check(model)
    return inv


def c_inverse_form(model: DamperModel, spec: Any, base: ControllerForm) -> CControllerForm:
    """The controller form of a quarter-car run of ``model`` with the C inverse ``spec``
    (:func:`load_c_inverse`), for the kernels of :func:`c_kernels`."""
    return load_c_inverse(model, spec).form(base)
