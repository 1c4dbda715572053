"""Any damper in the quarter-car loop: a controller built on one model, the car on another damper.

:func:`simulate_closed_loop` drives the quarter car (:mod:`mrdamper.control.loop.quarter_car`) with
the controller and inverse of ``model`` and ``plant`` as the damper, through the plant's
per-sample step (:meth:`~mrdamper.models.base.FittedModel.step`), so any model kind (Spencer,
P-15, NARX, LTI, the rig's reference damper) can be the damper. Without a plant (or with the model
itself as plant) a static map or LPV model runs in the fused kernel of the quarter car (the same
numbers as :func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car`).

Numerics of the generic loop (:mod:`mrdamper.control.loop._closed_loop_kernels`):

* the car is integrated by RK4 at the plant step ``h`` (``substeps`` per road sample, the road
  linear in between);
* a continuous-time plant (static maps, Spencer, P-15: ``Step.dt`` None) gives its force at
  *every Runge-Kutta stage*, from the stage's damper motion with the plant state held at its value
  at the step start, and its state is then advanced over ``h`` with the motion at both ends.
  Evaluating at every stage keeps the plant's direct dependence on the motion (the viscous and
  stiffness parts of a Bouc-Wen force, the whole of a static map) inside the car's RK4 as it is
  in the fused kernel (a static map as plant then gives the fused kernel's numbers); only the
  internal state lags by at most one step, which the halving check bounds;
* a discrete-time plant (LPV, LTI, NARX: ``Step.dt`` set) runs at its own sample time (an integer
  number of plant steps); between two samples its force is linear in time from its value at the
  present sample to the value its step gives for the next sample with the present motion and
  input held (a first-order hold). For a model without direct feedthrough (LPV, LTI) that next
  value is exact once the present motion is known; a held force (zero-order hold) would add half
  a sample of delay, which makes a stiff damper ring at the model's Nyquist frequency;
* the controller runs at the control sample (the road's sampling interval, or an LPV model's
  sample time) and its input is held in between (zero-order hold). A static map or LPV model is
  inverted by the quarter car's own inverse
  (:func:`~mrdamper.control.loop._quarter_car_kernels.control_sample`: the model runs as an observer
  of the measured damper motion); with a drive lag the command is the lag's inverse of the chosen
  ``rho`` and reaches the plant one control sample later than the model assumes. A model with a
  continuous-time step and no inverse form (Spencer, P-15, tanh, Bouc-Wen, Dahl, LuGre) is
  stepped as an observer of the
  measured motion and the applied input and inverted over a lead of ``n_lead`` control samples
  (the 63 % rise time of its force after an input step, measured on the step):
  :func:`~mrdamper.control.loop._closed_loop_kernels._step_inverse`. A discrete-time model without
  an
  inverse form (LTI, NARX) is inverted the same way at its own sample time, which is then the
  control sample (the road's rate an integer multiple of the model's).

:mod:`mrdamper.control.loop.fidelity` compares predicted (model as damper) and achieved (plant as
damper) metrics and checks the numerics.
"""

from __future__ import annotations

from typing import Any, cast

from mrdamper.control.damper import DamperModel
from mrdamper.control.export.c_inverse import c_inverse_form, c_kernels, load_c_inverse
from mrdamper.control.export.fmu_plant import is_fmu
from mrdamper.control.inverse.step_inverse import (
    StepControl,
    invert_through_step,
    plant_step,
    step_control,
)
from mrdamper.control.loop import _closed_loop_kernels as CK
from mrdamper.control.loop._loop import (
    LoopSetup,
    controller_form,
    damper_arrays,
    divergence_hint,
    loop_result,
    loop_setup,
)
from mrdamper.control.loop.car import loop_inputs, positive
from mrdamper.control.loop.controllers import law_of
from mrdamper.control.loop.quarter_car import (
    Controller,
    LinearDamper,
    QuarterCar,
    QuarterCarResult,
    Road,
    simulate_quarter_car,
)
from mrdamper.errors import DataValidationError, SimulationDivergedError
from mrdamper.models.base import FittedModel
from mrdamper.models.protocols import InvertibleModel
from mrdamper.models.step_dispatch import pack

__all__ = [
    "StepControl",
    "invert_through_step",
    "plant_step",
    "resolve_plant",
    "simulate_closed_loop",
    "step_control",
    "stepped",
]


def resolve_plant(spec: Any) -> Any:
    """The damper a ``--plant`` names.

    Parameters
    ----------
    spec : str, path or model
        ``"rig"`` (the virtual rig's default reference damper), ``"rig:NAME"`` (a shipped
        reference damper), the path of a saved model file, the path of a damper FMU written by
        :func:`~mrdamper.control.export.fmu.export_fmu` (its binary's step:
        :class:`~mrdamper.control.export.fmu_plant.FMUPlant`), or a model (returned as is).
    """
    from pathlib import Path

    from mrdamper.models.registry import load_model
    from mrdamper.rig.reference import DEFAULT_REFERENCE, reference_damper

    if not isinstance(spec, (str, Path)):
        return spec
    text = str(spec)
    if text == "rig":
        return reference_damper(DEFAULT_REFERENCE)
    if text.startswith("rig:"):
        return reference_damper(text[4:])
    if is_fmu(text):
        from mrdamper.control.export.fmu_plant import FMUPlant

        return FMUPlant(text)
    path = Path(text)
    if not path.is_file():
        raise DataValidationError(
            "--plant",
            f"expected 'rig', 'rig:NAME', a model file or an FMU, got {text!r} (no such file)",
        )
    return load_model(path)


def stepped(model: DamperModel, plant: Any = None) -> bool:
    """True when the loop drives its damper through the damper's per-sample step (another
    ``plant``, or a model without an inverse form); False when ``model`` is its own damper in the
    fused kernel of :func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car`."""
    own = plant is None or plant is model
    return not (own and isinstance(model, (InvertibleModel, LinearDamper)))


def check_pair(model: DamperModel, plant: Any) -> None:
    """Refuse a plant whose electrical input is another channel than the model's (one line)."""
    mi, pi = getattr(model, "input", None), getattr(plant, "input", None)
    if mi != pi:
        units = {"i": "coil current [A]", "voltage": "command voltage [V]"}
        raise DataValidationError(
            "plant",
            f"the {getattr(plant, 'kind', '?')} plant is driven by {units.get(str(pi), pi)}, the "
            f"{getattr(model, 'kind', '?')} model by {units.get(str(mi), mi)}: not the same input",
        )


def simulate_closed_loop(
    model: DamperModel,
    road: Road,
    controller: Controller | str = "soft",
    car: QuarterCar | None = None,
    *,
    plant: Any = None,
    substeps: int = 1,
    reg: float | None = None,
    v_ref: float = 0.3,
    rate: float | None = None,
    i_range: tuple[float, float] | None = None,
    n_grid: int = 16,
    bound: float = 10.0,
    c_inverse: Any = None,
) -> QuarterCarResult:
    """Drive the quarter car with ``model``'s controller and ``plant`` as the damper.

    Parameters
    ----------
    model : FittedModel
        The controller's model (its inverse). Semi-active controllers need a static map, an LPV
        model or a model with a continuous-time step; passive ones take any model.
    road : Road
        Road (its rate sets the control sample, or an LPV model's rate does).
    controller : Controller or str
        Controller.
    car : QuarterCar, optional
        Car (default :class:`QuarterCar()`).
    plant : FittedModel or str, optional
        The damper (see :func:`resolve_plant`); default ``model`` itself.
    substeps : int
        Plant steps per road sample.
    reg, v_ref, rate, i_range, n_grid, bound
        As :func:`~mrdamper.control.loop.quarter_car.simulate_quarter_car`.
    c_inverse : CInverse, str or Path, optional
        A compiled C export of ``model`` (a static map or an LPV model) whose inverse replaces the
        loop's own at every control sample (:mod:`mrdamper.control.export.c_inverse`).

    Returns
    -------
    QuarterCarResult
        ``F`` is the plant's force (rest force removed) at every plant step, ``i`` the applied
        input.
    """
    car, ctrl = loop_inputs(road, controller, car)
    plant = model if plant is None else resolve_plant(plant)
    invertible = isinstance(model, (InvertibleModel, LinearDamper))
    if not stepped(model, plant):
        return simulate_quarter_car(
            model,
            road,
            ctrl,
            car,
            reg=reg,
            v_ref=v_ref,
            rate=rate,
            i_range=i_range,
            n_grid=n_grid,
            bound=bound,
            substeps=substeps,
            c_inverse=c_inverse,
        )
    check_pair(model, plant)
    passive = law_of(ctrl.kind).passive
    sc: StepControl | None = None
    arrays = None
    if not invertible:
        if c_inverse is not None:
            load_c_inverse(model, c_inverse)  # refuses the kind (one line)
        arrays = damper_arrays(None)
        if not passive:
            sc = _step_control_of(cast(FittedModel, model), 1.0 / road.fs, v_ref)
    s = loop_setup(
        model,
        road,
        ctrl,
        car,
        reg=reg,
        v_ref=v_ref,
        rate=rate,
        i_range=i_range,
        substeps=substeps,
        arrays=arrays,
        authority=None if sc is None else sc.authority,
        sample=None if sc is None else sc.sample,
    )
    return _run(model, plant, s, sc, n_grid, bound, c_inverse)


def _step_control_of(model: FittedModel, dt_c: float, v_ref: float) -> StepControl:
    try:
        step = model.step()
    except DataValidationError:
        step = None
    if step is None:
        raise DataValidationError(
            "MODEL",
            f"kind {getattr(model, 'kind', '?')!r} has no inverse and no per-sample step to "
            "invert: semi-active controllers need one; passive soft/hard work",
        )
    return step_control(model, dt_c, positive("v_ref", v_ref, "m/s"))


def _run(
    model: DamperModel,
    plant: Any,
    s: LoopSetup,
    sc: StepControl | None,
    n_grid: int,
    bound: float,
    c_inverse: Any = None,
) -> QuarterCarResult:
    pstep = plant_step(plant, s.h)
    p_every = 0
    if pstep.dt is not None:
        ratio = pstep.dt / s.h
        p_every = round(ratio)
        if p_every < 1 or abs(ratio - p_every) > 1e-9 * ratio:
            raise DataValidationError(
                "plant",
                f"the {plant.kind} plant runs at {1.0 / pstep.dt:g} Hz; the plant step "
                f"{s.h:g} s must divide its sample time {pstep.dt:g} s",
            )
    e0 = float(s.gains[3]) if law_of(s.ctrl.kind).passive else s.lo
    p_state = pstep.initial_state(0.0, 0.0, e0)
    p_offset = float(pstep.force(pstep.form, p_state, 0.0, 0.0, e0))
    if sc is None:  # unused by the kernel: the plant's step stands in for the controller's
        c, c_state, c_offset, n_lead = pstep, p_state.copy(), 0.0, 1
    else:
        c = sc.step
        c_state = c.initial_state(0.0, 0.0, s.lo)
        c_offset = float(c.force(c.form, c_state, 0.0, 0.0, s.lo))
        n_lead = sc.n_lead
    form: Any = controller_form(s, n_grid)
    packed_loop, control = CK.run_loop_packed, None
    if c_inverse is not None:
        form = c_inverse_form(model, c_inverse, form)
        packed_loop, control = c_kernels()["loop"], c_kernels()["sample"]
    head = (s.zr, s.h, s.n_sub, s.car_arr, form, float(bound) * s.mr, sc is not None)
    p_packed, c_packed = pack(pstep), pack(c)
    if p_packed is not None and c_packed is not None:  # built-in families: the cached kernel
        out = packed_loop(
            *head, c_packed, c_state, c_offset, int(n_lead), p_packed, p_state, p_offset, p_every
        )
    else:  # a family added at run time: its functions as arguments (compiled in this process)
        loop = CK.run_loop(c.force, c.advance, pstep.force, pstep.advance, control)
        out = loop(
            *head, c.form, c_state, c_offset, int(n_lead), pstep.form, p_state, p_offset, p_every
        )
    X, F, Fd, E, sat, bad, status = out
    if bad >= 0:
        what = {-1: f"a car state left +-{bound:g}", -2: "the controller's model failed"}.get(
            int(status), f"the {plant.kind} plant's step failed (status {int(status)})"
        )
        hint = divergence_hint(plant) if int(status) == -1 else ""
        raise SimulationDivergedError(
            plant.kind, int(bad), f"{what} at t = {bad * s.h:.4g} s{hint}"
        )
    return loop_result(s, plant.kind, X, F, Fd, E, sat)
