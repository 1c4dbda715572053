"""The mistakes a new user makes, one test per case: every one ends in a working command, a note,
or a one-line error naming the field — never a traceback, a lost file or a silent wrong answer.

Most cases run the command line in-process (:func:`mrdamper.cli.main.main`) on small synthetic
records in a temporary folder; the cases about the shared measured data skip where it is absent.
"""

from __future__ import annotations

import errno
import json
import os
import re
import stat
import tomllib
import typing
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import typer

from mrdamper.cli.main import app, main
from mrdamper.data import Experiment, write_csv
from mrdamper.models.lpv import LPVModel

REPO = Path(__file__).resolve().parents[1]
FS = 200.0


# ----------------------------------------------------------------------------- helpers
def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        main(args)
        code = 0
    except SystemExit as exc:
        code = int(exc.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


def _one_line_error(code: int, err: str, expected_code: int = 2) -> str:
    assert code == expected_code, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and "Traceback" not in err
    return lines[0]


def _sine(
    name: str,
    cur: float,
    fs: float = FS,
    seconds: float = 4.0,
    amp: float = 0.01,
    freq: float = 1.5,
    seed: int = 0,
) -> Experiment:
    t = np.arange(int(fs * seconds)) / fs
    x = amp * np.sin(2 * np.pi * freq * t)
    v = amp * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t)
    F = (150 + 500 * cur) * np.tanh(v / 0.01 + x / 0.05) + 400 * v
    F = F + 2.0 * np.random.default_rng(seed).standard_normal(t.size)
    return Experiment(t=t, x=x, v=v, F=F, i=np.full(t.size, cur), name=name)


def _folder(
    path: Path, currents: tuple[float, ...] = (0.0, 0.5, 1.0), fs: tuple[float, ...] | None = None
) -> Path:
    """Records named with no convention (rec_a.csv, ...): the user's own data."""
    path.mkdir(parents=True)
    rates = fs or (FS,) * len(currents)
    for k, (cur, rate) in enumerate(zip(currents, rates)):
        write_csv(
            _sine(f"rec_{chr(97 + k)}", cur, fs=rate, seed=k), path / f"rec_{chr(97 + k)}.csv"
        )
    return path


def _lpv_model() -> LPVModel:
    return LPVModel(
        alpha=np.array([[-1.2, 0.1, -0.02], [0.4, -0.05, 0.01]]),
        beta=np.array([[300.0, 500.0, -40.0], [-200.0, -300.0, 30.0]]),
        offset=5.0,
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )


# ----------------------------------------------------------------------------- documented commands
def test_fit_on_records_of_different_rates_takes_the_lowest_rate_or_the_kinds_minimum(
    tmp_path, capsys
) -> None:
    data = _folder(tmp_path / "mixed", currents=(0.0, 0.5, 1.0, 0.25), fs=(FS, FS, 1000.0, 1000.0))
    for kind in ("lpv", "lti", "narx"):
        # the rate rule is under test, not stability: an unrefined LPV / LTI may be frozen-unstable
        extra = ["--set", "stability=warn"] if kind in ("lpv", "lti") else []
        code, _out, err = _run(
            [
                "fit",
                kind,
                str(data),
                "--out",
                str(tmp_path / f"{kind}.json"),
                "--no-refine",
                *extra,
            ],
            capsys,
        )
        assert code == 0, err
        notes = [ln for ln in err.splitlines() if ln.startswith("note: ")]
        saved = json.loads((tmp_path / f"{kind}.json").read_text())
        if kind == "narx":
            assert len(notes) == 1 and "model_fs = 200 Hz (the lowest" in notes[0], err
            assert saved["parameters"]["fs"] == FS
        else:  # the LPV family runs at 500 Hz at least: the 200 Hz records are up-sampled
            assert len(notes) == 1 and "model_fs = 500 Hz (the kind's lowest" in notes[0], err
            assert "records at 200 Hz are up-sampled" in notes[0], err
            assert saved["parameters"]["fs"] == 500.0


def test_rounded_time_column_is_read_with_the_estimated_rate(tmp_path, capsys) -> None:
    e = _sine("r", 0.5, fs=3004.8, seconds=2.0)
    df = e.to_frame()
    df["t"] = [
        float(f"{v:.6g}") for v in df["t"]
    ]  # printed with 6 digits, as the Dyke file: jitter
    p = tmp_path / "rounded.csv"
    df.to_csv(p, index=False)
    code, out, err = _run(["info", str(p), "--json"], capsys)
    assert code == 0, err
    [row] = json.loads(out)
    assert row["rate_hz"] == pytest.approx(3004.8)
    notes = [ln for ln in err.splitlines() if ln.strip()]
    assert (
        len(notes) == 1
        and notes[0].startswith("note: ")
        and "rate estimated as 3004.8 Hz" in notes[0]
    )


def test_dyke_record_reads_without_fs(dyke_csv, capsys) -> None:
    code, out, err = _run(["info", str(dyke_csv), "--json"], capsys)
    assert code == 0, err
    assert json.loads(out)[0]["rate_hz"] == pytest.approx(3004.8) and "note: " in err


def test_inverse_resamples_a_record_at_another_rate_like_simulate(tmp_path, capsys) -> None:
    model = tmp_path / "lpv.json"
    _lpv_model().save(model)
    rec = _sine("fast", 0.5, fs=1000.0)
    rec = rec.replace(F=_lpv_model().predict(rec))
    data = write_csv(rec, tmp_path / "fast.csv")
    code, _, err = _run(
        ["simulate", str(model), str(data), "--out", str(tmp_path / "sim.csv")], capsys
    )
    assert code == 0, err
    code, _out, err = _run(
        ["inverse", str(model), str(data), "--out", str(tmp_path / "cur.csv")], capsys
    )
    assert code == 0, err
    assert "note: " in err and "solved at the model rate" in err
    assert len(pd.read_csv(tmp_path / "cur.csv")) == rec.n


def test_model_rate_setting_is_model_fs_and_old_fs_still_works(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    code, _, err = _run(
        ["fit", "lti", str(data), "--out", str(tmp_path / "a.json"), "--set", "fs=100"], capsys
    )
    assert code == 0, err
    assert "note: " in err and "now called 'model_fs'" in err
    assert json.loads((tmp_path / "a.json").read_text())["parameters"]["fs"] == 100.0
    code, _, err = _run(
        ["fit", "lti", str(data), "--out", str(tmp_path / "b.json"), "--set", "model_fs=100"],
        capsys,
    )
    assert code == 0 and "note" not in err, err
    code, _, err = _run(
        ["fit", "sp1", str(data), "--out", str(tmp_path / "c.json"), "--set", "model_fs=100"],
        capsys,
    )
    assert "'model_fs'" in _one_line_error(code, err)
    # the record-rate option used for the model's rate: the message points to the model setting
    code, _, err = _run(
        ["fit", "lti", str(data), "--out", str(tmp_path / "d.json"), "--fs", "100"], capsys
    )
    assert "--set model_fs=" in _one_line_error(code, err)


@pytest.mark.slow
def test_every_record_reading_command_takes_the_reader_options(tmp_path, capsys) -> None:
    from mrdamper.cli._records import READER_OPTIONS

    group: Any = typer.main.get_command(app)
    readers = {"info", "fit", "simulate", "score", "study", "inverse"}
    for name in readers:
        opts = {p.name for p in group.commands[name].params}
        assert set(READER_OPTIONS) <= opts, (name, set(READER_OPTIONS) - opts)
    # a semicolon-separated file with a decimal comma, read by fit and score through the options
    df = _sine("comma", 0.5).to_frame()
    p = tmp_path / "comma.csv"
    df.to_csv(p, index=False, sep=";", decimal=",")
    code, _, err = _run(["fit", "sp1", str(p), "--out", str(tmp_path / "m.json")], capsys)
    assert "--decimal" in _one_line_error(code, err)
    data = _folder(tmp_path / "d")
    code, _, err = _run(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")], capsys)
    assert code == 0, err
    code, out, err = _run(
        ["score", str(tmp_path / "m.json"), str(p), "--decimal", ",", "--sep", ";", "--json"],
        capsys,
    )
    assert code == 0, err
    assert json.loads(out)["mean"]["n_scored"] == 1


@pytest.mark.slow
def test_study_on_own_records_runs_a_default_protocol_and_says_which(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "mine", currents=(0.0, 0.25, 0.5, 0.75, 1.0))
    out = tmp_path / "out"
    code, _stdout, err = _run(
        [
            "study",
            str(data),
            "--out",
            str(out),
            "--models",
            "sp2",
            "--workers",
            "1",
            "--no-progress",
        ],
        capsys,
    )
    assert code == 0, err
    chosen = [ln for ln in err.splitlines() if "protocol 'default'" in ln]
    assert (
        len(chosen) == 1
        and "5-fold by record" in chosen[0]
        and "force-velocity analysis" in chosen[0]
    )
    res = pd.read_csv(out / "results.csv")
    assert len(res) == 5 and set(res["status"]) == {"ok"}
    # one long record: a time split
    single = tmp_path / "one"
    single.mkdir()
    write_csv(_sine("long", 0.5, seconds=8.0), single / "long.csv")
    code, _, err = _run(
        [
            "study",
            str(single / "long.csv"),
            "--out",
            str(tmp_path / "o2"),
            "--models",
            "bingham",
            "--workers",
            "1",
            "--no-progress",
        ],
        capsys,
    )
    assert code == 0, err
    assert "first 70% trains" in err


# ----------------------------------------------------------------------------- usage errors
def _leaf_commands() -> list[tuple[list[str], Any]]:
    root = typer.main.get_command(app)
    out: list[tuple[list[str], Any]] = []

    def walk(cmd: Any, path: list[str]) -> None:
        if hasattr(cmd, "commands"):  # a group (Typer bundles its own click classes)
            for name, sub in cmd.commands.items():
                walk(sub, [*path, name])
        else:
            out.append((path, cmd))

    walk(root, [])
    return out


LEAVES = _leaf_commands()


def test_the_walk_finds_every_command() -> None:
    names = {" ".join(p) for p, _ in LEAVES}
    assert {
        "info",
        "fit",
        "simulate",
        "score",
        "study",
        "demo",
        "rig doe",
        "export",
        "inverse",
    } <= names


def _is_option(p: Any) -> bool:
    return getattr(p, "param_type_name", "") == "option"


def _is_numeric(p: Any) -> bool:
    """True for an int / float option (Typer's parameter objects differ between versions)."""
    desc = getattr(p, "type_descriptor", None)
    if desc is not None:
        ann = desc.annotation
        kinds = set(typing.get_args(ann)) - {type(None)} if typing.get_args(ann) else {ann}
        return bool(kinds) and kinds <= {int, float}
    return getattr(getattr(p, "type", None), "name", "") in ("integer", "float")


def _dummy_arguments(cmd: Any) -> list[str]:
    args: list[str] = []
    for p in cmd.params:
        if p.required and not _is_option(p):
            args.append("dummy")
        elif p.required:
            args += [p.opts[0], "dummy"]
    return args


@pytest.mark.parametrize("path", [p for p, _ in LEAVES], ids=[" ".join(p) for p, _ in LEAVES])
def test_usage_errors_are_one_line_with_exit_2(path: list[str], capsys) -> None:
    cmd = {tuple(p): c for p, c in LEAVES}[tuple(path)]
    # unknown option
    line = _one_line_error(*_run([*path, "--no-such-option"], capsys)[::2])
    assert "--no-such-option" in line
    # missing arguments (only where some are required)
    if any(p.required for p in cmd.params):
        _one_line_error(*_run(path, capsys)[::2])
    # a bad value for a numeric option
    numeric = [p for p in cmd.params if _is_option(p) and not p.is_flag and _is_numeric(p)]
    if numeric:
        opt = numeric[0].opts[0]
        line = _one_line_error(*_run([*path, *_dummy_arguments(cmd), opt, "abc"], capsys)[::2])
        assert opt in line
    # help works with -h
    code, out, _ = _run([*path, "-h"], capsys)
    assert code == 0 and "Usage" in out


def test_unknown_command_version_and_bare_group(capsys) -> None:
    assert "nope" in _one_line_error(*_run(["nope"], capsys)[::2])
    code, out, _ = _run(["--version"], capsys)
    from mrdamper.version import git_commit

    assert code == 0 and re.fullmatch(r"mrdamper \d+\.\d+\.\d+\S* \(.+\)\n", out)
    commit = git_commit()  # the report's commit, the same 12 characters
    assert (f"commit {commit[:12]}" if commit else "not run from a git checkout") in out
    code, out, _err = _run(["rig"], capsys)
    assert code == 0 and "doe" in out


def test_warnings_print_as_one_line(tmp_path, capsys) -> None:
    e = _sine("mm", 0.5)
    df = e.to_frame()
    df["x"] *= 1000.0  # millimetres in a column read as metres
    df["v"] *= 1000.0
    p = tmp_path / "mm.csv"
    df.to_csv(p, index=False)
    code, _out, err = _run(["info", str(p), "--json"], capsys)
    assert code == 0
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines and all(ln.startswith("warning: ") for ln in lines), err
    assert "warnings.warn" not in err and "Traceback" not in err


def test_cli_dependency_is_pinned_to_a_tested_range() -> None:
    deps = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    [spec] = [d for d in deps if d.startswith("typer")]
    assert ">=" in spec and "<" in spec.replace("<=", "")
    lo = re.search(r">=\s*([\d.]+)", spec).group(1)  # type: ignore[union-attr]
    hi = re.search(r"<\s*([\d.]+)", spec).group(1)  # type: ignore[union-attr]
    version = tuple(int(x) for x in typer.__version__.split(".")[:2])
    assert (
        tuple(int(x) for x in lo.split(".")[:2])
        <= version
        < tuple(int(x) for x in hi.split(".")[:2])
    )


# ------------------------------------------------------------------ data loss and unsafe writes
def test_study_out_equal_to_its_data_is_refused_even_with_force(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "D")
    before = sorted(p.name for p in data.iterdir())
    line = _one_line_error(*_run(["study", str(data), "--out", str(data), "--force"], capsys)[::2])
    assert "is an input" in line
    assert sorted(p.name for p in data.iterdir()) == before


def test_out_that_is_an_ancestor_of_the_working_folder_is_refused(
    tmp_path, capsys, monkeypatch
) -> None:
    proj = tmp_path / "proj"
    data = _folder(proj / "data")
    monkeypatch.chdir(proj)
    line = _one_line_error(*_run(["study", "data", "--out", "..", "--force"], capsys)[::2])
    assert "current folder or one of its ancestors" in line
    line = _one_line_error(*_run(["study", "data", "--out", ".", "--force"], capsys)[::2])
    assert "current folder" in line
    line = _one_line_error(*_run(["study", "data", "--out", "../proj", "--force"], capsys)[::2])
    assert "current folder" in line
    assert proj.is_dir() and data.is_dir()
    assert not list(tmp_path.rglob("*old-*")) and not list(tmp_path.rglob("*partial*"))


def test_simulate_cannot_overwrite_its_input_record(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    model = tmp_path / "m.json"
    assert _run(["fit", "sp1", str(data), "--out", str(model)], capsys)[0] == 0
    rec = data / "rec_a.csv"
    before = rec.read_bytes()
    line = _one_line_error(
        *_run(["simulate", str(model), str(rec), "--out", str(rec), "--force"], capsys)[::2]
    )
    assert "is an input" in line and rec.read_bytes() == before
    line = _one_line_error(
        *_run(["simulate", str(model), str(rec), "--out", str(model), "--force"], capsys)[::2]
    )
    assert "is an input" in line


@pytest.mark.skipif(
    not Path("/dev/full").exists(), reason="/dev/full is not available on this system"
)
def test_a_device_is_never_replaced(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    model = tmp_path / "m.json"
    assert _run(["fit", "sp1", str(data), "--out", str(model)], capsys)[0] == 0
    line = _one_line_error(
        *_run(
            ["simulate", str(model), str(data / "rec_a.csv"), "--out", "/dev/full", "--force"],
            capsys,
        )[::2]
    )
    assert "not a regular file" in line
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_unwritable_output_location_fails_before_any_computing(
    tmp_path, capsys, monkeypatch
) -> None:
    from mrdamper._io import safety
    from mrdamper.models import registry

    data = _folder(tmp_path / "d")

    def read_only(*_: Any, **__: Any) -> Any:
        raise OSError(errno.EROFS, "Read-only file system")

    def no_fit(*_: Any, **__: Any) -> Any:
        raise AssertionError("computing started before the output location was checked")

    monkeypatch.setattr(safety, "_probe", read_only)
    monkeypatch.setattr(registry, "get_estimator", no_fit)
    line = _one_line_error(*_run(["study", str(data), "--out", str(tmp_path / "o")], capsys)[::2])
    assert "Read-only file system" in line
    line = _one_line_error(*_run(["rig", "doe", "--out", str(tmp_path / "doe")], capsys)[::2])
    assert "Read-only file system" in line
    assert not (tmp_path / "o").exists() and not (tmp_path / "doe").exists()


def test_write_failure_is_one_line_and_leaves_nothing_partial(
    tmp_path, capsys, monkeypatch
) -> None:
    data = _folder(tmp_path / "d")
    real = Path.write_bytes

    def full(self: Path, data: bytes) -> int:
        if self.name.endswith(".part"):
            raise OSError(errno.ENOSPC, "No space left on device", str(self))
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", full)
    code, _, err = _run(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")], capsys)
    fitted, failed = err.splitlines()  # the fit's own last line (off a terminal), then the error
    assert re.fullmatch(r"fitting sp1 on 3 record\(s\), \d+ samples: done in \d+\.\d s", fitted)
    assert "No space left on device" in _one_line_error(code, failed, expected_code=1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]
    code, _, err = _run(
        [
            "study",
            str(data),
            "--out",
            str(tmp_path / "o"),
            "--models",
            "sp2",
            "--workers",
            "1",
            "--no-progress",
        ],
        capsys,
    )
    chosen, failed = [
        ln for ln in err.splitlines() if ln.strip()
    ]  # the protocol line, then the error
    assert "protocol 'default'" in chosen
    assert "No space left on device" in _one_line_error(code, failed, expected_code=1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


def test_rig_doe_failure_leaves_no_folder(tmp_path, capsys, monkeypatch) -> None:
    from mrdamper.data import ExperimentSet
    from mrdamper.rig import doe, doe_io

    def fail(*_: Any, **__: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(doe, "table_ii", lambda **_: ExperimentSet([_sine("exp1_rep01", 0.5)]))
    monkeypatch.setattr(doe_io, "_write_csv", fail)
    code, _, err = _run(["rig", "doe", "--out", str(tmp_path / "doe")], capsys)
    assert "No space left on device" in _one_line_error(code, err, expected_code=1)
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- interrupts
def _interrupting_fit(*_: Any, **__: Any) -> Any:
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as exc:  # what a compiled kernel does with Ctrl-C
        raise SystemError(
            "<built-in function kernel> returned a result with an exception set"
        ) from exc


@pytest.mark.parametrize("workers", ["1", "2"])
def test_ctrl_c_inside_a_kernel_ends_the_study_with_130(
    workers, tmp_path, capsys, monkeypatch
) -> None:
    from mrdamper.models.sp.model import _SPEstimator as SPEstimator

    data = _folder(tmp_path / "d")
    monkeypatch.setattr(SPEstimator, "fit", _interrupting_fit)
    code, out, err = _run(
        [
            "study",
            str(data),
            "--out",
            str(tmp_path / "o"),
            "--models",
            "sp2",
            "--workers",
            workers,
            "--no-progress",
        ],
        capsys,
    )
    assert code == 130 and err.strip().splitlines()[-1] == "interrupted"
    assert not (tmp_path / "o").exists() and "Headline" not in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


def test_ctrl_c_anywhere_ends_with_130_and_one_line(tmp_path, capsys, monkeypatch) -> None:
    import mrdamper.cli.models as cli_models

    def interrupt(*_: Any, **__: Any) -> Any:
        raise KeyboardInterrupt

    data = _folder(tmp_path / "d")
    monkeypatch.setattr(cli_models, "get_estimator", interrupt)
    code, _, err = _run(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")], capsys)
    assert code == 130 and [ln for ln in err.splitlines() if ln.strip()] == ["interrupted"]
    assert not (tmp_path / "m.json").exists()


# ----------------------------------------------------------------------------- silent wrong answers
def test_scoring_a_three_sample_record_is_an_error(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    model = tmp_path / "m.json"
    assert _run(["fit", "sp1", str(data), "--out", str(model)], capsys)[0] == 0
    short = tmp_path / "short.csv"
    pd.read_csv(data / "rec_b.csv").head(3).to_csv(short, index=False)
    line = _one_line_error(*_run(["score", str(model), str(short)], capsys)[::2])
    assert "short.csv: record has 3 sample(s)" in line


@pytest.mark.parametrize("kind", ["sp1", "sp2", "sp3", "sp4"])
def test_sp_models_refuse_records_without_motion(kind, tmp_path, capsys) -> None:
    folder = tmp_path / "still"
    folder.mkdir()
    for k, cur in enumerate((0.0, 0.5, 1.0)):
        e = _sine(f"s{k}", cur)
        write_csv(e.replace(v=np.zeros(e.n)), folder / f"s{k}.csv")
    line = _one_line_error(
        *_run(["fit", kind, str(folder), "--out", str(tmp_path / "m.json")], capsys)[::2]
    )
    assert line.startswith("error: v: ") and "zero velocity" in line


def test_broken_symlink_in_a_folder_is_reported(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    (data / "rec_z.csv").symlink_to(tmp_path / "gone.csv")
    line = _one_line_error(*_run(["info", str(data)], capsys)[::2])
    assert "rec_z.csv is a broken symbolic link" in line


def test_model_file_with_nan_coefficients_is_refused_at_load(tmp_path, capsys) -> None:
    path = tmp_path / "lpv.json"
    _lpv_model().save(path)
    d = json.loads(path.read_text())
    d["parameters"]["alpha"]["__ndarray__"][0] = None
    d["sample_time"] = 0.001  # the one null (turned into NaN below) is the coefficient
    text = json.dumps(d).replace("null", "NaN")
    path.write_text(text)
    rec = write_csv(_sine("r", 0.5), tmp_path / "r.csv")
    line = _one_line_error(*_run(["score", str(path), str(rec)], capsys)[::2])
    assert "parameters.alpha: holds NaN" in line


def test_exporting_a_model_that_is_not_frozen_stable_warns(tmp_path, capsys) -> None:
    unstable = LPVModel(
        alpha=np.array([[-1.05]]),
        beta=np.array([[1.0]]),
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )
    path = tmp_path / "u.json"
    unstable.save(path)
    code, _out, err = _run(["export", str(path), "--out", str(tmp_path / "u.mat")], capsys)
    assert code == 0
    warns = [ln for ln in err.splitlines() if ln.startswith("warning: ")]
    assert len(warns) == 1 and "not frozen-stable" in warns[0]


def test_implausible_units_warn_and_bounds_can_be_overridden(tmp_path, capsys) -> None:
    e = _sine("mm", 0.5, amp=2.3)  # a 4.6 m stroke: millimetres declared as metres
    df = e.to_frame()
    df["i"] = 1000.0 * df["i"]  # current in mA, undeclared
    p = tmp_path / "mm.csv"
    df.to_csv(p, index=False)
    code, out, err = _run(["info", str(p), "--json"], capsys)
    assert code == 0
    warned = [ln for ln in err.splitlines() if ln.startswith("warning: ")]
    assert any(ln.startswith("warning: x: stroke") for ln in warned)
    assert any(ln.startswith("warning: v: ") for ln in warned)
    assert any(ln.startswith("warning: i: ") for ln in warned)
    assert any("implausible" in prob for prob in json.loads(out)[0]["problems"])
    code, _, err = _run(
        [
            "info",
            str(p),
            "--plausible-max",
            "stroke=10",
            "--plausible-max",
            "v=100",
            "--plausible-max",
            "i=1000",
        ],
        capsys,
    )
    assert code == 0 and "warning" not in err
    df["F"] = 1e7  # a force of 10 MN
    df.loc[::2, "F"] = -1e7
    df.to_csv(p, index=False)
    code, _, err = _run(["fit", "sp1", str(p), "--out", str(tmp_path / "m.json")], capsys)
    assert "warning: F: largest magnitude" in err


# ----------------------------------------------------------------------------- Python version
def test_requires_python_matches_the_standard_library_used() -> None:
    meta = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert (
        meta["project"]["requires-python"] == ">=3.11"
    )  # protocol files are read with tomllib (3.11+)
    assert "import tomllib" in (REPO / "src" / "mrdamper" / "study" / "presets.py").read_text()
    assert meta["tool"]["mypy"]["python_version"] == "3.11"
