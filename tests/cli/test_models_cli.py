"""``mrdamper fit / simulate / score``: round trip on synthetic CSV files, refusals, one-line
errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mrdamper.cli.main import main
from mrdamper.data import Experiment, write_csv
from mrdamper.models import load_model
from mrdamper.models.phenomenological import P15Model
from mrdamper.models.semiphenomenological import SP3Model

TRUE = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), f0=10.0, input_range=(0.0, 1.0))


def _record(folder: Path, name: str, seed: int, n: int = 3000) -> Path:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 1000.0
    ph = rng.uniform(0, 2 * np.pi)
    x = 0.008 * np.sin(2 * np.pi * 2.5 * t + ph)
    v = 0.008 * 2 * np.pi * 2.5 * np.cos(2 * np.pi * 2.5 * t + ph)
    i = 0.5 + 0.5 * np.sin(2 * np.pi * 0.6 * t + seed)
    e = Experiment(t=t, x=x, v=v, F=np.zeros(n), i=i, name=name)
    e = e.replace(F=TRUE.predict(e))
    return write_csv(e, folder / f"{name}.csv")


@pytest.fixture()
def data_dir(tmp_path: Path) -> Path:
    d = tmp_path / "data"
    d.mkdir()
    for k in range(3):
        _record(d, f"rec{k}", seed=k)
    return d


def _exit_code(args: list[str]) -> int:
    with pytest.raises(SystemExit) as info:
        main(args)
    return int(info.value.code)


def test_fit_simulate_score_round_trip(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = tmp_path / "m.json"
    main(["fit", "sp3", str(data_dir), "--out", str(model), "--seed", "3", "--n-starts", "2"])
    assert "sp3: identified on 3 record(s)" in capsys.readouterr().out
    fitted = load_model(model)
    assert fitted.kind == "sp3" and fitted.provenance["settings"]["seed"] == 3
    np.testing.assert_allclose(fitted.S, TRUE.S, rtol=1e-6)

    pred = tmp_path / "pred.csv"
    main(["simulate", str(model), str(data_dir / "rec1.csv"), "--out", str(pred)])
    frame = pd.read_csv(pred)
    assert list(frame.columns) == ["t", "F", "F_pred"]
    np.testing.assert_allclose(frame["F_pred"], frame["F"], atol=1e-3 * frame["F"].abs().max())
    capsys.readouterr()

    main(["score", str(model), str(data_dir), "--json"])
    result = json.loads(capsys.readouterr().out)
    assert [r["record"] for r in result["records"]] == ["rec0", "rec1", "rec2"]
    assert result["mean"]["n_scored"] == 3 and result["mean"]["esr"] < 1e-9
    main(["score", str(model), str(data_dir / "rec0.csv")])
    table = capsys.readouterr().out
    assert "rec0" in table and "mean of 1" in table


def test_refuses_to_overwrite_without_force(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = tmp_path / "m.json"
    model.write_text("keep me")
    assert _exit_code(["fit", "sp2", str(data_dir), "--out", str(model)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "already exists" in err and "--force" in err
    assert model.read_text() == "keep me"
    # --force replaces only a file of the kind the command writes
    assert _exit_code(["fit", "sp2", str(data_dir), "--out", str(model), "--force"]) == 2
    assert "not a mrdamper model file" in capsys.readouterr().err
    assert model.read_text() == "keep me"
    model.unlink()
    main(["fit", "sp1", str(data_dir), "--out", str(model)])
    main(["fit", "sp2", str(data_dir), "--out", str(model), "--force"])
    assert load_model(model).kind == "sp2"

    pred = tmp_path / "pred.csv"
    pred.write_text("old")
    assert _exit_code(["simulate", str(model), str(data_dir / "rec0.csv"), "--out", str(pred)]) == 2
    assert pred.read_text() == "old"
    sim = ["simulate", str(model), str(data_dir / "rec0.csv"), "--out", str(pred), "--force"]
    assert _exit_code(sim) == 2 and pred.read_text() == "old"
    pred.unlink()
    main(sim[:-1])
    main(sim)
    assert pd.read_csv(pred).shape == (3000, 3)


def test_unknown_model_kind_is_one_line_exit_2(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _exit_code(["fit", "sp9", str(data_dir), "--out", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: model: unknown kind 'sp9'") and err.count("\n") == 1
    assert not (tmp_path / "m.json").exists()


def test_setting_the_model_does_not_take(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        _exit_code(["fit", "sp1", str(data_dir), "--out", str(tmp_path / "m.json"), "--n-m", "3"])
        == 2
    )
    err = capsys.readouterr().err
    assert "--n-m: model 'sp1' does not take the setting 'n_m'" in err and "n_starts" in err
    assert (
        _exit_code(
            ["fit", "p15", str(data_dir), "--out", str(tmp_path / "m.json"), "--set", "colour=red"]
        )
        == 2
    )
    assert "does not take the setting 'colour'" in capsys.readouterr().err


def test_generic_settings_reach_the_estimator(tmp_path: Path, data_dir: Path) -> None:
    model = tmp_path / "p.json"
    main(
        [
            "fit",
            "p15",
            str(data_dir),
            "--out",
            str(model),
            "--set",
            "form=monotone",
            "--set",
            "cutoff=50",
            "--no-offset",
        ]
    )
    fitted = load_model(model)
    assert isinstance(fitted, P15Model)
    assert fitted.provenance["settings"]["form"] == "monotone"
    assert fitted.provenance["settings"]["cutoff"] == 50
    assert fitted.f0 == 0.0


def test_score_reports_divergence_and_exits_1(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    W = np.zeros((5, 3))
    W[0, 0], W[1, 0], W[2, 0] = 1500.0, -1e-2, 2e-4  # w3 > 0: a growing mode
    bad = P15Model(W=tuple(W.ravel()), input_range=(0.0, 1.0), force_bound=3000.0, max_step=1e-4)
    path = bad.save(tmp_path / "bad.json")
    assert _exit_code(["score", str(path), str(data_dir), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["mean"]["n_diverged"] == 3 and result["mean"]["esr"] is None
    assert all(r["diverged_at_sample"] > 0 for r in result["records"])


def test_missing_data_path(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        _exit_code(["fit", "sp2", str(tmp_path / "nope"), "--out", str(tmp_path / "m.json")]) == 2
    )
    assert "no such file or folder" in capsys.readouterr().err


def test_options_are_the_estimator_setting_names() -> None:
    from mrdamper.cli.models import estimator_settings

    assert {"n_m", "n_rho"} <= set(estimator_settings("lpv"))
    assert "n_starts" in estimator_settings("sp1") and "form" in estimator_settings("p15")
    assert "max_nfev" in estimator_settings("narx") and "refine_max_nfev" not in (
        estimator_settings("narx")
    )


def test_an_lpv_stiffness_set_on_the_command_line_is_identified_and_reported(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.models.test_lpv_stiffness import K_X, _train

    data = tmp_path / "data"
    data.mkdir()
    for e in _train():
        write_csv(e, data / f"{e.name}.csv")
    model = tmp_path / "k.json"
    common = ["--n-m", "2", "--set", "input_signal=v", "--out"]
    main(["fit", "lpv", str(data), *common, str(model), "--set", "stiffness=identify"])
    said = capsys.readouterr().out
    fitted = load_model(model)
    assert fitted.stiffness == pytest.approx(K_X, rel=1e-3)
    assert f"stiffness k_x = {fitted.stiffness:.4g} N/m" in said
    main(["fit", "lpv", str(data), *common, str(tmp_path / "paper.json")])  # the default: none
    assert load_model(tmp_path / "paper.json").stiffness == 0.0
    assert "k_x" not in capsys.readouterr().out


def test_choice_records_on_the_command_line_decide_the_lpv_stiffness(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mrdamper.rig import VirtualRig, reference_damper
    from tests.models.test_lpv_stiffness import _stroke_test

    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=1000.0)
    t = np.arange(1250) / rig.fs
    x = 0.005 * np.sin(2 * np.pi * 2.0 * t) * np.clip(2.0 * t, 0.0, 1.0)
    train = [
        rig.run(x, np.full(t.size, c), seed=k, name=f"s{k}") for k, c in enumerate((0, 0.5, 1))
    ]
    train += [_stroke_test(level, 40 + k) for k, level in enumerate((0.0, 1.0))]
    data, held = tmp_path / "data", tmp_path / "held"
    for folder, recs in (
        (data, train),
        (held, [_stroke_test(lv, 50 + k) for k, lv in enumerate((0.0, 1.0))]),
    ):
        folder.mkdir()
        for e in recs:
            write_csv(e, folder / f"{e.name}.csv")
    model = tmp_path / "auto.json"
    main(
        [
            "fit",
            "lpv",
            str(data),
            "--set",
            "stroke=1e-4",
            "--choice-records",
            str(held),
            "--out",
            str(model),
        ]
    )
    fitted = load_model(model)
    # the reference damper's accumulator is 693 N/m; five short records place it within ~2x
    assert 300.0 < fitted.stiffness < 1500.0
    assert f"stiffness k_x = {fitted.stiffness:.4g} N/m" in capsys.readouterr().out
    assert fitted.provenance["hysteretic_held_out"]["held_out"] == ["stroke50", "stroke51"]
    with pytest.raises(SystemExit):
        main(
            [
                "fit",
                "sp1",
                str(data),
                "--choice-records",
                str(held),
                "--out",
                str(tmp_path / "s.json"),
            ]
        )
    err = capsys.readouterr().err
    assert "--choice-records" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "s.json").exists()
