"""Conformance checks of a model family, in the spirit of scikit-learn's ``check_estimator``.

:func:`check_family` fits an estimator once on a small synthetic record set (sines at three current
levels through the reference damper, with seeded noise) and checks what every tool of the package
relies on:

* ``registered``: the kind is known to the registry with these classes (so model files load);
* ``unknown_setting``: an unknown setting is refused in one line that names it;
* ``single_level``: a fit on one current level works, or is refused in one line;
* ``round_trip``: the saved model loads back with its sample time and predicts bit for bit the
  same force, and the file holds no wall-clock or CPU time and no date;
* ``step_equals_predict``: the per-sample step (:meth:`~mrdamper.models.FittedModel.step` with the
  record's interval and the velocity bound :meth:`~mrdamper.models.FittedModel.step_vmax`, run by
  :func:`mrdamper.models.step.run_step`) gives the force of ``predict`` sample by sample, to
  :data:`STEP_RTOL` of the force scale, on a record with a stepped current (one rule for the
  integration sub-steps of both);
* ``discrete_step``: a discrete-time step refuses to run at another sample time than its own (a
  continuous-time or static step runs at any).

The package's own conformance tests (``tests/models/test_conformance.py``) run these same checks
over every kind of the kind table; a family without a per-sample step skips the two step checks
(it then cannot be the damper of the quarter car nor be exported).
"""

from __future__ import annotations

import inspect
import json
import re
import tempfile
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mrdamper.errors import ConformanceError, DataValidationError, IdentificationError

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from mrdamper.data import Experiment
    from mrdamper.models import Estimator, FittedModel
    from mrdamper.models.step import Step

__all__ = [
    "CHECKS",
    "FS",
    "STEP_RTOL",
    "FamilyCheck",
    "check_discrete_step",
    "check_family",
    "check_registered",
    "check_round_trip",
    "check_single_level",
    "check_step_equals_predict",
    "check_unknown_setting",
    "fit_quietly",
    "has_step",
    "model_step",
    "probe_record",
    "synthetic_record",
    "training_records",
]

#: Sampling rate of the synthetic records [Hz].
FS = 500.0
#: Current levels of the training records [A].
LEVELS = (0.2, 0.5, 0.8)
#: Largest step-vs-predict difference, relative to the largest predicted force.
STEP_RTOL = 1e-9


def synthetic_record(
    amp: float, freq: float, levels: tuple[float, ...], name: str, cycles: float
) -> Experiment:
    """A sine displacement with the current stepping through ``levels``, and the force of the
    reference damper plus seeded noise (5 N rms).

    Parameters
    ----------
    amp : float
        Displacement amplitude [m].
    freq : float
        Frequency [Hz].
    levels : tuple of float
        Current levels [A], each held for an equal share of the record.
    name : str
        Record name (also seeds the noise).
    cycles : float
        Length in periods.
    """
    from mrdamper.data import Experiment
    from mrdamper.rig import reference_damper

    t = np.arange(round(cycles / freq * FS)) / FS
    x = amp * np.sin(2 * np.pi * freq * t)
    v = amp * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t)
    i = np.asarray(levels)[(np.arange(t.size) * len(levels)) // t.size]
    meta = {"current": levels[0]} if len(levels) == 1 else {}
    e = Experiment(t=t, x=x, v=v, F=np.zeros_like(t), i=i, name=name, metadata=meta)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        F = reference_damper().predict(e)
    return e.replace(F=F + np.random.default_rng(len(name)).normal(0.0, 5.0, t.size))


def training_records() -> list[Experiment]:
    """Six records: a slow and a fast sine at each level of :data:`LEVELS`."""
    out = []
    for lev in LEVELS:
        out.append(synthetic_record(0.01, 1.0, (lev,), f"slow{lev}", 2.0))
        out.append(synthetic_record(0.004, 4.0, (lev,), f"fast{lev}", 4.0))
    return out


def probe_record() -> Experiment:
    """A record with a stepped current inside the training range; its first forces are zero (a
    free run that takes past forces as initial conditions and the step both start from rest)."""
    e = synthetic_record(0.008, 2.0, (0.3, 0.7, 0.4, 0.6), "probe", 3.0)
    F = e.F.copy()
    F[:20] = 0.0
    return e.replace(F=F)


def fit_quietly(estimator: Estimator, records: list[Experiment]) -> FittedModel:
    """``estimator.fit(records)`` with its warnings and notes silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return estimator.fit(records)


def _fail(kind: str, check: str, text: str) -> ConformanceError:
    return ConformanceError(f"{kind}: {check}: {' '.join(text.split())}")


def has_step(model: FittedModel) -> bool:
    """Whether the model's family gives a per-sample step (overrides the base refusal)."""
    from mrdamper.models import FittedModel

    return type(model).step is not FittedModel.step


def model_step(model: FittedModel, record: Experiment) -> tuple[FittedModel, Step]:
    """The model and its step for ``record``: with the record's interval and the velocity bound
    :meth:`~mrdamper.models.FittedModel.step_vmax` of its motion where the step takes them (the
    continuous-time families; ``predict`` takes the sub-steps of this step)."""
    params = inspect.signature(model.step).parameters
    if "dt" in params:
        return model, model.step(dt=record.dt, vmax=model.step_vmax(record.v))
    return model, model.step()


def check_registered(estimator: Estimator) -> None:
    """The estimator's kind is known to the registry, with this estimator's and model's classes."""
    from mrdamper.models.registry import get_estimator, known_kinds, model_class

    kind = estimator.kind
    if kind not in known_kinds():
        raise _fail(
            kind,
            "registered",
            "the kind is not in the kind table; give it an entry point in the group "
            "mrdamper.kinds (every process) or call mrdamper.models.register (this one)",
        )
    cls = getattr(type(estimator), "model_class", None)
    if cls is not None and model_class(kind) is not cls:
        raise _fail(kind, "registered", f"the registry's model class is {model_class(kind)!r}")
    if type(get_estimator(kind)) is not type(estimator):
        raise _fail(kind, "registered", f"the registry's estimator is {type(get_estimator(kind))}")


def check_unknown_setting(estimator: Estimator) -> None:
    """An unknown setting is refused in one line that names it."""
    kind = estimator.kind
    try:
        type(estimator).from_settings(no_such_setting=1)
    except DataValidationError as exc:
        if "no_such_setting" not in str(exc) or "\n" in str(exc):
            raise _fail(kind, "unknown_setting", f"the refusal {str(exc)!r}") from None
        return
    raise _fail(kind, "unknown_setting", "the setting 'no_such_setting' was accepted")


def check_single_level(estimator: Estimator) -> None:
    """A fit on records at one current level works (range collapsed to the level, finite
    prediction) or is refused in one line."""
    kind = estimator.kind
    records = [
        synthetic_record(0.01, 1.0, (0.5,), "one", 2.0),
        synthetic_record(0.004, 4.0, (0.5,), "two", 4.0),
    ]
    try:
        model = fit_quietly(estimator, records)
    except (DataValidationError, IdentificationError) as exc:
        if "\n" in str(exc):
            raise _fail(kind, "single_level", "refused over several lines") from None
        return
    if model.input_range != (0.5, 0.5):
        raise _fail(kind, "single_level", f"input range {model.input_range}, expected (0.5, 0.5)")
    if not np.all(np.isfinite(model.predict(records[0]))):
        raise _fail(kind, "single_level", "the prediction is not finite")


def check_round_trip(model: FittedModel, probe: Experiment, folder: str | Path) -> None:
    """The model saved in ``folder`` loads back as the same class and predicts ``probe`` bit for
    bit; the file is JSON without timing entries or dates."""
    from mrdamper.models.base import TIMING_PROVENANCE
    from mrdamper.models.registry import load_model

    kind = model.kind
    path = model.save(Path(folder) / f"{kind}.json")
    back = load_model(path)
    if type(back) is not type(model):
        raise _fail(kind, "round_trip", f"loads back as {type(back).__name__}")
    if back.sample_time != model.sample_time:
        raise _fail(
            kind, "round_trip", f"sample_time {model.sample_time!r} loads as {back.sample_time!r}"
        )
    if not np.array_equal(back.predict(probe), model.predict(probe)):
        raise _fail(kind, "round_trip", "the loaded model predicts another force")
    text = path.read_text(encoding="utf-8")
    json.loads(text)
    found = set(re.findall(r'"(\w+)"\s*:', text)) & TIMING_PROVENANCE
    if found:
        raise _fail(kind, "round_trip", f"timing entries in the model file: {sorted(found)}")
    if re.search(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}", text):
        raise _fail(kind, "round_trip", "a date or clock time in the model file")


def check_step_equals_predict(model: FittedModel, probe: Experiment) -> None:
    """The per-sample step from rest gives ``predict``'s force on ``probe`` to
    :data:`STEP_RTOL` of the force scale."""
    from mrdamper.models.step import run_step

    kind = model.kind
    model, step = model_step(model, probe)
    expected = model.predict(probe)
    if step.kind != kind:
        raise _fail(kind, "step_equals_predict", f"the step says kind {step.kind!r}")
    e = model.electrical_input(probe)
    F, status, sample = run_step(step, probe.x, probe.v, e, probe.dt)
    if status != 0 or sample != -1:
        raise _fail(kind, "step_equals_predict", f"status {status} at sample {sample}")
    scale = float(np.max(np.abs(expected)))
    worst = float(np.max(np.abs(F - expected))) / scale
    if not worst <= STEP_RTOL:
        raise _fail(
            kind, "step_equals_predict", f"the step differs by {worst:.3g} of the force scale"
        )


def check_discrete_step(model: FittedModel, probe: Experiment) -> None:
    """A discrete-time step (``Step.dt`` set) runs at ``probe``'s interval and refuses twice
    that in one line; another step runs at twice the interval."""
    from mrdamper.models.step import run_step

    kind = model.kind
    model, step = model_step(model, probe)
    e = model.electrical_input(probe)
    if step.dt is None:
        _, status, _ = run_step(step, probe.x, probe.v, e, 2 * probe.dt)
        if status != 0:
            raise _fail(kind, "discrete_step", f"status {status} at twice the interval")
        return
    if not np.isclose(step.dt, probe.dt, rtol=1e-9, atol=0.0):
        raise _fail(kind, "discrete_step", f"step.dt {step.dt!r} s on a {probe.dt!r} s record")
    try:
        run_step(step, probe.x, probe.v, e, 2 * probe.dt)
    except ValueError as exc:
        if not re.match(r"dt: the \w+ step runs at its own sample time", str(exc)):
            raise _fail(kind, "discrete_step", f"the refusal {str(exc)!r}") from None
        return
    raise _fail(kind, "discrete_step", "ran at twice its own sample time")


#: The checks of :func:`check_family`, in order: name -> check. The first three take the
#: estimator; the others the fitted model and the probe record (``round_trip`` also a folder).
CHECKS: dict[str, Callable[..., None]] = {
    "registered": check_registered,
    "unknown_setting": check_unknown_setting,
    "single_level": check_single_level,
    "round_trip": check_round_trip,
    "step_equals_predict": check_step_equals_predict,
    "discrete_step": check_discrete_step,
}


@dataclass(frozen=True)
class FamilyCheck:
    """Outcome of :func:`check_family`.

    Attributes
    ----------
    kind : str
        The family's kind.
    passed : tuple of str
        Checks passed (names of :data:`CHECKS`), in order.
    skipped : tuple of (str, str)
        Checks that do not apply, with the reason.
    """

    kind: str
    passed: tuple[str, ...]
    skipped: tuple[tuple[str, str], ...]

    def to_frame(self) -> pd.DataFrame:
        """One row per check: ``check``, ``status`` (``passed`` / ``skipped``), ``reason``."""
        import pandas as pd

        rows = [{"check": c, "status": "passed", "reason": ""} for c in self.passed]
        rows += [{"check": c, "status": "skipped", "reason": r} for c, r in self.skipped]
        order = list(CHECKS)
        rows.sort(key=lambda r: order.index(r["check"]))
        return pd.DataFrame(rows, columns=["check", "status", "reason"])


def check_family(estimator: Estimator | type[Estimator]) -> FamilyCheck:
    """Run the conformance checks (:data:`CHECKS`) on a model family.

    The estimator is fitted once on :func:`training_records` (with its own settings; keep them
    cheap) and the fitted model is checked on :func:`probe_record`.

    Parameters
    ----------
    estimator : Estimator or type of Estimator
        The family's estimator (a class is used with its default settings).

    Returns
    -------
    FamilyCheck
        The checks passed and those skipped (a family without a per-sample step skips the two
        step checks).

    Raises
    ------
    ConformanceError
        One line naming every check that failed and why.

    Examples
    --------
    >>> from mrdamper import check_family, get_estimator
    >>> check_family(get_estimator("bingham")).passed[:3]
    ('registered', 'unknown_setting', 'single_level')
    """
    from mrdamper.models import Estimator

    if isinstance(estimator, type):
        estimator = estimator()
    if not isinstance(estimator, Estimator):
        raise DataValidationError(
            "estimator", f"expected an Estimator or its class, got {type(estimator).__name__}"
        )
    kind = estimator.kind
    failed: list[str] = []
    passed: list[str] = []
    skipped: list[tuple[str, str]] = []

    def run(name: str, *args: Any) -> None:
        try:
            CHECKS[name](*args)
        except ConformanceError as exc:
            failed.append(str(exc).removeprefix(f"{kind}: "))
        except Exception as exc:  # noqa: BLE001 - a family's own error is a failed check
            failed.append(f"{name}: raised {type(exc).__name__}: {' '.join(str(exc).split())}")
        else:
            passed.append(name)

    for name in ("registered", "unknown_setting", "single_level"):
        run(name, estimator)
    try:
        model = fit_quietly(estimator, training_records())
    except Exception as exc:  # noqa: BLE001 - reported as the failure it is
        failed.append(f"fit: raised {type(exc).__name__}: {' '.join(str(exc).split())}")
        skipped += [(n, "the fit failed") for n in list(CHECKS)[3:]]
        model = None
    if model is not None:
        probe = probe_record()
        with tempfile.TemporaryDirectory(prefix="mrdamper-check-") as folder:
            run("round_trip", model, probe, folder)
        for name in ("step_equals_predict", "discrete_step"):
            if has_step(model):
                run(name, model, probe)
            else:
                skipped.append((name, "no per-sample step (FittedModel.step)"))
    if failed:
        raise ConformanceError(f"{kind}: " + "; ".join(failed))
    return FamilyCheck(kind, tuple(passed), tuple(skipped))
