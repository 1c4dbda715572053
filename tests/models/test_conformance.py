"""Conformance of every model kind (in the spirit of scikit-learn's ``check_estimator``).

For each kind of this version (the rows of :data:`mrdamper.kinds.KINDS`), fitted once on a small
synthetic record set (sines at three current levels through the reference damper, with noise):

* the saved model loads back and predicts bit for bit the same force;
* the saved file holds no wall-clock or CPU time;
* a fit on one current level works, or is refused in one line;
* an unknown setting is refused in one line that names it;
* the per-sample step (:meth:`FittedModel.step` with the record's interval and the velocity
  bound :meth:`FittedModel.step_vmax`, driven by :func:`mrdamper.models.step.run_step`) gives the
  force of ``predict`` sample by sample, to 1e-9 of the force scale, on a record with a stepped
  current (one rule for the integration sub-steps of both);
* a discrete-time step refuses to run at another sample time than its own.
"""

from __future__ import annotations

import inspect
import json
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment, get_estimator, load_model
from mrdamper.errors import IdentificationError
from mrdamper.models.base import TIMING_PROVENANCE, FittedModel
from mrdamper.models.step import run_step
from mrdamper.rig import reference_damper
from tests.conftest import package_kinds

FS = 500.0
LEVELS = (0.2, 0.5, 0.8)
#: Settings that keep each fit short (the hysteretic LPV input with its stroke and share given,
#: so no candidate grid runs; one Spencer start).
FAST: dict[str, dict[str, Any]] = {
    "lpv": {"stroke": 1e-4, "blend": 0.5},
    "lti": {"stroke": 1e-4, "blend": 0.5},
    "spencer": {"n_starts": 1, "max_nfev": 20},
    "p15": {"max_nfev": 10},
}
#: Largest step-vs-predict difference, relative to the largest predicted force.
STEP_RTOL = 1e-9


def _record(
    amp: float, freq: float, levels: tuple[float, ...], name: str, cycles: float
) -> Experiment:
    """Sine displacement, current stepping through ``levels``, force of the reference damper."""
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


def _fit(kind: str, records: list[Experiment]) -> FittedModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return get_estimator(kind, **FAST.get(kind, {})).fit(records)


@pytest.fixture(scope="module")
def training() -> list[Experiment]:
    out = []
    for lev in LEVELS:
        out.append(_record(0.01, 1.0, (lev,), f"slow{lev}", 2.0))
        out.append(_record(0.004, 4.0, (lev,), f"fast{lev}", 4.0))
    return out


@pytest.fixture(scope="module")
def fitted(training: list[Experiment]) -> dict[str, FittedModel]:
    """Each kind fitted once (lazily, on first use)."""
    return {}


def _model(kind: str, fitted: dict[str, FittedModel], training: list[Experiment]) -> FittedModel:
    if kind not in fitted:
        fitted[kind] = _fit(kind, training)
    return fitted[kind]


@pytest.fixture(scope="module")
def probe() -> Experiment:
    """A record with a stepped current inside the training range; its first forces are zero (the
    NARX free run takes them as initial conditions, the step starts from rest)."""
    e = _record(0.008, 2.0, (0.3, 0.7, 0.4, 0.6), "probe", 3.0)
    F = e.F.copy()
    F[:20] = 0.0
    return e.replace(F=F)


def _step(model: FittedModel, record: Experiment) -> Any:
    """The model's step for the record's interval and velocity, where the step takes them
    (the continuous-time families): ``predict`` takes the sub-steps of this step."""
    params = inspect.signature(model.step).parameters
    if "dt" in params:
        return model.step(dt=record.dt, vmax=model.step_vmax(record.v))
    return model.step()


KINDS = package_kinds()


@pytest.mark.parametrize("kind", KINDS)
def test_save_load_round_trip(
    kind: str,
    fitted: dict[str, FittedModel],
    training: list[Experiment],
    probe: Experiment,
    tmp_path: Path,
) -> None:
    model = _model(kind, fitted, training)
    # the interval it was fitted at: a discrete model's own, else the records'
    assert model.sample_time == (1.0 / model.fs if hasattr(model, "fs") else 1.0 / FS)
    path = model.save(tmp_path / f"{kind}.json")
    back = load_model(path)
    assert type(back) is type(model)
    assert back.sample_time == model.sample_time
    np.testing.assert_array_equal(back.predict(probe), model.predict(probe))
    text = path.read_text(encoding="utf-8")
    found = set(re.findall(r'"(\w+)"\s*:', text)) & TIMING_PROVENANCE
    assert not found, f"{kind}: timing entries in the model file: {sorted(found)}"
    # no date or clock time either (ISO 8601 stamps)
    assert not re.search(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}", text), kind
    json.loads(text)


@pytest.mark.parametrize("kind", KINDS)
def test_step_equals_predict(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    model = _model(kind, fitted, training)
    expected = model.predict(probe)
    step = _step(model, probe)
    assert step.kind == kind
    F, status, sample = run_step(step, probe.x, probe.v, model.electrical_input(probe), probe.dt)
    assert status == 0 and sample == -1, (kind, status, sample)
    scale = float(np.max(np.abs(expected)))
    worst = float(np.max(np.abs(F - expected))) / scale
    assert worst <= STEP_RTOL, (
        f"{kind}: step differs from predict by {worst:.3g} of the force scale"
    )


@pytest.mark.parametrize("kind", KINDS)
def test_discrete_step_refuses_another_interval(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    model = _model(kind, fitted, training)
    step = _step(model, probe)
    if step.dt is None:  # continuous-time or static: any interval is allowed
        _, status, _ = run_step(step, probe.x, probe.v, model.electrical_input(probe), 2 * probe.dt)
        assert status == 0
        return
    assert step.dt == pytest.approx(probe.dt)
    with pytest.raises(ValueError, match=r"^dt: the \w+ step runs at its own sample time") as err:
        run_step(step, probe.x, probe.v, model.electrical_input(probe), 2 * probe.dt)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("kind", KINDS)
def test_unknown_setting_refused_in_one_line(kind: str) -> None:
    with pytest.raises(DataValidationError, match="no_such_setting") as err:
        get_estimator(kind, no_such_setting=1)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("kind", KINDS)
def test_single_level_fit_works_or_refuses_in_one_line(kind: str) -> None:
    records = [
        _record(0.01, 1.0, (0.5,), "one", 2.0),
        _record(0.004, 4.0, (0.5,), "two", 4.0),
    ]
    try:
        model = _fit(kind, records)
    except (DataValidationError, IdentificationError) as exc:
        assert "\n" not in str(exc), f"{kind}: refusal over several lines"
        return
    assert model.input_range == (0.5, 0.5)
    assert np.all(np.isfinite(model.predict(records[0])))


@pytest.mark.parametrize("kind", KINDS)
def test_step_packs_for_the_cached_dispatch(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    # every built-in family reaches the disk-cached kernels (models.step_dispatch): its packed
    # form, run through the dispatch, gives the force of its own step
    from mrdamper.models.step_dispatch import family_advance, family_force, pack

    model = _model(kind, fitted, training)
    step = _step(model, probe)
    pk = pack(step)
    assert pk is not None, kind
    e = model.electrical_input(probe)
    own = step.initial_state(float(probe.x[0]), float(probe.v[0]), float(e[0]))
    packed = own.copy()
    dt = probe.dt
    for k in range(40):
        a = step.force(step.form, own, probe.x[k], probe.v[k], e[k])
        b = family_force(pk, packed, probe.x[k], probe.v[k], e[k])
        assert a == b, (kind, k)
        args = (probe.x[k], probe.v[k], e[k], probe.x[k + 1], probe.v[k + 1], e[k + 1], dt)
        assert step.advance(step.form, own, *args) == family_advance(pk, packed, *args)
    np.testing.assert_array_equal(own, packed)
