"""Bingham plastic reference model of an MR damper, current dependent.

``F = fc(e) * sign(v) + c0(e) * v + f0`` with ``fc`` and ``c0`` polynomials of degree ``degree``
in the electrical input e (coil current ``i`` [A] or command ``voltage`` [V]). With
``v_eps > 0`` the sign is smoothed to ``tanh(v / v_eps)``. The model is static (no state), so its
free-run prediction is a direct evaluation; it is identified by linear least squares over all
records.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource, require_experiment
from mrdamper.errors import DataValidationError
from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    TrainingData,
    check_int,
    check_number,
)
from mrdamper.models.bingham.fit import identify
from mrdamper.models.protocols import StaticMapForm
from mrdamper.models.sp.kernels import make_static_step
from mrdamper.models.step import Step

__all__ = ["BinghamEstimator", "BinghamModel"]


def _coefficients(name: str, values: Any) -> tuple[float, ...]:
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise DataValidationError(
            name, f"expected a sequence of polynomial coefficients, got {values!r}"
        )
    out = []
    for k, v in enumerate(values):
        if (
            isinstance(v, bool)
            or not isinstance(v, (int, float, np.integer, np.floating))
            or not math.isfinite(float(v))
        ):
            raise DataValidationError(name, f"coefficient {k} must be a finite number, got {v!r}")
        out.append(float(v))
    if not out:
        raise DataValidationError(name, "expected at least one coefficient")
    return tuple(out)


@dataclass(frozen=True, kw_only=True)
class BinghamModel(FittedModel):
    """Bingham plastic model with current-dependent yield force and viscous damping.

    Parameters
    ----------
    fc : tuple of float
        Yield (friction) force polynomial in the electrical input, lowest degree first:
        ``fc(e) = fc[0] + fc[1] e + ...`` [N], [N/U], ... (U = A or V).
    c0 : tuple of float
        Viscous damping polynomial, lowest degree first [N s/m], [N s/(m U)], ...
    f0 : float
        Force offset [N].
    v_eps : float
        Smoothing velocity of the sign [m/s]; 0 uses the exact sign.

    Examples
    --------
    >>> import numpy as np
    >>> from mrdamper.data import Experiment
    >>> t = np.arange(100) * 1e-3
    >>> v = np.sin(2 * np.pi * 5 * t) * 0.1
    >>> e = Experiment(t=t, x=0 * t, v=v, F=0 * t, i=0 * t + 1.0, name="demo")
    >>> m = BinghamModel(fc=(100.0, 500.0), c0=(1000.0, 2000.0), f0=0.0, input_range=(0, 1))
    >>> round(float(m.predict(e)[50]), 6)  # v = 0.1 m/s at 1 A: 600 N + 3000 N s/m * 0.1 m/s
    900.0
    """

    kind: ClassVar[str] = "bingham"

    fc: tuple[float, ...]
    c0: tuple[float, ...]
    f0: float = 0.0
    v_eps: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "fc", _coefficients("fc", self.fc))
        object.__setattr__(self, "c0", _coefficients("c0", self.c0))
        for name in ("f0", "v_eps"):
            v = getattr(self, name)
            if (
                isinstance(v, bool)
                or not isinstance(v, (int, float, np.integer, np.floating))
                or not math.isfinite(float(v))
            ):
                raise DataValidationError(name, f"expected a finite number, got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.v_eps < 0:
            raise DataValidationError(
                "v_eps", f"expected a smoothing velocity >= 0 [m/s], got {self.v_eps!r}"
            )
        if self.input not in ("i", "voltage"):
            raise DataValidationError("input", f"expected 'i' or 'voltage', got {self.input!r}")

    def sign(self, v: np.ndarray) -> np.ndarray:
        """``sign(v)`` or ``tanh(v / v_eps)`` [-]."""
        return np.sign(v) if self.v_eps == 0.0 else np.tanh(v / self.v_eps)

    def force(self, x: np.ndarray, v: np.ndarray, i: np.ndarray) -> np.ndarray:
        """Evaluate the model on plain arrays (no range policy) [N].

        Parameters
        ----------
        x, v, i : ndarray
            Displacement [m] (unused: the model does not depend on it), velocity [m/s],
            electrical input [A or V].
        """
        fc = np.polynomial.polynomial.polyval(i, self.fc)
        c0 = np.polynomial.polynomial.polyval(i, self.c0)
        return np.asarray(fc * self.sign(v) + c0 * v + self.f0)

    def inverse_form(self) -> StaticMapForm:
        """The model as a static map of the control kernels: ``fc(i) tanh(v / v_eps) + c0(i) v +
        f0``, the exact sign written ``tanh(1e300 v)`` when ``v_eps = 0`` (invertible, see
        :class:`~mrdamper.models.protocols.InvertibleModel`)."""
        comp = [0] * len(self.fc) + [1] + [3] * len(self.c0)
        power = list(range(len(self.fc))) + [0] + list(range(len(self.c0)))
        slope = 1e300 if self.v_eps == 0.0 else 1.0 / self.v_eps
        return StaticMapForm(
            np.asarray(comp, dtype=np.int64),
            np.asarray(power, dtype=np.int64),
            np.asarray([*self.fc, slope, *self.c0], dtype=np.float64),
            float(self.f0),
        )

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The model as a per-sample step (:mod:`mrdamper.models.step`): the static map of
        :meth:`inverse_form`, stateless but for the input it holds; no range policy.

        Parameters
        ----------
        dt, vmax : float
            Interval [s] and largest velocity [m/s] the step will see; unused by this family
            (the common signature of :meth:`~mrdamper.models.FittedModel.step`).
        """
        return make_static_step(self.kind, self.inverse_form())

    def predict(self, experiment: Experiment) -> np.ndarray:
        """Force [N] from the record's velocity and electrical input.

        Raises
        ------
        DataValidationError
            If the record lacks the model's electrical input channel.
        OutOfRangeError
            If the input leaves ``input_range`` and ``range_policy == "error"``.
        """
        require_experiment(experiment)
        return self.force(experiment.x, experiment.v, self.electrical_input(experiment))


@dataclass
class BinghamEstimator(Estimator):
    """Identify a :class:`BinghamModel` by linear least squares over all records (settings only).

    Parameters
    ----------
    input : {"i", "voltage"}
        Electrical input channel.
    degree : int
        Polynomial degree of ``fc`` and ``c0`` in the input; needs at least ``degree + 1``
        distinct input levels in the data, except at one constant level, where both reduce to
        constants (degree 0; noted in ``provenance["note"]`` and a ``UserWarning``).
    v_eps : float
        Sign smoothing velocity [m/s] (0: exact sign).
    weighting : {"record", "none"}
        ``"record"`` weights each record by ``1 / (std(F) sqrt(N_record))`` so records count
        equally; ``"none"`` weights samples equally.
    range_policy : {"error", "warn", "clip", "ignore"}
        Range policy of the fitted model.
    """

    kind: ClassVar[str] = "bingham"
    model_class: ClassVar[type[FittedModel]] = BinghamModel

    input: ElectricalSource = "i"
    degree: int = 2
    v_eps: float = 0.0
    weighting: Literal["record", "none"] = "record"
    range_policy: RangePolicy = "error"

    def _validate(self) -> None:
        super()._validate()
        check_int("degree", self.degree, 0)
        check_number("v_eps", self.v_eps, strict=False, what="a smoothing velocity >= 0 [m/s]")

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """Weighted linear least squares over all records (blockwise QR, never one big matrix).

        Raises
        ------
        IdentificationError
            The regression is rank deficient (e.g. fewer input levels than ``degree + 1``).
        """
        sign = BinghamModel(fc=(0.0,), c0=(0.0,), v_eps=self.v_eps).sign
        # one level: fc and c0 reduce to constants
        deg = 0 if data.single else int(self.degree)
        coef, provenance = identify(
            data.records, data.electrical, deg, self.weighting, sign, self.input
        )
        return Identified(
            parameters={
                "fc": tuple(coef[: deg + 1]),
                "c0": tuple(coef[deg + 1 : 2 * deg + 2]),
                "f0": float(coef[-1]),
                "v_eps": float(self.v_eps),
            },
            provenance=provenance,
        )
