"""The LPV input ``u``: one strategy object per kind of input, and the choice of its settings.

The model's input is built from the velocity and the scheduling variable ``rho`` in one of three
ways, each a class with one interface (:class:`LPVInput`):

========================  ====================================================================
:class:`StaticInput`      ``"u"``: the paper's zone-law input of eqs. 19-22 (``reading``)
:class:`HystereticInput`  ``"hysteretic"``: the same with a Dahl pre-yield state of stroke
                          scale ``stroke`` [m] and share ``blend`` [-]
                          (:mod:`mrdamper.analysis.hysteretic`)
:class:`VelocityInput`    ``"v"``: the velocity itself (ablation)
========================  ====================================================================

The interface: :meth:`~LPVInput.signal` (the input of a record at the model rate),
:meth:`~LPVInput.kernel_arrays` (what the per-sample step reads: the zone-law mode and arrays and
the Dahl state's ``blend`` / ``stroke``; the compiled step, the inverse, the quarter car and the C
rendering all use these numbers), :meth:`~LPVInput.dahl_along` (the Dahl state along a motion),
:meth:`~LPVInput.steady` (the input of a steady motion) and :meth:`~LPVInput.saved` (the fields of
the model file: ``input_signal`` is the saved name, :data:`INPUTS` maps it back; files of earlier
versions load unchanged). A later input is one more class and one more row of :data:`INPUTS`.

When a hysteretic estimator's ``stroke`` [m] or ``blend`` [-] is None, they are chosen on the
grid :data:`STROKES` x :data:`BLENDS` by :func:`mrdamper.models.lpv.choice.fit_choosing`.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numpy as np
import numpy.typing as npt

from mrdamper.analysis.hysteretic import dahl_state, hysteretic_input
from mrdamper.analysis.scheduling import Reading
from mrdamper.errors import DataValidationError
from mrdamper.models.lpv.step import MODE_CONTINUOUS, MODE_LITERAL, MODE_V, zone_input

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.analysis import ZoneLaws

__all__ = [
    "BLENDS",
    "INPUTS",
    "STROKES",
    "HystereticInput",
    "InputArrays",
    "LPVInput",
    "StaticInput",
    "VelocityInput",
    "from_saved",
    "input_class",
]

FloatArray = npt.NDArray[np.float64]

#: Candidate stroke scales ``x_y`` [m] when ``stroke`` is not given.
STROKES: tuple[float, ...] = (5e-5, 1e-4, 2e-4)
#: Candidate pre-yield shares ``lambda`` [-] when ``blend`` is not given.
BLENDS: tuple[float, ...] = (0.25, 0.5)


class InputArrays(NamedTuple):
    """The input as the per-sample step reads it (:func:`~mrdamper.models.lpv.step.zone_input`).

    Attributes
    ----------
    mode : int
        ``MODE_V`` (``u = v``), ``MODE_CONTINUOUS`` or ``MODE_LITERAL`` (reading of eq. 22).
    gamma_m, gamma_c : ndarray, shape (3, degree + 1)
        Zone-law slopes and intercepts (zeros of shape (3, 1) for the velocity input).
    mu_high, mu_low : ndarray, shape (2,)
        Breakpoint laws (zeros for the velocity input).
    blend : float
        Share of the Dahl state in the pre-yield input [-] (0: a static input).
    stroke : float
        Stroke scale of the Dahl state [m] (0 for the static inputs).
    """

    mode: int
    gamma_m: FloatArray
    gamma_c: FloatArray
    mu_high: FloatArray
    mu_low: FloatArray
    blend: float
    stroke: float


def _check_stroke(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
        raise DataValidationError("stroke", f"expected a stroke scale [m], got {value!r}")
    if not (np.isfinite(value) and value > 0):
        raise DataValidationError("stroke", f"expected a positive stroke scale [m], got {value!r}")
    return float(value)


def _check_blend(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
        raise DataValidationError("blend", f"expected a share in [0, 1], got {value!r}")
    if not (np.isfinite(value) and 0.0 <= value <= 1.0):
        raise DataValidationError("blend", f"expected a share in [0, 1], got {value!r}")
    return float(value)


class LPVInput(abc.ABC):
    """One kind of LPV input (immutable); see the module docstring for the interface."""

    #: Saved name (the model file's ``input_signal``).
    name: ClassVar[str]
    #: Whether the input is built with zone laws (the estimator fits them when not given).
    needs_laws: ClassVar[bool] = True
    #: Zone laws the input is built with (None: the input needs none).
    laws: ZoneLaws | None = None

    @classmethod
    def open_settings(cls, reading: str, stroke: Any, blend: Any) -> tuple[str, ...]:
        """Validate an estimator's settings of this input; the names left to choose on the
        training records (none by default: a static input takes no ``stroke`` / ``blend``)."""
        for name, value in (("stroke", stroke), ("blend", blend)):
            if value is not None:
                raise DataValidationError(
                    name,
                    f"applies to input_signal='hysteretic' only; got {name}={value!r} "
                    f"with input_signal={cls.name!r}",
                )
        return ()

    @classmethod
    @abc.abstractmethod
    def build(cls, laws: ZoneLaws | None, reading: Reading, stroke: Any, blend: Any) -> LPVInput:
        """The input of a fitted model from its saved fields (validated; one-line errors)."""

    @abc.abstractmethod
    def signal(self, v: FloatArray, rho: FloatArray, dt: float) -> FloatArray:
        """The input ``u`` [m/s] of one record from its velocity [m/s] and ``rho`` at the model
        rate (sample time ``dt`` [s])."""

    @abc.abstractmethod
    def kernel_arrays(self) -> InputArrays:
        """The input as the per-sample step, the inverse and the quarter car read it."""

    @abc.abstractmethod
    def steady(self, v_ref: float, rho: float) -> float:
        """The input [m/s] of a steady motion at ``v_ref`` [m/s] (a Dahl state settled at
        ``sign(v_ref)``) and frozen ``rho``."""

    def dahl_along(self, v: FloatArray, dt: float) -> FloatArray:
        """The Dahl state [-] along the velocity ``v`` [m/s] from rest (zeros: no Dahl state)."""
        return np.zeros(v.size)

    def saved(self) -> dict[str, Any]:
        """The model's fields that carry the input (``input_signal``, ``stroke``, ``blend``)."""
        return {"input_signal": self.name, "stroke": None, "blend": None}


def _law_arrays(laws: ZoneLaws) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    return (
        np.ascontiguousarray(laws.gamma_m, dtype=np.float64),
        np.ascontiguousarray(laws.gamma_c, dtype=np.float64),
        np.asarray(laws.mu_high, dtype=np.float64),
        np.asarray(laws.mu_low, dtype=np.float64),
    )


def _need_laws(name: str, laws: ZoneLaws | None) -> ZoneLaws:
    if laws is None:
        raise DataValidationError("zone_laws", f"input_signal={name!r} needs zone laws to build u")
    return laws


@dataclass(frozen=True, eq=False)
class VelocityInput(LPVInput):
    """``u = v``: the velocity itself (ablation)."""

    name: ClassVar[str] = "v"
    needs_laws: ClassVar[bool] = False

    @classmethod
    def build(cls, laws: ZoneLaws | None, reading: Reading, stroke: Any, blend: Any) -> LPVInput:
        cls.open_settings(reading, stroke, blend)
        return cls()

    def signal(self, v: FloatArray, rho: FloatArray, dt: float) -> FloatArray:
        return v

    def kernel_arrays(self) -> InputArrays:
        z = np.zeros((3, 1))
        return InputArrays(MODE_V, z, z.copy(), np.zeros(2), np.zeros(2), 0.0, 0.0)

    def steady(self, v_ref: float, rho: float) -> float:
        return float(v_ref)


@dataclass(frozen=True, eq=False)
class StaticInput(LPVInput):
    """The zone-law input ``u(v, rho)`` of eqs. 19-22 (the paper's), reading ``reading``."""

    name: ClassVar[str] = "u"
    laws: ZoneLaws
    reading: Reading = "continuous"

    @classmethod
    def build(cls, laws: ZoneLaws | None, reading: Reading, stroke: Any, blend: Any) -> LPVInput:
        cls.open_settings(reading, stroke, blend)
        return cls(_need_laws(cls.name, laws), reading)

    def signal(self, v: FloatArray, rho: FloatArray, dt: float) -> FloatArray:
        return np.asarray(self.laws.scheduling_input(v, rho, reading=self.reading))

    def kernel_arrays(self) -> InputArrays:
        mode = MODE_CONTINUOUS if self.reading == "continuous" else MODE_LITERAL
        return InputArrays(mode, *_law_arrays(self.laws), 0.0, 0.0)

    def steady(self, v_ref: float, rho: float) -> float:
        u = self.laws.scheduling_input(np.array([v_ref]), np.array([rho]), reading=self.reading)
        return float(u[0])


@dataclass(frozen=True, eq=False)
class HystereticInput(StaticInput):
    """The zone-law input with a Dahl pre-yield state (continuous reading; see
    :mod:`mrdamper.analysis.hysteretic`): stroke scale ``stroke`` [m], share ``blend`` [-]."""

    name: ClassVar[str] = "hysteretic"
    stroke: float = 0.0
    blend: float = 0.0

    @classmethod
    def open_settings(cls, reading: str, stroke: Any, blend: Any) -> tuple[str, ...]:
        if reading != "continuous":
            raise DataValidationError(
                "reading",
                f"the hysteretic input builds on the continuous reading, got {reading!r}",
            )
        if stroke is not None:
            _check_stroke(stroke)
        if blend is not None:
            _check_blend(blend)
        return tuple(n for n, val in (("stroke", stroke), ("blend", blend)) if val is None)

    @classmethod
    def build(cls, laws: ZoneLaws | None, reading: Reading, stroke: Any, blend: Any) -> LPVInput:
        if stroke is None or blend is None:
            raise DataValidationError(
                "stroke", "input_signal='hysteretic' needs both stroke [m] and blend [-]"
            )
        cls.open_settings(reading, stroke, blend)
        laws = _need_laws(cls.name, laws)
        return cls(laws, "continuous", _check_stroke(stroke), _check_blend(blend))

    def signal(self, v: FloatArray, rho: FloatArray, dt: float) -> FloatArray:
        return hysteretic_input(self.laws, v, rho, dt, self.stroke, self.blend)

    def kernel_arrays(self) -> InputArrays:
        return InputArrays(MODE_CONTINUOUS, *_law_arrays(self.laws), self.blend, self.stroke)

    def steady(self, v_ref: float, rho: float) -> float:
        if self.blend == 0.0:  # the static input exactly
            return super().steady(v_ref, rho)
        a = self.kernel_arrays()
        z_ss = float(np.sign(v_ref))  # steady motion: the Dahl state has reached sign(v_ref)
        return float(
            zone_input(
                float(v_ref), rho, a.mode, a.gamma_m, a.gamma_c, a.mu_high, a.mu_low, z_ss, a.blend
            )
        )

    def dahl_along(self, v: FloatArray, dt: float) -> FloatArray:
        if self.blend == 0.0:
            return np.zeros(v.size)
        return np.asarray(dahl_state(v, dt, self.stroke))

    def saved(self) -> dict[str, Any]:
        return {"input_signal": self.name, "stroke": self.stroke, "blend": self.blend}


#: Every LPV input by its saved name (the model file's and the estimator's ``input_signal``).
INPUTS: dict[str, type[LPVInput]] = {
    c.name: c for c in (StaticInput, VelocityInput, HystereticInput)
}


def input_class(name: str) -> type[LPVInput]:
    """The input class saved as ``name``; an unknown name is refused in one line."""
    try:
        return INPUTS[name]
    except (KeyError, TypeError):
        raise DataValidationError(
            "input_signal", f"expected one of {sorted(INPUTS)}, got {name!r}"
        ) from None


def from_saved(
    name: str, laws: ZoneLaws | None, reading: Reading, stroke: Any, blend: Any
) -> LPVInput:
    """The input of a fitted model from its saved fields (``input_signal`` and the others)."""
    return input_class(name).build(laws, reading, stroke, blend)
