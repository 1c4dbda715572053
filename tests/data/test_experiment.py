"""Validation of Experiment and ExperimentSet: each bad input gives the documented error."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment, ExperimentSet


def _rec(n: int = 100, name: str = "r", **meta: float) -> Experiment:
    t = np.arange(n) * 1e-3
    return Experiment(
        t=t, x=np.sin(t), v=np.cos(t), F=10 * np.cos(t), i=np.full(n, 0.5), name=name, metadata=meta
    )


def test_valid_record_properties() -> None:
    e = _rec(101)
    assert e.fs == pytest.approx(1000.0)
    assert e.duration == pytest.approx(0.1)
    assert e.channel_names == ("t", "x", "v", "i", "F")
    with pytest.raises(ValueError):
        e.F[0] = 1.0  # read-only


def test_input_arrays_are_copied() -> None:
    t = np.arange(10) * 1e-3
    F = np.ones(10)
    e = Experiment(t=t, x=t, v=t, F=F, i=t)
    F[0] = 99.0
    assert e.F[0] == 1.0


@pytest.mark.parametrize(
    ("change", "field", "text"),
    [
        ({"F": np.ones(99)}, "F", "has 99 samples"),
        ({"x": np.r_[np.nan, np.zeros(99)]}, "x", "non-finite"),
        ({"t": np.r_[0.0, np.arange(99) * 1e-3]}, "t", "strictly increasing"),
        ({"t": np.r_[np.arange(50) * 1e-3, 0.0505 + np.arange(50) * 1e-3]}, "t", "not uniform"),
        ({"i": None}, "i", "no electrical input"),
        ({"name": ""}, "name", "non-empty"),
        ({"v": np.zeros((100, 2))}, "v", "1-D"),
        ({"F": ["a"] * 100}, "F", "numbers"),
    ],
)
def test_bad_input_names_field(change: dict, field: str, text: str) -> None:
    t = np.arange(100) * 1e-3
    kw = {"t": t, "x": t, "v": t, "F": t, "i": t, "name": "r"}
    kw.update(change)
    with pytest.raises(DataValidationError, match=text) as info:
        Experiment(**kw)
    assert info.value.field == field


def test_nan_policies() -> None:
    t = np.arange(100) * 1e-3
    F = np.sin(50 * t)
    F[[0, 1, 40, 41]] = np.nan
    with pytest.raises(DataValidationError, match="non-finite"):
        Experiment.from_arrays(t=t, x=t, v=t, F=F, i=t)
    with pytest.raises(DataValidationError, match="non-finite"):
        Experiment.from_arrays(t=t, x=t, v=t, F=F, i=t, nan_policy="drop-edges")
    e = Experiment.from_arrays(t=t, x=t, v=t, F=F, i=t, nan_policy="interpolate")
    assert e.n == 98
    assert e.F[38] == pytest.approx(np.sin(50 * t[40]), abs=5e-3)
    with pytest.raises(DataValidationError, match="max_gap"):
        Experiment.from_arrays(t=t, x=t, v=t, F=F, i=t, nan_policy="interpolate", max_gap=1)
    with pytest.raises(DataValidationError, match="nan_policy"):
        Experiment.from_arrays(t=t, x=t, v=t, F=F, i=t, nan_policy="zero")  # type: ignore[arg-type]


def test_resample_non_uniform_time() -> None:
    t = np.sort(np.r_[np.arange(50) * 1e-3, 0.0505 + np.arange(50) * 1e-3])
    with pytest.raises(DataValidationError, match="not uniform"):
        Experiment.from_arrays(t=t, x=t, v=t, F=2 * t, i=t)
    e = Experiment.from_arrays(t=t, x=t, v=t, F=2 * t, i=t, resample_fs=1000.0)
    assert e.fs == pytest.approx(1000.0)
    np.testing.assert_allclose(e.F, 2 * e.t)
    assert "resampled" in e.metadata["repairs"][0]


def test_electrical_source_errors() -> None:
    t = np.arange(10) * 1e-3
    e = Experiment(t=t, x=t, v=t, F=t, voltage=t)
    assert e.electrical("voltage") is e.voltage
    with pytest.raises(DataValidationError, match="no 'i' channel"):
        e.electrical("i")
    # the channel a record carries: the current when it has one, else the voltage
    assert e.electrical_channel == "voltage" and "input='voltage'" in repr(e)
    both = Experiment(t=t, x=t, v=t, F=t, i=2 * t, voltage=t)
    assert both.electrical_channel == "i" and "input='i'" in repr(both)
    assert both.electrical(both.electrical_channel) is both.i


def test_set_filter_groups_split_logo() -> None:
    recs = [
        _rec(name=f"r{k}", current=c, condition=k % 3)
        for k, c in enumerate([0.0, 0.5, 0.5, 1.0, 1.0, 1.0])
    ]
    s = ExperimentSet(recs, name="s")
    assert s.filter(current=0.5).names == ["r1", "r2"]
    assert s.filter(current=[0.0, 1.0]).names == ["r0", "r3", "r4", "r5"]
    assert list(s.groups("current")) == [0.0, 0.5, 1.0]
    a, b = s.split((0.5, 0.5))
    assert a.names == ["r0", "r1", "r2"] and b.names == ["r3", "r4", "r5"]
    a1, _ = s.split((0.5, 0.5), seed=3)
    a2, _ = s.split((0.5, 0.5), seed=3)
    assert a1.names == a2.names
    folds = list(s.leave_one_group_out("condition"))
    assert len(folds) == 3
    for g, train, test in folds:
        assert set(train.names).isdisjoint(test.names)
        assert all(e.metadata["condition"] == g for e in test)
        assert len(train) + len(test) == 6
    assert s["r3"].name == "r3"
    with pytest.raises(DataValidationError, match="duplicate"):
        ExperimentSet([recs[0], recs[0]])


def test_pickle_round_trip_revalidates() -> None:
    import pickle

    e = _rec(name="p", current=0.5)
    back = pickle.loads(pickle.dumps(e))
    assert back.name == "p" and dict(back.metadata) == {"current": 0.5}
    assert np.array_equal(back.F, e.F) and not back.F.flags.writeable


def test_read_only_channels_are_shared_writable_ones_copied() -> None:
    import numpy as np

    from mrdamper.data import Experiment

    t = np.arange(100) * 1e-3
    e = Experiment(t=t, x=t.copy(), v=t.copy(), F=t.copy(), i=t.copy())
    assert not np.shares_memory(e.x, t) and not e.x.flags.writeable  # writable input: copied
    s = e.slice(10, 60)
    assert np.shares_memory(s.F, e.F)  # a slice of a record: no copy
    frozen = t.copy()
    frozen.setflags(write=False)
    view = frozen[::1]
    assert np.shares_memory(Experiment(t=t, x=view, v=t, F=t, i=t).x, frozen)
    base = t.copy()
    ro_view = base[:]
    ro_view.setflags(write=False)  # read-only view of a writable array: still copied
    e2 = Experiment(t=t, x=ro_view, v=t, F=t, i=t)
    assert not np.shares_memory(e2.x, base)
    base[0] = 99.0
    assert e2.x[0] == 0.0


def test_require_experiment_passes_a_record_and_names_the_field_otherwise() -> None:
    from mrdamper.data.experiment import require_experiment

    t = np.arange(4) / 100.0
    e = Experiment(t=t, x=0 * t, v=0 * t, F=0 * t, i=0 * t, name="r")
    assert require_experiment(e) is e
    with pytest.raises(DataValidationError, match=r"^experiment: expected an Experiment, got dict"):
        require_experiment({"t": t})
    with pytest.raises(DataValidationError, match=r"^record: expected an Experiment, got list"):
        require_experiment([e], "record")
