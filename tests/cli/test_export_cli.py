"""``mrdamper export`` and ``mrdamper inverse`` on temporary files: outputs, refusals, one-line
errors."""

from __future__ import annotations

import json
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.io import loadmat

from mrdamper.cli.main import main
from mrdamper.control import state_space
from mrdamper.data import Experiment, write_csv
from mrdamper.models.base import decode_value
from mrdamper.models.lpv import LPVModel
from mrdamper.models.semiphenomenological import SP3Model

SP3 = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), f0=10.0, input_range=(0.0, 1.0))
LPV = LPVModel(
    alpha=np.array([[-1.2, 0.1, -0.02], [0.4, -0.05, 0.01]]),
    beta=np.array([[300.0, 500.0, -40.0], [-200.0, -300.0, 30.0]]),
    offset=5.0,
    fs=1000.0,
    input_signal="v",
    rho_range=(0.0, 1.0),
    input_range=(0.0, 1.0),
)


def _record(path: Path, model: object) -> Path:
    n = 2000
    t = np.arange(n) / 1000.0
    x = -0.008 * np.cos(2 * np.pi * 2.5 * t)
    v = 0.008 * 2 * np.pi * 2.5 * np.sin(2 * np.pi * 2.5 * t)
    i = np.repeat(np.random.default_rng(1).uniform(0.1, 0.9, n // 100), 100)
    e = Experiment(t=t, x=x, v=v, F=np.zeros(n), i=i, name="rec")
    e = e.replace(F=model.predict(e))  # type: ignore[attr-defined]
    return write_csv(e, path)


def _exit_code(args: list[str]) -> int:
    with pytest.raises(SystemExit) as info:
        main(args)
    return int(info.value.code)


def test_export_mat_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = LPV.save(tmp_path / "lpv.json")
    out = tmp_path / "lpv.mat"
    main(["export", str(model), "--out", str(out)])
    assert "lpv: wrote" in capsys.readouterr().out
    d = loadmat(out)
    A = (d["A_poly"] * 0.4 ** np.arange(3)).sum(-1)
    np.testing.assert_allclose(A, state_space(LPV, 0.4).A, rtol=1e-14)
    assert _exit_code(["export", str(model), "--out", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err
    js = tmp_path / "lpv_ss.json"
    main(["export", str(model), "--out", str(js)])
    d = decode_value(json.loads(js.read_text()))
    np.testing.assert_array_equal(d["C_poly"][0, :, 1], LPV.beta[::-1, 1])
    main(["export", str(model), "--out", str(out), "--format", "json", "--force"])
    assert json.loads(out.read_text())["schema"] == "mrdamper.lpv_export"


def test_export_refuses_static_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = SP3.save(tmp_path / "sp3.json")
    assert _exit_code(["export", str(model), "--out", str(tmp_path / "x.mat")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "'sp3'" in err and "'lpv'" in err
    assert not (tmp_path / "x.mat").exists()


@pytest.mark.parametrize("which", ["lpv", "sp3"])
def test_inverse_writes_current(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], which: str
) -> None:
    m = LPV if which == "lpv" else SP3
    model = m.save(tmp_path / "m.json")
    rec = _record(tmp_path / "rec.csv", m)
    out = tmp_path / "current.csv"
    main(["inverse", str(model), str(rec), "--out", str(out), "--method", "exact"])
    printed = capsys.readouterr().out
    assert "saturated; wrote" in printed
    assert "median |i error| over |v| > 20 % of peak" in printed and "ratio" in printed
    frame = pd.read_csv(out)
    assert list(frame.columns) == ["t", "F_desired", "i", "F_achieved", "saturated"]
    ok = frame["saturated"] == 0
    assert ok.mean() > 0.9
    scale = frame["F_desired"].abs().max()
    np.testing.assert_allclose(frame["F_achieved"][ok], frame["F_desired"][ok], atol=1e-5 * scale)
    assert frame["i"].between(0.0, 1.0).all()
    assert _exit_code(["inverse", str(model), str(rec), "--out", str(out)]) == 2


def test_inverse_default_is_regularised_and_prints_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = SP3.save(tmp_path / "m.json")
    rec = _record(tmp_path / "rec.csv", SP3)
    main(["inverse", str(model), str(rec), "--out", str(tmp_path / "o.csv"), "--rate", "20"])
    printed = capsys.readouterr().out
    assert "(regularised)" in printed
    err = float(printed.split("peak: ")[1].split(" A")[0])
    assert err < 0.05  # the record's current is piecewise constant in [0.1, 0.9] A
    frame = pd.read_csv(tmp_path / "o.csv")
    assert np.max(np.abs(np.diff(frame["i"]))) <= 20.0 / 1000.0 + 1e-12


def test_export_c(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = LPV.save(tmp_path / "lpv.json")
    main(
        [
            "export",
            str(model),
            "--format",
            "c",
            "--out",
            str(tmp_path / "c"),
            "--name",
            "lpv_damper",
        ]
    )
    assert "(C99)" in capsys.readouterr().out
    header = (tmp_path / "c" / "lpv_damper.h").read_text()
    assert "double lpv_damper_inverse_step(lpv_damper_state *s" in header
    assert (
        _exit_code(
            [
                "export",
                str(model),
                "--format",
                "c",
                "--out",
                str(tmp_path / "c"),
                "--name",
                "lpv_damper",
            ]
        )
        == 2
    )
    assert "already exists" in capsys.readouterr().err


def test_inverse_of_a_kind_without_an_inverse_form_runs_through_its_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mrdamper.models.lpv import LTIModel

    lti = LTIModel(
        alpha=LPV.alpha[:, :1],
        beta=LPV.beta[:, :1],
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )
    model = lti.save(tmp_path / "lti.json")
    rec = _record(tmp_path / "rec.csv", SP3)
    out = tmp_path / "o.csv"
    main(["inverse", str(model), str(rec), "--out", str(out)])
    table = pd.read_csv(out)
    assert len(table) > 0 and np.isfinite(table.select_dtypes("number").to_numpy()).all()
    capsys.readouterr()
    # the exact inverse needs an inverse form: refused in one line naming the kind
    args = ["inverse", str(model), str(rec), "--out", str(tmp_path / "x.csv"), "--method", "exact"]
    assert _exit_code(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "lti" in err


def test_inverse_horizon_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = SP3.save(tmp_path / "m.json")
    rec = _record(tmp_path / "rec.csv", SP3)
    assert (
        _exit_code(
            ["inverse", str(model), str(rec), "--out", str(tmp_path / "o.csv"), "--horizon", "-1"]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "horizon" in err
    assert not (tmp_path / "o.csv").exists()
    # no drive lag: the horizon has no use, and is refused rather than dropped
    args = ["inverse", str(model), str(rec), "--out", str(tmp_path / "o.csv"), "--horizon", "0.01"]
    assert _exit_code(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "horizon: a lead horizon is a setting" in err
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found")
def test_export_fmu(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from mrdamper.data import read_csv
    from mrdamper.models.semiphenomenological import SP3Estimator

    fitted = SP3Estimator().fit(read_csv(_record(tmp_path / "rec.csv", SP3)))
    model = fitted.save(tmp_path / "sp3.json")
    out = tmp_path / "damper.fmu"
    main(["export", str(model), "--out", str(out)])  # format from the suffix, dt from the fit
    assert "FMI 2.0 co-simulation" in capsys.readouterr().out
    with zipfile.ZipFile(out) as z:
        assert "binaries/linux64/damper.so" in z.namelist()
        assert 'stepSize="0.001"' in z.read("modelDescription.xml").decode()
    main(["export", str(model), "--out", str(tmp_path / "inv.fmu"), "--inverse"])
    assert _exit_code(["export", str(model), "--out", str(out)]) == 2  # exists
    assert "exists" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"schema": "something.else", "kind": "sp3"}))
    assert _exit_code(["export", str(bad), "--out", str(tmp_path / "b.fmu")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "schema" in err
    from mrdamper.models.phenomenological import P15Model

    p15 = P15Model(input_range=(0.0, 1.0)).save(tmp_path / "p15.json")
    assert _exit_code(["export", str(p15), "--out", str(tmp_path / "p.fmu")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "records no sample time it was fitted at" in err
    assert sorted(p.name for p in tmp_path.glob("*.fmu")) == ["damper.fmu", "inv.fmu"]
    assert not list(tmp_path.glob(".*part"))
