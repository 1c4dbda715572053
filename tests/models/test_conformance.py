"""Conformance of every model kind (in the spirit of scikit-learn's ``check_estimator``).

For each kind of this version (the rows of :data:`mrdamper.kinds.KINDS`), fitted once on the small
synthetic record set of :mod:`mrdamper.conformance` (sines at three current levels through the
reference damper, with noise), every check of :data:`mrdamper.conformance.CHECKS` (the checks
that :func:`mrdamper.check_family` runs on any family, a plug-in's included): registration, an
unknown setting refused in one line, a fit on one current level, the save / load round trip, the
per-sample step against ``predict``, a discrete-time step's own interval. Here each check is one
test per kind (the fits shared), plus the packing of every built-in step for the disk-cached
dispatch.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper import check_family, get_estimator
from mrdamper.conformance import (
    CHECKS,
    FS,
    check_discrete_step,
    check_round_trip,
    check_single_level,
    check_step_equals_predict,
    fit_quietly,
    model_step,
    probe_record,
    training_records,
)
from mrdamper.data import Experiment
from mrdamper.errors import ConformanceError
from mrdamper.models.base import Estimator, FittedModel
from tests.conftest import package_kinds

#: Settings that keep each fit short (the hysteretic LPV input with its stroke and share given,
#: so no candidate grid runs; one Spencer start).
FAST: dict[str, dict[str, Any]] = {
    "lpv": {"stroke": 1e-4, "blend": 0.5},
    "lti": {"stroke": 1e-4, "blend": 0.5},
    "spencer": {"n_starts": 1, "max_nfev": 20},
    "p15": {"max_nfev": 10},
}


def _estimator(kind: str) -> Estimator:
    return get_estimator(kind, **FAST.get(kind, {}))


@pytest.fixture(scope="module")
def training() -> list[Experiment]:
    return training_records()


@pytest.fixture(scope="module")
def fitted(training: list[Experiment]) -> dict[str, FittedModel]:
    """Each kind fitted once (lazily, on first use)."""
    return {}


def _model(kind: str, fitted: dict[str, FittedModel], training: list[Experiment]) -> FittedModel:
    if kind not in fitted:
        fitted[kind] = fit_quietly(_estimator(kind), training)
    return fitted[kind]


@pytest.fixture(scope="module")
def probe() -> Experiment:
    return probe_record()


KINDS = package_kinds()


@pytest.mark.parametrize("kind", KINDS)
def test_registered_and_unknown_setting_refused(kind: str) -> None:
    CHECKS["registered"](_estimator(kind))
    CHECKS["unknown_setting"](_estimator(kind))


@pytest.mark.parametrize("kind", KINDS)
def test_save_load_round_trip(
    kind: str,
    fitted: dict[str, FittedModel],
    training: list[Experiment],
    probe: Experiment,
    tmp_path: Path,
) -> None:
    check_round_trip(_model(kind, fitted, training), probe, tmp_path)


@pytest.mark.parametrize("kind", KINDS)
def test_the_model_records_the_interval_it_was_fitted_at(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment]
) -> None:
    # a discrete model's own interval, else the training records' (export's default --dt)
    model = _model(kind, fitted, training)
    assert model.sample_time == (1.0 / model.fs if hasattr(model, "fs") else 1.0 / FS)


@pytest.mark.parametrize("kind", KINDS)
def test_step_equals_predict(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    check_step_equals_predict(_model(kind, fitted, training), probe)


@pytest.mark.parametrize("kind", KINDS)
def test_discrete_step_refuses_another_interval(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    check_discrete_step(_model(kind, fitted, training), probe)


@pytest.mark.parametrize("kind", KINDS)
def test_single_level_fit_works_or_refuses_in_one_line(kind: str) -> None:
    check_single_level(_estimator(kind))


def test_a_check_that_fails_says_so(
    fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    # a predict that drifts from the step is caught; check_family names every failed check in
    # one line (a lax estimator that takes any setting is not the registered one either)
    model = _model("bingham", fitted, training)

    class Off(type(model)):  # type: ignore[misc]
        def predict(self, experiment: Experiment) -> np.ndarray:
            return super().predict(experiment) + 1.0

    bad = Off(**{f.name: getattr(model, f.name) for f in dataclasses.fields(model) if f.init})
    with pytest.raises(ConformanceError, match=r"^bingham: step_equals_predict: the step differs"):
        check_step_equals_predict(bad, probe)

    class Lax(type(_estimator("bingham"))):  # type: ignore[misc]
        @classmethod
        def from_settings(cls, **settings: Any) -> Estimator:
            return cls()

    failed = r"^bingham: registered: .*; unknown_setting: "
    with pytest.raises(ConformanceError, match=failed) as err:
        check_family(Lax)
    assert "\n" not in str(err.value)


def test_check_family_on_a_built_in_kind() -> None:
    report = check_family(_estimator("bingham"))
    assert report.kind == "bingham" and report.passed == tuple(CHECKS)
    assert list(report.to_frame()["status"]) == ["passed"] * len(CHECKS)


@pytest.mark.parametrize("kind", KINDS)
def test_step_packs_for_the_cached_dispatch(
    kind: str, fitted: dict[str, FittedModel], training: list[Experiment], probe: Experiment
) -> None:
    # every built-in family reaches the disk-cached kernels (models.step_dispatch): its packed
    # form, run through the dispatch, gives the force of its own step
    from mrdamper.models.step_dispatch import family_advance, family_force, pack

    model = _model(kind, fitted, training)
    model, step = model_step(model, probe)
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
