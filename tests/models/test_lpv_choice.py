"""The hysteretic LPV input's ``stroke`` / ``blend`` chosen on held-out records
(:mod:`mrdamper.models.lpv.choice`): the inner split (every level kept, deterministic, the time
split of few records), the held-out and the beyond-envelope (default) choices against the
training choice on rig records, the fallback of records without a frequency band above the
others, the given choice records, and the refusals."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment
from mrdamper.data import ExperimentSet
from mrdamper.models.lpv import LPVEstimator, LPVModel
from mrdamper.models.lpv import choice as _choice
from mrdamper.models.lpv import inputs as _lpv_inputs

FS = 200.0


def _record(level: float, k: int, n: int = 400, metadata: bool = True, varying: bool = False):
    t = np.arange(n) / FS
    v = 0.1 * np.sin(2 * np.pi * (1.0 + 0.1 * k) * t)
    volts = 0.5 + 0.5 * np.sin(2 * np.pi * 0.3 * t) if varying else np.full(n, level)
    return Experiment(
        t=t,
        x=np.cumsum(v) / FS,
        v=v,
        F=1000.0 * v,
        voltage=volts,
        name=f"L{level}_{k}",
        metadata={"current": level} if metadata else {},
    )


def _fit(train, **options) -> LPVModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return LPVEstimator(**options.pop("settings", {})).fit(train, **options)


# ----------------------------------------------------------------------------- the inner split
def test_each_record_of_a_level_is_held_out_once_and_every_level_kept() -> None:
    # four levels, records interleaved; level 3 has only two records (never held out)
    recs = [_record(lev, k) for k in range(4) for lev in (0.0, 1.0, 2.0)]
    recs += [_record(3.0, k) for k in range(2)]
    folds = _choice.inner_splits(ExperimentSet(recs), "voltage")
    assert len(folds) == _choice.HOLD_EVERY and {f.how for f in folds} == {"records"}
    assert list(folds[2].held_out.names) == ["L0.0_2", "L1.0_2", "L2.0_2"]
    assert list(folds[0].held_out.names) == ["L0.0_0", "L1.0_0", "L2.0_0"] + [
        "L0.0_3",
        "L1.0_3",
        "L2.0_3",
    ]
    held = [n for f in folds for n in f.held_out.names]
    assert sorted(held) == sorted(e.name for e in recs if e.metadata["current"] != 3.0)
    for f in folds:
        kept = [e.metadata["current"] for e in f.fit]
        assert min(kept.count(lev) for lev in (0.0, 1.0, 2.0, 3.0)) >= 2
        assert len(f.fit) + len(f.held_out) == len(recs)
    # deterministic: the same records give the same folds
    again = _choice.inner_splits(ExperimentSet(recs), "voltage")
    assert [list(f.held_out.names) for f in again] == [list(f.held_out.names) for f in folds]


def test_levels_of_the_constant_input_when_no_record_carries_a_current() -> None:
    recs = [_record(lev, k, metadata=False) for lev in (0.0, 1.5) for k in range(3)]
    weights = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    fold = _choice.inner_splits(ExperimentSet(recs), "voltage", weights)[2]
    assert list(fold.held_out.names) == ["L0.0_2", "L1.5_2"]
    assert fold.held_out_weights == [3.0, 6.0]
    assert fold.fit_weights == [1.0, 2.0, 4.0, 5.0]


@pytest.mark.parametrize("n_records", [1, 3])
def test_few_records_hold_out_the_end_of_every_record(n_records: int) -> None:
    """One record, or three records of one group (folds of one held-out record are too few): the
    last 30 % of every record is held out, the first 70 % fits."""
    recs = [_record(0.0, k, n=1000, metadata=False, varying=True) for k in range(n_records)]
    (split,) = _choice.inner_splits(ExperimentSet(recs), "voltage")
    assert split.how == "time"
    assert [e.n for e in split.fit] == [700] * n_records
    assert [e.n for e in split.held_out] == [300] * n_records
    np.testing.assert_array_equal(split.held_out[0].t, recs[0].t[700:])
    assert split.record()["held_out"][0] == "L0.0_0[700:1000]"


# ----------------------------------------------------------------------------- the choice
def test_held_out_choice_generalises_where_the_training_choice_does_not(rig_data) -> None:
    """Rig sines at three currents: the held-out choice scores each candidate on three folds of
    records it did not fit (each record held out once), and picks a candidate that predicts a
    small-stroke chirp (never seen) better than the candidate the training fit picks."""
    train, test = rig_data
    held = _fit(train, settings={"choose_on": "held-out"})
    trained = _fit(train, settings={"choose_on": "training"})
    folds = held.provenance["hysteretic_held_out"]["folds"]
    assert folds[2]["held_out"] == ["s0.002_5.0_0.0", "s0.002_5.0_0.5", "s0.002_5.0_1.0"]
    assert sorted(n for f in folds for n in f["held_out"]) == sorted(e.name for e in train)
    rows = held.provenance["hysteretic_choice"]
    assert len(rows) == len(_lpv_inputs.STROKES) * len(_lpv_inputs.BLENDS)
    assert all(len(r["fold_esr"]) == 3 for r in rows)
    best = min(rows, key=lambda r: r["held_out_esr"])
    assert (held.stroke, held.blend) == (best["stroke"], best["blend"])
    assert "held-out" in held.provenance["hysteretic_note"]
    assert held.provenance["settings"]["choose_on"] == "held-out"
    assert trained.provenance["settings"]["choose_on"] == "training"
    assert held.provenance["n_samples"] == sum(e.n for e in train)  # refitted on every record
    # the training choice: scored on the training records, no split recorded
    assert "train_esr" in trained.provenance["hysteretic_choice"][0]
    assert "hysteretic_held_out" not in trained.provenance
    assert (held.stroke, held.blend) != (trained.stroke, trained.blend)
    assert held.score(test[0]).esr < 0.6 * trained.score(test[0]).esr


def test_beyond_choice_scores_on_held_out_records_and_the_highest_frequency_ones(
    rig_data,
) -> None:
    """The default: the three folds of held-out records plus one fold holding out the 5 Hz sines
    (every current), fitted on the others; the chosen candidate predicts the unseen 1-10 Hz chirp
    better than the one the training fit picks."""
    train, test = rig_data
    beyond = _fit(train)
    trained = _fit(train, settings={"choose_on": "training"})
    folds = beyond.provenance["hysteretic_held_out"]["folds"]
    assert len(folds) == _choice.HOLD_EVERY + 1
    assert "highest frequency held out" in folds[-1]["how"]
    assert folds[-1]["held_out"] == ["s0.002_5.0_0.0", "s0.002_5.0_0.5", "s0.002_5.0_1.0"]
    assert len(folds[-1]["inner_training"]) == 6
    rows = beyond.provenance["hysteretic_choice"]
    assert all(len(r["fold_esr"]) == _choice.HOLD_EVERY + 1 for r in rows)
    for r in rows:
        assert r["held_out_esr"] == pytest.approx(np.mean(r["fold_esr"]))
    best = min(rows, key=lambda r: r["held_out_esr"])
    assert (beyond.stroke, beyond.blend) == (best["stroke"], best["blend"])
    assert beyond.provenance["settings"]["choose_on"] == "beyond"
    assert "beyond the others' envelope" in beyond.provenance["hysteretic_note"]
    assert beyond.provenance["n_samples"] == sum(e.n for e in train)  # refitted on every record
    assert beyond.score(test[0]).esr < 0.6 * trained.score(test[0]).esr


def test_beyond_choice_falls_back_to_the_training_choice() -> None:
    """Records with neither folds of records (fewer than three per level) nor a band beyond the
    others that holds at most a third of them (one band; two conditions: the candidates would be
    fitted on one) are chosen on the training records."""
    same = ExperimentSet([_record(lev, 0, n=600) for lev in (0.0, 1.0, 0.5)])
    assert _choice.beyond_split(same) is None
    (split,) = _choice._choice_split(LPVEstimator(input="voltage"), same, None, None)
    assert split.how == "training"
    two = ExperimentSet([_record(lev, k, n=600) for k in (0, 5) for lev in (0.0, 1.0)])
    assert _choice.envelope_folds(two)  # a frequency fold exists: half of the records
    assert _choice.beyond_split(two) is None
    three = ExperimentSet([_record(lev, k, n=600) for k in (0, 3, 6) for lev in (0.0, 1.0)])
    split = _choice.beyond_split(three, record_weights=[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    assert split is not None and list(split.held_out.names) == ["L0.0_6", "L1.0_6"]
    assert split.held_out_weights == [5.0, 6.0] and split.fit_weights == [1.0, 2.0, 3.0, 4.0]


def test_one_record_is_chosen_on_the_training_fit() -> None:
    t = np.arange(2000) / FS
    v = 0.05 * np.sin(2 * np.pi * 1.0 * t) * np.where(t > 8.0, 2.0, 1.0)
    e = Experiment(t=t, x=np.cumsum(v) / FS, v=v, F=1000.0 * v, voltage=np.full(t.size, 1.0))
    assert _choice.envelope_folds(ExperimentSet([e]))  # a later block leaves the earlier range
    assert _choice.beyond_split(ExperimentSet([e])) is None


def test_given_choice_records_score_the_candidates(rig_data) -> None:
    train, test = rig_data
    m = _fit(train[:6], choice_records=test, settings={"choose_on": "held-out"})
    info = m.provenance["hysteretic_held_out"]
    assert info["held_out"] == ["chirp"] and info["inner_training"] == list(
        ExperimentSet(train[:6]).names
    )
    best = min(m.provenance["hysteretic_choice"], key=lambda r: r["held_out_esr"])
    assert (m.stroke, m.blend) == (best["stroke"], best["blend"])
    assert best["held_out_esr"] == pytest.approx(m.score(test[0]).esr, rel=0.5)
    assert m.provenance["training_records"] == list(ExperimentSet(train[:6]).names)


def test_refusals(rig_data) -> None:
    train, test = rig_data
    with pytest.raises(DataValidationError, match=r"^choose_on: .*'held-out'") as exc:
        LPVEstimator(choose_on="validation").fit(train)  # type: ignore[arg-type]
    assert "\n" not in str(exc.value)
    with pytest.raises(DataValidationError, match="^choice_records: .*choose_on='training'"):
        LPVEstimator(choose_on="training").fit(train, choice_records=test)
    with pytest.raises(DataValidationError, match="^choice_records: .*no setting is left open"):
        LPVEstimator(input_signal="u").fit(train, choice_records=test)
    with pytest.raises(DataValidationError, match="^choice_records: .*at least one record"):
        LPVEstimator(choose_on="held-out").fit(train, choice_records=[])


@pytest.mark.slow
def test_long_campaigns_choose_on_windows_of_both_parts(rig_data, monkeypatch) -> None:
    """Above the threshold the inner-training and held-out parts are both windowed; the model
    is fitted on every sample."""
    train, _ = rig_data
    monkeypatch.setattr(_choice, "CHOICE_THRESHOLD", 1000)
    monkeypatch.setattr(_choice, "CHOICE_BUDGET", 4000)
    m = _fit(train, settings={"choose_on": "held-out"})
    info = m.provenance["hysteretic_windows"]  # of the first fold
    assert info["windows"] == 6 and info["scored_on"]["windows"] == 3
    assert m.provenance["n_samples"] == sum(e.n for e in train)
    assert m.stroke in _lpv_inputs.STROKES
