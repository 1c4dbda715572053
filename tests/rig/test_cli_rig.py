"""``mrdamper rig doe`` on the command line."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import mrdamper.cli.rig as cli_rig
from mrdamper.cli.main import main
from mrdamper.models.spencer import spencer1997
from mrdamper.rig.doe import record_seeds


@pytest.fixture()
def fast_damper(monkeypatch: pytest.MonkeyPatch, damper) -> None:  # type: ignore[no-untyped-def]
    # the CLI wiring is tested with the small test damper; damper resolution is tested below
    monkeypatch.setattr(cli_rig, "_damper", lambda spec: damper)


@pytest.mark.slow
def test_rig_doe_writes_files_and_refuses_to_overwrite(
    fast_damper: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "doe"
    main(["rig", "doe", "--out", str(out), "--seed", "3", "--scale", "0.07", "--fs", "200"])
    said = capsys.readouterr().out
    assert "61 records" in said and "manifest" in said
    table = pd.read_csv(out / "manifest.csv")
    assert len(table) == 61 and table["seed"].tolist() == record_seeds(3, 61)
    assert (out / "exp8_rep07.csv").exists()
    first = (out / "exp1_rep01.csv").read_bytes()
    with pytest.raises(SystemExit) as info:
        main(["rig", "doe", "--out", str(out), "--seed", "3", "--scale", "0.07", "--fs", "200"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "--force" in err and len(err.strip().splitlines()) == 1
    main(
        [
            "rig",
            "doe",
            "--out",
            str(out),
            "--seed",
            "3",
            "--scale",
            "0.07",
            "--fs",
            "200",
            "--force",
            "--workers",
            "2",
        ]
    )
    assert (out / "exp1_rep01.csv").read_bytes() == first


@pytest.mark.parametrize(
    "args, word",
    [
        (["--scale", "0.001"], "scale"),
        (["--fs", "-5"], "fs"),
        (["--damper", "nonsense"], "--damper"),
    ],
)
def test_rig_doe_bad_options_one_line_error(
    args: list[str], word: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as info:
        main(["rig", "doe", "--out", str(tmp_path / "o"), *args])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert word in err and len(err.strip().splitlines()) == 1


def test_damper_option_accepts_a_model_file(tmp_path: Path) -> None:
    path = spencer1997().save(tmp_path / "sp.json")
    loaded = cli_rig._damper(str(path))
    assert loaded.kind == "spencer" and loaded.input == "voltage"
    assert cli_rig._damper(None) is None


def test_rig_doe_parquet_reads_back_and_says_how_much(
    fast_damper: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("pyarrow")
    from mrdamper.rig.doe_io import read_doe

    csv_out, pq_out = tmp_path / "csv", tmp_path / "pq"
    main(["rig", "doe", "--out", str(csv_out), "--seed", "3", "--scale", "0.07", "--fs", "200"])
    main(
        [
            "rig",
            "doe",
            "--out",
            str(pq_out),
            "--seed",
            "3",
            "--scale",
            "0.07",
            "--fs",
            "200",
            "--format",
            "parquet",
            "--workers",
            "2",
        ]
    )
    said = capsys.readouterr().out
    files = sorted(pq_out.glob("*.parquet"))
    assert len(files) == 61 and not list(pq_out.glob("exp*.csv"))
    mb = sum(f.stat().st_size for f in files) / 1e6
    assert f"wrote 61 parquet files, {mb:.1f} MB" in said
    a, b = read_doe(csv_out), read_doe(pq_out)
    assert a.names == b.names
    for ra, rb in zip(a, b):
        assert rb.metadata["experiment"] == ra.metadata["experiment"]
        for ch in ("t", "x", "v", "i", "F"):
            assert getattr(ra, ch).tobytes() == getattr(rb, ch).tobytes()


def test_rig_doe_rejects_unknown_format(
    fast_damper: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        main(["rig", "doe", "--out", str(tmp_path / "x"), "--format", "hdf5", "--scale", "0.07"])
    err = capsys.readouterr().err
    assert "--format" in err and "parquet" in err
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_fit_reads_a_doe_folder_through_its_manifest(
    fast_damper: None, tmp_path: Path, capsys: pytest.CaptureFixture[str], fmt: str
) -> None:
    out = tmp_path / "doe"
    main(
        [
            "rig",
            "doe",
            "--out",
            str(out),
            "--scale",
            "0.07",
            "--fs",
            "200",
            "--format",
            fmt,
            "--no-progress",
        ]
    )
    capsys.readouterr()
    main(["fit", "bingham", str(out), "--out", str(tmp_path / "b.json")])
    said = capsys.readouterr().out
    assert "identified on 61 record(s)" in said  # the manifest is not read as a record


def test_study_reads_a_doe_folder_as_virtual_rig_records(fast_damper: None, tmp_path: Path) -> None:
    from mrdamper.data import read_records
    from mrdamper.rig.doe_io import is_doe_folder
    from mrdamper.study.runner import data_origin

    out = tmp_path / "doe"
    main(["rig", "doe", "--out", str(out), "--scale", "0.07", "--fs", "200", "--no-progress"])
    data = read_records(out)
    assert len(data) == 61 and all(e.metadata["source"] == "virtual rig" for e in data)
    assert data_origin(data).startswith("virtual rig")  # the report's captions follow this
    other = tmp_path / "mine"
    other.mkdir()
    (other / "manifest.csv").write_text("file,comment\nrec_a.csv,my own list\n")
    assert not is_doe_folder(other) and is_doe_folder(out)
