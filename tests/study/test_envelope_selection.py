"""Validation beyond the training envelope: the folds that leave it, the stress test (bounded,
dissipative, no divergence beyond; no bursts inside), a kind that fails is not recommended and
the table says why, the recommendation states its envelope; the paper's LPV keeps its row."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd
import pytest

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.envelope import envelope_of, training_envelope
from mrdamper.models.envelope_folds import envelope_folds
from mrdamper.models.narx import NARXModel
from mrdamper.study import cross_validate
from mrdamper.study.protocol import Protocol
from mrdamper.study.selection import INTERPOLATION_ONLY, SCORE_COLUMNS, selection_from_scores
from mrdamper.study.stress import StressResult, stress_motions, stress_test
from mrdamper.study.tables import headlines

TRUTH = BinghamModel(
    fc=(100.0, 400.0, -50.0), c0=(800.0, 1500.0, 0.0), f0=5.0, v_eps=0.0, input_range=(0.0, 1.0)
)


def _sine(amp: float, freq: float, level: float, n: int = 1500, name: str = "") -> Experiment:
    t = np.arange(n) / 500.0
    x = amp * np.sin(2 * np.pi * freq * t)
    v = amp * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t)
    e = Experiment(
        t=t,
        x=x,
        v=v,
        F=np.zeros(n),
        i=np.full(n, level),
        name=name or f"a{amp * 1e3:g}_f{freq:g}_{level:g}",
    )
    return e.replace(F=TRUTH.predict(e))


def _with_envelope(model, records):
    env = envelope_of(
        [e.x for e in records],
        [e.v for e in records],
        [e.i for e in records],
        [e.F for e in records],
        [e.dt for e in records],
    )
    return dataclasses.replace(model, provenance={"envelope": env, "record_dt": [0.002]})


def test_envelope_folds_hold_out_the_largest_amplitude_and_highest_frequency() -> None:
    # 30 s records: several cycles of the slowest sine, so that its frequency band is its own
    recs = ExperimentSet(
        [
            _sine(a, f, lev, n=15000)
            for a, f in ((0.02, 0.5), (0.01, 1.0), (0.004, 3.0))
            for lev in (0, 1)
        ]
    )
    folds = envelope_folds(recs)
    assert [label.split(" held")[0] for label, _, _ in folds] == [
        "beyond: largest amplitude",
        "beyond: highest frequency",
    ]
    (_, tr_a, te_a), (_, tr_f, te_f) = folds
    assert set(te_a.names) == {"a20_f0.5_0", "a20_f0.5_1"}
    assert max(np.ptp(e.x) for e in tr_a) < min(np.ptp(e.x) for e in te_a)
    assert set(te_f.names) == {"a4_f3_0", "a4_f3_1"} and not set(tr_f.names) & set(te_f.names)
    # the slowest records are the largest too: no second fold holds them out; slower ones of
    # another amplitude get their own "lowest frequency" fold
    slow = ExperimentSet([*recs, *(_sine(0.006, 0.2, lev, n=15000) for lev in (0, 1))])
    labels = [label for label, _, _ in envelope_folds(slow)]
    assert labels[-1].startswith("beyond: lowest frequency held out (0.2")
    (_, tr_s, te_s) = envelope_folds(slow)[-1]
    assert set(te_s.names) == {"a6_f0.2_0", "a6_f0.2_1"} and len(tr_s) == len(recs)
    # records that share one envelope: no fold leaves it
    same = ExperimentSet([_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)])
    assert envelope_folds(same) == []


def test_one_record_whose_later_part_grows_gets_a_later_block_fold() -> None:
    t = np.arange(5000) / 500.0
    amp = np.where(t < 7.0, 0.01, 0.017)
    x = amp * np.sin(2 * np.pi * t)
    e = Experiment(t=t, x=x, v=np.gradient(x, t), F=np.zeros_like(t), i=np.full(t.size, 0.5))
    e = e.replace(F=TRUTH.predict(e), name="grow")
    ((label, train, test),) = envelope_folds(ExperimentSet([e]))
    assert label.startswith("beyond: later block") and "1.7" in label
    assert np.max(np.abs(test[0].x)) > 1.5 * np.max(np.abs(train[0].x))
    assert train[0].n + test[0].n == e.n
    steady = e.slice(0, 3000, name="steady")
    assert envelope_folds(ExperimentSet([steady])) == []


def test_stress_test_passes_a_sound_model_and_builds_its_motions() -> None:
    recs = [_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)]
    model = _with_envelope(TRUTH, recs)
    motions = stress_motions(model, recs)
    groups = [m.metadata["group"] for m in motions]
    assert groups.count("beyond") == 4 and groups.count("inside") >= 2
    beyond = [m for m in motions if m.metadata["group"] == "beyond"]
    assert max(np.max(np.abs(m.x)) for m in beyond) == pytest.approx(0.015, rel=0.01)
    rnd = motions[-1]
    assert rnd.x[0] == pytest.approx(0.0, abs=1e-9) and rnd.v[0] == pytest.approx(0.0, abs=1e-3)
    assert np.max(np.abs(rnd.v)) <= 0.0629 and np.ptp(rnd.x) <= 0.02 + 1e-9
    res = stress_test(model, recs)
    assert res.passed and res.reason == "ok"
    assert (res.table.loc[res.table["group"] == "beyond", "mean_power_W"] > 0).all()


def test_stress_levels_are_the_core_of_the_input_range_not_a_drive_spike() -> None:
    """A switching transient of a few samples (a drive's overshoot) sets the range's ends but
    is not a level the damper ran at: the stress motions hold the ends of the 99 % core."""
    recs = [_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)]
    i = recs[0].i.copy()
    i[100:103] = -0.4
    recs[0] = recs[0].replace(i=i)
    env = training_envelope(recs, [r.i for r in recs])
    assert env["e_range"][0] == -0.4 and env["e_core_range"] == [0.0, 1.0]
    model = dataclasses.replace(TRUTH, provenance={"envelope": env, "record_dt": [0.002]})
    beyond = [m for m in stress_motions(model, recs) if m.metadata["group"] == "beyond"]
    assert {float(m.i[0]) for m in beyond} == {0.0, 1.0}
    # a model saved before the core range was recorded keeps the full range
    old = {k: v for k, v in env.items() if k != "e_core_range"}
    model = dataclasses.replace(TRUTH, provenance={"envelope": old, "record_dt": [0.002]})
    beyond = [m for m in stress_motions(model, recs) if m.metadata["group"] == "beyond"]
    assert {float(m.i[0]) for m in beyond} == {-0.4, 1.0}


def test_stress_test_fails_a_model_that_bursts_or_diverges() -> None:
    recs = [_sine(0.01, 1.0, lev) for lev in (0.0, 0.5, 1.0)]
    unstable = NARXModel(  # F[k] = 1.02 F[k-1] + c v[k]: grows without bound
        fs=500.0,
        base=[[0, 1], [2, 0]],
        terms=[[0], [1]],
        theta=[1.02, 0.5],
        scales=[1000.0, 0.01, 0.1, 1.0, 1.0],
        v0=0.005,
        force_bound=1e5,
        input_range=(0.0, 1.0),
    )
    res = stress_test(_with_envelope(unstable, recs), recs)
    assert not res.passed
    assert any(w for w in res.table["why"]) and res.reason.split(":")[0] in {
        "SimulationDivergedError",
        "unbounded",
        "burst",
        "growing",
    }


def test_a_kind_that_fails_the_stress_test_is_not_recommended_and_the_table_says_why() -> None:
    rows = [
        {"model": m, "fold": f"c{k}", "record": f"r{k}", "esr": esr, "clipped": False, "error": ""}
        for m, esr in (("p15", 0.01), ("sp1", 0.02))
        for k in range(3)
    ]
    rows += [
        {"model": "p15", "fold": "beyond: x", "record": "big", "esr": 0.5, "clipped": False,
         "error": "", "beyond": True},
        {"model": "sp1", "fold": "beyond: x", "record": "big", "esr": 0.03, "clipped": False,
         "error": "", "beyond": True},
    ]  # fmt: skip
    scores = pd.DataFrame(rows, columns=list(SCORE_COLUMNS))
    ok = StressResult(pd.DataFrame(), True, "ok")
    bad = StressResult(pd.DataFrame(), False, "burst: peak 3 x the largest training force (x)")
    res = selection_from_scores(
        scores, ["p15", "sp1"], {}, "condition", 3, stress={"p15": bad, "sp1": ok},
        envelope="|v| <= 0.1 m/s",
    )  # fmt: skip
    assert res.recommended == "sp1" and res.n_beyond == 1
    assert res.table.loc["p15", "status"].startswith("not recommended: stress test: burst")
    assert res.table.loc["sp1", "rank_esr"] == pytest.approx(0.5 * (0.02 + 0.03))
    assert "Validated within |v| <= 0.1 m/s" in res.reason and "p15" in res.reason
    # without the stress failure, the beyond-envelope fold alone ranks sp1 first
    res2 = selection_from_scores(scores, ["p15", "sp1"], {}, "condition", 3)
    assert res2.recommended == "sp1" and res2.table.loc["p15", "status"] == "eligible"
    # the study's scores (no 'beyond' column) are all inside the envelope
    study = scores[~scores["beyond"].eq(True)].drop(columns="beyond")
    inside = selection_from_scores(study, ["p15", "sp1"], {}, "c", 3)
    assert inside.recommended == "p15" and inside.n_beyond == 0


def test_an_interpolation_only_kind_is_not_recommended_when_validated_beyond() -> None:
    """NARX best everywhere: scored and shown, but recommended only when the selection stays
    inside the training envelope."""
    rows = [
        {"model": m, "fold": f, "record": "r", "esr": esr, "clipped": False, "error": "",
         "beyond": f.startswith("beyond")}
        for m, esr in (("narx", 0.01), ("sp1", 0.02))
        for f in ("c0", "c1", "beyond: x")
    ]  # fmt: skip
    scores = pd.DataFrame(rows, columns=list(SCORE_COLUMNS))
    res = selection_from_scores(scores, ["narx", "sp1"], {}, "condition", 2)
    assert res.recommended == "sp1"
    assert res.table.loc["narx", "status"] == f"not recommended: {INTERPOLATION_ONLY}"
    assert res.table.loc["narx", "rank_esr"] < res.table.loc["sp1", "rank_esr"]
    ok = StressResult(pd.DataFrame(), True, "ok")
    inside = scores[~scores["beyond"]]
    stressed = selection_from_scores(inside, ["narx", "sp1"], {}, "c", 2, stress={"narx": ok})
    assert stressed.recommended == "sp1"
    assert selection_from_scores(inside, ["narx", "sp1"], {}, "c", 2).recommended == "narx"


def test_cross_validate_scores_beyond_the_envelope_and_stress_tests() -> None:
    recs = [_sine(a, f, lev) for a, f in ((0.02, 0.5), (0.01, 1.0)) for lev in (0.0, 0.5, 1.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = cross_validate(recs, models=["bingham"], n_folds=2)
    assert res.n_beyond >= 1 and res.scores["beyond"].any()
    assert res.table.loc["bingham", "stress"] == "ok" and res.recommended == "bingham"
    assert "Validated within |v| <= " in res.reason and "stress motions" in res.reason
    quick = cross_validate(recs, models=["bingham"], n_folds=2, beyond=False, stress=False)
    assert quick.n_beyond == 0 and quick.table.loc["bingham", "stress"] == "-"


def test_the_default_model_set_has_the_papers_lpv_beside_the_default_one() -> None:
    labels = [(s.label, s.kind, dict(s.settings)) for s in Protocol().resolved_models()]
    names = [lab for lab, _, _ in labels]
    assert names.index("lpv-paper") == names.index("lpv") + 1
    assert labels[names.index("lpv-paper")][1:] == ("lpv", {"input_signal": "u"})
    summary = pd.DataFrame(
        {
            "model": ["lpv", "lpv-paper", "sp1"],
            "kind": ["lpv", "lpv", "sp1"],
            "esr_mean": [0.02, 0.03, 0.06],
            "ssse_mean": [10.0, 12.0, 20.0],
        }
    )
    first, second = headlines(summary)
    assert first["model"] == "lpv-paper" and second["model"] == "lpv"
    assert first["esr_improvement_pct"] == pytest.approx(50.0)
    assert [h["model"] for h in headlines(summary[summary["model"] != "lpv-paper"])] == ["lpv"]


def test_the_report_says_which_input_each_lpv_uses() -> None:
    from mrdamper.study.protocol import ModelSpec
    from mrdamper.study.report import _model_text

    p = Protocol()
    paper = _model_text(p, ModelSpec("lpv", {"input_signal": "u"}, "lpv-paper"))
    default = _model_text(p, ModelSpec("lpv"))
    assert paper.startswith("lpv-paper (lpv, input_signal='u', input: static zone-law input u")
    assert default == "lpv (input: zone-law input with a hysteretic pre-yield state (default))"
    stiff = _model_text(p, ModelSpec("lpv", {"stiffness": "identify"}))
    assert stiff.endswith("; parallel stiffness k_x identified)")
    assert _model_text(p, ModelSpec("sp1")) == "sp1"
