"""Protocols: selections, splits, presets, protocol files (JSON / TOML) and their errors."""

from __future__ import annotations

import json

import pytest

from mrdamper.errors import SchemaError
from mrdamper.study import (
    ModelSpec,
    Protocol,
    Selection,
    Split,
    doe_protocol,
    load_protocol,
    make_folds,
    protocol_from_dict,
)
from mrdamper.study.splits import roles_frame


def test_selection_match_take_and_globs(doe) -> None:
    sel = Selection(match={"experiment": [1, 2]}, group_by="experiment", take=2)
    assert sel.select(doe).names == ["exp1_rep01", "exp1_rep02", "exp2_rep01", "exp2_rep02"]
    assert Selection(names=("exp6_*",), exclude={"replicate": 1}).select(doe).names == [
        "exp6_rep02",
        "exp6_rep03",
    ]
    assert len(Selection().select(doe)) == len(doe)


def test_doe_default_protocol_never_scores_training_records(doe) -> None:
    (fold,) = make_folds(doe, doe_protocol())
    assert fold.analysis.names == ["exp6_rep01", "exp7_rep01", "exp8_rep01"]
    assert fold.train.names == ["exp1_rep01", "exp2_rep01", "exp3_rep01"]
    used = set(fold.train.names) | set(fold.analysis.names)
    assert used.isdisjoint(fold.score.names)
    assert len(fold.score) == len(doe) - len(used)
    roles = roles_frame([fold])
    assert set(roles["role"]) == {"analysis", "train", "score"}


def test_leave_one_group_out_and_time_split(doe) -> None:
    p = Protocol(
        train=Selection(), score=Selection(), split=Split("leave-one-group-out", key="experiment")
    )
    folds = make_folds(doe, p)
    assert [f.name for f in folds] == [f"experiment={k}" for k in (1, 2, 3, 6, 7, 8)]
    for f in folds:
        assert {e.metadata["experiment"] for e in f.score} == {int(f.name.split("=")[1])}
        assert set(f.train.names).isdisjoint(f.score.names)
    p = Protocol(
        train=Selection(names=("exp1_rep01",)),
        score=Selection(names=("exp1_rep01",)),
        split=Split("time", fraction=0.7),
    )
    (fold,) = make_folds(doe, p)
    tr, sc = fold.train[0], fold.score[0]
    assert tr.n + sc.n == doe["exp1_rep01"].n
    assert tr.t[-1] < sc.t[0]
    assert sc.name == "exp1_rep01[70%:]"


def test_empty_training_or_scoring_is_a_clear_error(doe) -> None:
    with pytest.raises(SchemaError, match="train: fold 'all' has no training record"):
        make_folds(doe, Protocol(train=Selection(match={"experiment": 99})))
    with pytest.raises(SchemaError, match="score: no record left to score"):
        make_folds(doe, Protocol(train=Selection(), score=Selection()))


def test_protocol_json_round_trip(tmp_path) -> None:
    p = doe_protocol(models=["lpv", ModelSpec("sp1", {"n_starts": 2}, label="SP-1")])
    path = tmp_path / "p.json"
    path.write_text(p.to_json())
    q = load_protocol(path)
    assert q.to_dict() == p.to_dict()
    assert q.models[1].settings["n_starts"] == 2 and q.models[1].label == "SP-1"


def test_protocol_toml_file(tmp_path) -> None:
    path = tmp_path / "p.toml"
    path.write_text(
        'name = "mine"\ninput = "i"\nmodels = ["sp2", {kind = "lti", label = "LTI-3", settings = '
        "{order = 3}}]\n[analysis]\nmatch = {experiment = [6, 7, 8]}\ngroup_by = "
        '"experiment"\ntake = 1\n[train]\nmatch = {pattern = ["ICPS", "APRBS"]}\n[split]\nkind = '
        '"leave-one-group-out"\nkey = "experiment"\n'
    )
    p = load_protocol(path)
    assert p.name == "mine" and p.split.key == "experiment"
    assert [m.label for m in p.models] == ["sp2", "LTI-3"]
    assert p.train.match["pattern"] == ("ICPS", "APRBS")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"trian": {}}, r"unknown key\(s\) \['trian'\]"),
        ({"split": {"kind": "random"}}, "split.kind: expected"),
        (
            {"split": {"kind": "time", "fraction": 1.5}},
            r"split.fraction: expected a number in \(0, 1\), got 1.5",
        ),
        ({"split": {"kind": "leave-one-group-out"}}, "split.key: leave-one-group-out needs"),
        ({"models": ["sp1", "sp1"]}, r"duplicate label\(s\) \['sp1'\]"),
        ({"models": [{"settings": {}}]}, "has no 'kind'"),
        ({"train": {"take": 2}}, "group_by: 'take' needs"),
        ({"train": {"take": 0, "group_by": "x"}}, "take: expected a positive integer, got 0"),
        ({"input": "current"}, "input: expected 'i' or 'voltage', got 'current'"),
        ({"range_policy": "maybe"}, "range_policy: expected"),
        ({"schema_version": 7}, "schema_version: expected 1, got 7"),
        ({"exclude_trained": "yes"}, "exclude_trained: expected true or false"),
    ],
)
def test_bad_protocol_files_name_the_key(data, message) -> None:
    with pytest.raises(SchemaError, match=message):
        protocol_from_dict(data)


def test_load_protocol_errors(tmp_path) -> None:
    with pytest.raises(FileNotFoundError, match="protocol file not found"):
        load_protocol(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(SchemaError, match="cannot parse protocol file"):
        load_protocol(bad)
    yaml = tmp_path / "p.yaml"
    yaml.write_text("name: x")
    with pytest.raises(SchemaError, match="must end in .json or .toml"):
        load_protocol(yaml)
    assert load_protocol("quiroz").split.key == "condition"
    assert json.loads(load_protocol("dyke").to_json())["input"] == "voltage"


def test_per_kind_settings_are_defaults_that_model_entries_override(tmp_path) -> None:
    p = Protocol(
        models=["lpv", ModelSpec("lpv", {"fs": 500.0}, label="lpv-500"), "sp1"],
        settings={"lpv": {"fs": 200.0, "n_m": 2}},
    )
    assert p.settings_for(p.models[0]) == {"fs": 200.0, "n_m": 2}
    assert p.settings_for(p.models[1]) == {"fs": 500.0, "n_m": 2}
    assert p.settings_for(p.models[2]) == {}
    path = tmp_path / "p.json"
    path.write_text(p.to_json())
    assert load_protocol(path).settings_for(load_protocol(path).models[1]) == {
        "fs": 500.0,
        "n_m": 2,
    }
    with pytest.raises(SchemaError, match="settings: expected a table"):
        protocol_from_dict({"settings": {"lpv": 3}})
    assert load_protocol("dyke").range_policy == "clip"
