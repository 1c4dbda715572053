"""The FittedModel contract: JSON round trip, range policy, schema checks, atomic saving."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pytest

from mrdamper import Experiment, OutOfRangeError, OutputExistsError, SchemaError
from mrdamper.models import FittedModel, model_from_dict
from mrdamper.models.base import decode_value, encode_value


@dataclass(frozen=True)
class _Viscous(FittedModel):
    """Test double: F = c(i) * v with c polynomial in i."""

    kind: ClassVar[str] = "viscous-test"
    coefficients: np.ndarray = field(default_factory=lambda: np.array([100.0, 50.0]))

    def predict(self, experiment: Experiment) -> np.ndarray:
        i = self.electrical_input(experiment)
        return np.polyval(self.coefficients[::-1], i) * experiment.v


def _record(i_level: float = 0.5) -> Experiment:
    t = np.arange(1000) / 1000.0
    v = np.sin(2 * np.pi * 2 * t)
    return Experiment(
        t=t,
        x=-np.cos(2 * np.pi * 2 * t),
        v=v,
        F=(100 + 50 * i_level) * v,
        i=np.full(t.size, i_level),
    )


def test_predict_simulate_score() -> None:
    m = _Viscous(input_range=(0.0, 1.0))
    e = _record()
    sim = m.simulate(e)
    np.testing.assert_allclose(sim.F_pred, e.F)
    assert sim.scores.esr == pytest.approx(0.0, abs=1e-20)
    assert list(sim.to_frame().columns)[-1] == "F_pred"
    assert m.score(e).ssse == pytest.approx(0.0, abs=1e-12)


def test_range_policy() -> None:
    m = _Viscous(input_range=(0.0, 1.0))
    e = _record(1.5)
    with pytest.raises(OutOfRangeError, match=r"i: viscous-test was identified on \[0, 1\]"):
        m.predict(e)
    clipped = m.with_range_policy("clip").predict(e)
    np.testing.assert_allclose(clipped, 150 * e.v)
    with pytest.warns(RuntimeWarning, match="extrapolating"):
        m.with_range_policy("warn").predict(e)


def test_json_round_trip_bit_identical(tmp_path) -> None:
    coeffs = np.array([0.1 + 0.2, 1 / 3, np.pi * 1e-17])
    m = _Viscous(
        input_range=(0.0, 1.0), coefficients=coeffs, provenance={"records": ["a", "b"], "cost": 1.5}
    )
    d = m.to_dict()
    back = _Viscous.from_dict(json.loads(json.dumps(d)))
    assert np.array_equal(back.coefficients, coeffs)
    e = _record()
    assert np.array_equal(back.predict(e), m.predict(e))
    path = m.save(tmp_path / "m.json")
    with pytest.raises(OutputExistsError, match="already exists"):
        m.save(path)
    m.save(path, force=True)
    assert not list(tmp_path.glob("*.part"))


def test_schema_errors() -> None:
    d = _Viscous(input_range=(0.0, 1.0)).to_dict()
    with pytest.raises(SchemaError, match="schema_version"):
        _Viscous.from_dict({**d, "schema_version": 99})
    with pytest.raises(SchemaError, match="schema"):
        _Viscous.from_dict({**d, "schema": "other"})
    with pytest.raises(SchemaError, match="unknown field"):
        _Viscous.from_dict({**d, "parameters": {"bogus": 1.0}})
    with pytest.raises(SchemaError, match="unknown kind"):
        model_from_dict({**d, "kind": "no-such-model"})


def test_encode_decode_values() -> None:
    v = {"a": np.arange(6.0).reshape(2, 3), "b": [1.0, float("inf")], "c": np.float64(2.5)}
    back = decode_value(json.loads(json.dumps(encode_value(v))))
    assert np.array_equal(back["a"], v["a"]) and back["a"].shape == (2, 3)
    assert back["b"][1] == float("inf") and back["c"] == 2.5


def test_known_kinds_lists_every_family() -> None:
    from mrdamper.kinds import KINDS
    from mrdamper.models import known_kinds

    assert [row.kind for row in KINDS] == [
        "lpv",
        "p15",
        "sp1",
        "sp2",
        "sp3",
        "sp4",
        "lti",
        "spencer",
        "bingham",
        "narx",
        "tanh",
        "boucwen",
        "dahl",
        "lugre",
    ]
    assert known_kinds()[: len(KINDS)] == [row.kind for row in KINDS]


def test_sample_time_is_saved_and_old_files_still_load(tmp_path) -> None:
    m = _Viscous(input_range=(0.0, 1.0), sample_time=0.005)
    d = json.loads(json.dumps(m.to_dict()))
    assert d["schema_version"] == 2 and d["sample_time"] == 0.005
    assert _Viscous.from_dict(d).sample_time == 0.005
    old = {k: v for k, v in d.items() if k != "sample_time"} | {"schema_version": 1}
    back = _Viscous.from_dict(old)  # written before the field existed
    assert back.sample_time is None
    assert np.array_equal(back.predict(_record()), m.predict(_record()))
    for bad in (0.0, -1.0, "5 ms", True):
        with pytest.raises(SchemaError, match="^sample_time: expected a positive interval"):
            _Viscous.from_dict({**d, "sample_time": bad})
    with pytest.raises(ValueError, match="^sample_time: "):
        _Viscous(input_range=(0.0, 1.0), sample_time=float("nan"))


def test_fit_records_its_sample_time() -> None:
    """The largest training interval (records at 200 Hz and 1 kHz: 5 ms), the default step of
    the exports (a discrete model's own sample time: ``tests/models/test_conformance.py``)."""
    import warnings

    from mrdamper import get_estimator
    from mrdamper.control.export.fmu import fmu_sources

    fast = _record()
    slow = fast.replace(
        t=fast.t[::5], x=fast.x[::5], v=fast.v[::5], F=fast.F[::5], i=fast.i[::5], name="slow"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bingham = get_estimator("bingham").fit([fast, slow])
    assert bingham.sample_time == 0.005
    assert fmu_sources(bingham, "b")[1] == 0.005  # the FMU's default communication step
