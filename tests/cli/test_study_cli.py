"""``mrdamper study`` and ``mrdamper demo`` end to end on tiny data (real estimators, real
readers)."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from mrdamper.cli.main import main


def _write_sine_folder(folder, fs: float = 200.0, duration: float = 3.0) -> None:
    """Quiroz-like constant-current sine records: two conditions x three currents."""
    folder.mkdir()
    t = np.arange(int(fs * duration)) / fs
    rng = np.random.default_rng(0)
    for amp_mm, freq in ((5, 2), (10, 1)):
        for cur in (0.0, 0.5, 1.0):
            x = amp_mm * 1e-3 * np.sin(2 * np.pi * freq * t)
            v = amp_mm * 1e-3 * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t)
            F = (
                (150 + 500 * cur) * np.tanh(v / 0.01 + x / 0.05)
                + 400 * v
                + 3 * rng.standard_normal(t.size)
            )
            pd.DataFrame({"t": t, "x": x, "v": v, "i": cur, "F": F}).to_csv(
                folder / f"sine_{amp_mm}mm_{freq}Hz_{cur:g}A.csv", index=False
            )


def _run(args, capsys):
    try:
        main(args)
        code = 0
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.slow
def test_study_on_a_folder_writes_report_and_prints_summary(tmp_path, capsys) -> None:
    data = tmp_path / "sine"
    _write_sine_folder(data)
    out = tmp_path / "out"
    code, stdout, stderr = _run(
        [
            "study",
            str(data),
            "--out",
            str(out),
            "--models",
            "sp2,sp3",
            "--workers",
            "1",
            "--no-progress",
        ],
        capsys,
    )
    assert code == 0, stderr
    assert "protocol 'quiroz-loco'" in stderr
    assert "sp2" in stdout and "sp3" in stdout and "Headline" in stdout
    assert f"Report: {out / 'report.html'}" in stdout.replace("\n", "")
    res = pd.read_csv(out / "results.csv")
    assert set(res["fold"]) == {"condition=5mm_2Hz", "condition=10mm_1Hz"}
    assert len(res) == 2 * 6 and set(res["status"]) == {"ok"}
    # every score is on a held-out condition
    roles = pd.read_csv(out / "roles.csv")
    for fold, grp in roles.groupby("fold"):
        assert set(grp.loc[grp.role == "train", "record"]).isdisjoint(
            grp.loc[grp.role == "score", "record"]
        )
    assert (out / "report.html").read_text().count("data:image/png;base64,") >= 7


def test_study_refuses_non_empty_out_before_computing(tmp_path, capsys) -> None:
    data = tmp_path / "sine"
    _write_sine_folder(data)
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("keep")
    code, _, stderr = _run(
        ["study", str(data), "--out", str(out), "--models", "sp2", "--workers", "1"], capsys
    )
    assert code == 2
    assert stderr.strip().count("\n") == 0 and "not empty; pass --force" in stderr
    assert (out / "old.txt").read_text() == "keep"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--models", "sp9"], "unknown kind(s) ['sp9']"),
        (["--protocol", "nope"], "protocol file not found"),
        (
            ["--workers", "1", "--scheduler", "tcp://127.0.0.1:1"],
            "--workers: not with --scheduler",
        ),
        (["--control-plant", "rig:nope"], "--control-plant: expected rig, rig:NAME"),
        (["--control-plant", "missing.json"], "or a model file, got 'missing.json'"),
    ],
)
def test_study_bad_options_one_line_errors(tmp_path, capsys, extra, message) -> None:
    data = tmp_path / "sine"
    _write_sine_folder(data)
    code, _, stderr = _run(["study", str(data), "--out", str(tmp_path / "o"), *extra], capsys)
    assert code == 2 and message in stderr and "Traceback" not in stderr


def test_study_with_a_protocol_file(tmp_path, capsys) -> None:
    data = tmp_path / "sine"
    _write_sine_folder(data)
    proto = tmp_path / "p.json"
    proto.write_text(
        json.dumps(
            {
                "name": "train-on-10mm",
                "train": {"match": {"condition": "10mm_1Hz"}},
                "score": {"match": {"condition": "5mm_2Hz"}},
                "models": [{"kind": "sp2", "label": "SP-2"}],
            }
        )
    )
    out = tmp_path / "out"
    code, _, stderr = _run(
        ["study", str(data), "--out", str(out), "--protocol", str(proto), "--workers", "1"], capsys
    )
    assert code == 0, stderr
    # off a terminal: one plain line per finished model and for the control step, no bars
    assert "\r" not in stderr and "\x1b" not in stderr and "fitting" not in stderr
    assert re.search(
        r"^study: SP-2: fitted on 1 of 1 fold\(s\), mean ESR [0-9.e-]+ over 3 record\(s\) "
        r"\(1 of 1\)$",
        stderr,
        re.MULTILINE,
    ), stderr
    assert re.search(
        r"^study: control relevance: the quarter-car loop in \d+ s$", stderr, re.MULTILINE
    )
    res = pd.read_csv(out / "results.csv")
    assert list(res["model"].unique()) == ["SP-2"] and len(res) == 3
    assert res["record"].str.startswith("sine_5mm").all()
    assert json.loads((out / "protocol.json").read_text())["name"] == "train-on-10mm"


@pytest.mark.slow
def test_study_on_a_dask_scheduler_address(tmp_path, capsys) -> None:
    distributed = pytest.importorskip("distributed")
    data = tmp_path / "sine"
    _write_sine_folder(data)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cl:
        code, _, stderr = _run(
            [
                "study",
                str(data),
                "--out",
                str(tmp_path / "out"),
                "--models",
                "sp2",
                "--scheduler",
                cl.scheduler_address,
                "--no-progress",
            ],
            capsys,
        )
    assert code == 0, stderr
    study = json.loads((tmp_path / "out" / "study.json").read_text())
    assert study["executor"] == f"Dask scheduler {cl.scheduler_address}"
    assert len(pd.read_csv(tmp_path / "out" / "results.csv")) == 6


@pytest.mark.slow
def test_demo_quick_on_the_virtual_rig(tmp_path, capsys, monkeypatch) -> None:
    doe = pytest.importorskip("mrdamper.rig.doe")
    try:
        from mrdamper.rig import reference_damper

        reference_damper()
    except (ImportError, FileNotFoundError) as exc:
        pytest.skip(f"virtual rig reference damper not installed: {exc}")
    assert doe is not None
    monkeypatch.chdir(tmp_path)
    code, stdout, stderr = _run(
        ["demo", "--scale", "0.1", "--models", "lti,sp2", "--workers", "1", "--no-progress"], capsys
    )
    assert code == 0, stderr
    out = tmp_path / "mrdamper-demo"
    assert (out / "report.html").exists() and "Headline" in stdout
    res = pd.read_csv(out / "results.csv")
    assert set(res["model"]) == {"lti", "sp2"}
    # second run refuses to overwrite, one line, exit 2
    code, _, stderr = _run(["demo", "--scale", "0.1", "--models", "sp2", "--workers", "1"], capsys)
    assert code == 2 and "pass --force" in stderr
    # with --force the same command runs again over its own outputs
    again = ["demo", "--scale", "0.1", "--models", "sp2", "--workers", "1", "--no-progress"]
    code, _, stderr = _run([*again, "--force"], capsys)
    assert code == 0, stderr
    assert set(pd.read_csv(out / "results.csv")["model"]) == {"sp2"}
