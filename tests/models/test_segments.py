"""A training record longer than ``SEGMENT_SAMPLES`` is identified as consecutive segments.

The fit template cuts it (bounded work arrays whatever the record length); the model is the one
fitted on the segments given as separate records, a note says so and the provenance records it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mrdamper import Experiment, get_estimator
from mrdamper.errors import Note
from mrdamper.models import _scale
from mrdamper.rig import reference_damper
from tests.conftest import package_kinds

KINDS = package_kinds()
FAST = {"spencer": {"n_starts": 1, "max_nfev": 20}}
FS = 500.0
CAP = 1500


def _record(n: int, name: str, seed: int) -> Experiment:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    x = 0.006 * np.sin(2 * np.pi * 1.3 * t) + 0.003 * np.sin(2 * np.pi * 3.1 * t + 0.4)
    v = np.gradient(x, t)
    i = np.repeat(rng.uniform(0.0, 1.0, n // 250 + 1), 250)[:n]
    e = Experiment(t=t, x=x, v=v, F=np.zeros(n), i=i, name=name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return e.replace(F=reference_damper().predict(e) + rng.normal(0.0, 5.0, n))


@pytest.fixture(scope="module")
def records() -> list[Experiment]:
    return [_record(4000, "long", 1), _record(1200, "short", 2)]


def test_split_long_cuts_views_of_equal_length(records: list[Experiment]) -> None:
    from mrdamper.data import ExperimentSet

    exps = ExperimentSet(records)
    same, owners = _scale.split_long(exps, 5000)
    assert same is exps and owners == (0, 1)
    parts, owners = _scale.split_long(exps, CAP)
    assert [e.name for e in parts] == ["long [1/3]", "long [2/3]", "long [3/3]", "short"]
    assert owners == (0, 0, 0, 1)
    assert [e.n for e in parts] == [1333, 1334, 1333, 1200]
    np.testing.assert_array_equal(np.concatenate([e.F for e in parts[:3]]), records[0].F)
    assert np.shares_memory(parts[1].F, records[0].F)  # a view, not a copy


@pytest.mark.parametrize("kind", KINDS)
def test_long_record_is_fitted_as_its_segments(
    kind: str, records: list[Experiment], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_scale, "SEGMENT_SAMPLES", CAP)
    parts, _ = _scale.split_long(_as_set(records), CAP)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cut = get_estimator(kind, **FAST.get(kind, {})).fit(records)
        given = get_estimator(kind, **FAST.get(kind, {})).fit(list(parts))
    notes = [str(w.message) for w in caught if issubclass(w.category, Note)]
    assert any("'long' (4000 samples) is identified as 3 consecutive segments" in m for m in notes)
    assert cut.provenance["segments"] == {"long": 3}
    assert "segments" not in given.provenance
    test = _record(1000, "test", 3)
    np.testing.assert_array_equal(cut.predict(test), given.predict(test))


def test_record_weights_follow_their_record(
    records: list[Experiment], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_scale, "SEGMENT_SAMPLES", CAP)
    parts, _ = _scale.split_long(_as_set(records), CAP)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cut = get_estimator("lpv").fit(records, record_weights=[2.0, 0.5])
        given = get_estimator("lpv").fit(list(parts), record_weights=[2.0, 2.0, 2.0, 0.5])
    test = _record(1000, "test", 3)
    np.testing.assert_array_equal(cut.predict(test), given.predict(test))
    with pytest.raises(Exception, match="record_weights"):
        get_estimator("lpv").fit(records, record_weights=[1.0])


def _as_set(records: list[Experiment]):  # type: ignore[no-untyped-def]
    from mrdamper.data import ExperimentSet

    return ExperimentSet(records)
