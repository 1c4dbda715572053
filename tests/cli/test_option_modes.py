"""Every option of every command is honoured in each of the command's modes or refused there in one
line: the table :data:`mrdamper.cli._modes.MODES` walked against the command line itself.

* every command of the app (with its options, read from the app) is either a command with one
  mode (all options honoured) or has its modes in the table, and the table names only options
  the command has;
* every option a mode refuses is refused, in a real invocation entering that mode, with one line
  naming the option and the mode, before anything is read or computed (so the walk is cheap);
* a few options are checked honoured where they used to be dropped (``quartercar --plant`` with
  ``--car`` and ``--c-sky`` in :mod:`tests.test_failure_catalogue_3`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import typer

from mrdamper.cli._modes import MODES
from mrdamper.cli.main import app
from tests.test_bad_inputs import _folder, _lpv_model, _one_line_error, _run
from tests.test_failure_catalogue import SP3

#: Commands with one mode: every option is honoured (nothing to refuse).
ONE_MODE = {"fit", "simulate", "score"}

#: A value for each option a mode refuses (None: a flag).
VALUES: dict[str, str | None] = {
    "--plant": "rig",
    "--reg": "100",
    "--rate": "10",
    "--tune": None,
    "--bump": None,
    "--bump-height": "0.1",
    "--bump-length": "3",
    "--controllers": "skyhook",
    "--c-sky": "1000",
    "--c-ground": "1000",
    "--alpha": "0.3",
    "--name": "mine",
    "--dt": "0.001",
    "--inverse": None,
    "--horizon": "0.01",
    "--control-roads": "B",
    "--control-duration": "2",
    "--control-plant": "rig",
    "--workers": "1",
    "--loop-model": "sp3.json",
    "--format": "parquet",
    "--i-range": "0,1",
    "--pattern": "rec_.*",
    "--fs": "200",
    "--resample-fs": "200",
    "--nan-policy": "drop-edges",
    "--max-gap": "3",
    "--decimal": ",",
    "--sep": ";",
    "--column": "F=force",
    "--units": "x=mm",
    "--struct": "data",
    "--plausible-max": "stroke=2",
    "--derive-velocity": None,
    "--folds": "record",
    "--n-folds": "3",
    "--inside-only": None,
    "--no-halving": None,
    "--time-budget": "10",
    "--loop-roads": "B",
    "--loop-speeds": "10",
    "--loop-duration": "3",
}


def _commands() -> dict[str, list[str]]:
    """Command path (``"rig doe"``) -> its options' flags, read from the app."""
    root = typer.main.get_command(app)
    out: dict[str, list[str]] = {}

    def walk(cmd: Any, path: str) -> None:
        subs = getattr(cmd, "commands", None)
        if subs is None:
            out[path.strip()] = [f for p in cmd.params for f in (*p.opts, *p.secondary_opts)]
            return
        for name, sub in subs.items():
            walk(sub, f"{path} {name}")

    walk(root, "")
    return out


def test_every_command_is_in_the_table_and_the_table_names_real_options() -> None:
    commands = _commands()
    assert set(commands) == ONE_MODE | set(MODES), sorted(set(commands) ^ (ONE_MODE | set(MODES)))
    for command, modes in MODES.items():
        for mode in modes:
            assert mode.name.split()[0] in commands[command], (command, mode.name)
            for flag in mode.refused:
                assert flag in commands[command], (command, mode.name, flag)
                assert flag in VALUES, flag


def _entering(command: str, mode: str, tmp: Path) -> list[str]:
    """A command line of ``command`` in ``mode`` (records and models made in ``tmp``)."""
    model, data = tmp / "sp3.json", tmp / "d"
    out = str(tmp / "out")
    base = {
        "info": ["info"],
        "quartercar": ["quartercar", str(model), "--out", out],
        "export": ["export", str(tmp / "lpv.json"), "--out", str(tmp / "m.mat")],
        "inverse": ["inverse", str(model), str(data / "rec_a.csv"), "--out", str(tmp / "i.csv")],
        "study": ["study", str(data), "--out", out],
        "demo": ["demo", "--out", out],
        "rig doe": ["rig", "doe", "--out", out],
        "select": ["select", str(data), "--csv", str(tmp / "out")],
    }[command]
    if mode == "--scheduler":
        return [*base, "--scheduler", "tcp://127.0.0.1:1"]
    if mode == "--c-inverse":
        return [*base, "--c-inverse", str(tmp / "lib.so")]
    flag, *value = mode.split()
    if not value and VALUES.get(flag) is not None:  # a mode entered by an option's value
        value = [str(VALUES[flag])]
    return [*base, flag, *value]


CASES = [(c, m.name, f) for c, modes in MODES.items() for m in modes for f in m.refused]


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("modes")
    SP3.save(tmp / "sp3.json")
    _lpv_model().save(tmp / "lpv.json")
    _folder(tmp / "d")
    (tmp / "lib.so").write_bytes(b"")
    return tmp


@pytest.mark.parametrize(("command", "mode", "flag"), CASES)
def test_an_option_a_mode_cannot_use_is_refused_in_one_line(
    command: str, mode: str, flag: str, files: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    value = VALUES[flag]
    args = [*_entering(command, mode, files), flag, *([] if value is None else [value])]
    if flag == "--loop-model":
        args[-1] = str(files / "sp3.json")
    line = _one_line_error(*_run(args, capsys)[::2])
    assert line.startswith(f"error: {flag}: not with {mode}: "), line
    assert not (files / "out").exists()  # refused before anything was written


def test_an_option_the_model_cannot_use_is_refused_in_one_line(files: Path, capsys) -> None:
    """``inverse --horizon`` applies to an LPV model with a drive lag only, whatever the mode."""
    rec = str(files / "d" / "rec_a.csv")
    args = ["inverse", str(files / "sp3.json"), rec, "--out", str(files / "i.csv")]
    line = _one_line_error(*_run([*args, "--horizon", "0.01"], capsys)[::2])
    assert line.startswith("error: horizon: a lead horizon is a setting of the regularised")
    assert not (files / "i.csv").exists()


def test_a_plant_for_measured_records_is_refused_in_one_line(files: Path, capsys) -> None:
    """``study --control-plant`` is the truth of virtual-rig records; measured ones have none."""
    args = ["study", str(files / "d"), "--out", str(files / "out"), "--models", "sp2"]
    line = _one_line_error(*_run([*args, "--control-plant", "rig"], capsys)[::2])
    assert line.startswith("error: --control-plant: the records are not all from the virtual rig")
    assert not (files / "out").exists()
