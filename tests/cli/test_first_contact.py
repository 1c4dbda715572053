"""What a new user sees first: the report (provenance, same bytes for the same run, wording),
the help text (units, value types, kinds) and the notes (each once)."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from mrdamper._io import MARK_NAME
from mrdamper.data import write_csv
from mrdamper.models import known_kinds
from tests.cli.test_study_cli import _write_sine_folder
from tests.test_bad_inputs import _folder, _run, _sine

STUDY = ["--models", "sp2,sp3", "--workers", "1", "--no-progress"]


#: The study run twice: a static map, a hysteretic map, the linear model and the seeded NARX peer.
TWICE = ["--models", "sp2,sp3,lti,narx", "--seed", "3", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """The same small study run twice into two folders (``sine/`` beside them holds the data)."""
    from mrdamper.cli.main import main

    base = tmp_path_factory.mktemp("twice")
    data = base / "sine"
    _write_sine_folder(data)
    outs = [base / "run1", base / "run2"]
    for out in outs:
        try:
            main(["study", str(data), "--out", str(out), *TWICE])
        except SystemExit as exc:
            assert not exc.code
    return outs


@pytest.mark.slow
def test_identical_runs_give_identical_files_but_the_timings(two_runs) -> None:
    a, b = two_runs
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    differ = [str(f) for f in files if (a / f).read_bytes() != (b / f).read_bytes()]
    timings = {"timings.csv", "timings.json"}
    assert set(differ) <= {*timings, MARK_NAME}, differ
    # the mark lists the same files with the same checksums, but the timings', for its own path
    marks = [json.loads((d / MARK_NAME).read_text()) for d in (a, b)]
    entries = [{k: v for k, v in m["entries"].items() if k not in timings} for m in marks]
    assert entries[0] == entries[1] and [m["path"] for m in marks] == [str(a), str(b)]
    names = {str(f) for f in files}
    assert {"report.html", "results.csv", "summary.csv", "fits.csv", "study.json"} <= names
    assert len([f for f in files if f.parts[0] == "models" and f.suffix == ".json"]) >= 4
    assert "timings.csv" in names and "wall_time_s" in (a / "timings.json").read_text()


@pytest.mark.slow
def test_model_fits_run_twice_from_the_command_line_give_the_same_bytes(two_runs, capsys) -> None:
    data = two_runs[0].parent / "sine"
    outs = [two_runs[0].parent / f"cli{k}.json" for k in (1, 2)]
    for o in outs:
        assert _run(["fit", "narx", str(data), "--out", str(o)], capsys)[0] == 0
    assert outs[0].read_bytes() == outs[1].read_bytes()


def test_report_and_study_json_carry_the_provenance(two_runs) -> None:
    from mrdamper import __version__
    from mrdamper.study.provenance import git_commit

    out = two_runs[0]
    prov = json.loads((out / "study.json").read_text())["provenance"]
    assert prov["mrdamper_version"] == __version__
    assert prov["git_commit"] == git_commit()
    settings = prov["settings"]
    assert settings["protocol"] == "quiroz-loco" and settings["seed"] == 3
    assert set(settings["models"]) == {"sp2", "sp3", "lti", "narx"}
    html = (out / "report.html").read_text()
    assert f"Provenance: mrdamper {__version__}, commit {(git_commit() or 'none')[:12]}" in html
    assert "quiroz-loco" in html
    # no times in the report: they are in timings.json
    assert "fit time" not in html and "wall" not in html


def test_report_title_and_record_wording(two_runs) -> None:
    html = (two_runs[0] / "report.html").read_text()
    title = re.search(r"<title>(.*?)</title>", html).group(1)
    assert title == "Which damper model? 4 models compared on 6 measured records"
    assert "comparison: " not in html


def test_record_wording_of_the_virtual_rig() -> None:
    from mrdamper.study.provenance import records_text

    assert (
        records_text(61, "virtual rig (spencer damper)")
        == "61 records from the virtual rig (spencer damper model)"
    )
    assert records_text(1, "measured") == "1 measured record"


@pytest.mark.slow
def test_one_scored_record_shows_no_quartiles(tmp_path, capsys) -> None:
    data = tmp_path / "one"
    data.mkdir()
    write_csv(_sine("only", 0.5, seconds=8.0), data / "only.csv")
    out = tmp_path / "out"
    code, _o, err = _run(["study", str(data), "--out", str(out), *STUDY], capsys)
    assert code == 0, err
    html = (out / "report.html").read_text()
    summary = html[html.index("<h2>Summary</h2>") : html.index("<h2>Which model")]
    spans = re.findall(r"<td>([^<]*\u2013[^<]*)</td>", summary)
    assert spans == [], spans  # no "a-a" quartiles from a single score
    assert "- for a single score" in summary


def test_one_warning_of_several_models_is_one_row() -> None:
    from mrdamper.study.report import _merged_notes

    note = "RuntimeWarning: i: {m} was identified on [0, 1.00594] but the record spans [0, 1.00616]"
    notes = pd.DataFrame(
        [
            {"model": m, "record": f"r{k}", "note": note.format(m=m)}
            for m in ("lpv", "sp1", "p15")
            for k in range(4)
        ]
        + [{"model": "narx", "record": "r0", "note": "RuntimeWarning: narx diverged late"}]
    )
    merged = _merged_notes(notes)
    assert len(merged) == 2
    assert merged.iloc[0]["models"] == "lpv, sp1, p15" and merged.iloc[0]["rows"] == 12
    assert "<model> was identified" in merged.iloc[0]["example"]


def test_time_domain_captions_give_the_window(two_runs) -> None:
    html = (two_runs[0] / "report.html").read_text()
    for fig in ("fig09_force_time", "fig10_fv_models", "fig11_fx_loops"):
        cap = re.search(rf'<figure id="{fig}">.*?<figcaption>(.*?)</figcaption>', html, re.DOTALL)
        assert cap is not None, fig
        assert re.search(r"drawn (whole, )?(from )?t = [\d.]+ to [\d.]+ s", cap.group(1)), cap


# ----------------------------------------------------------------------------- help text
def _help(args: list[str], capsys) -> str:
    code, out, err = _run([*args, "--help"], capsys)
    assert code == 0, err
    return out


@pytest.mark.parametrize(
    ("command", "units"),
    [
        ("quartercar", ["Vehicle speed [m/s]", "Length of each ISO road [s]", "Bump height [m]"]),
        ("study", ["[samples]", "[Hz]"]),
        ("fit", ["[samples]"]),
    ],
)
def test_help_keeps_units(command, units, capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "250")  # one line per option
    text = _help([command], capsys)
    for unit in units:
        assert unit in text, unit


def test_help_shows_readable_value_types(capsys, monkeypatch) -> None:
    from mrdamper.cli.main import app

    monkeypatch.setenv("COLUMNS", "250")
    commands = [c.name for c in app.registered_commands]
    assert len(commands) >= 10
    for command in commands:
        text = _help([command], capsys)
        assert "<bool>" not in text and "<list[" not in text, command
    text = _help(["fit"], capsys)
    assert re.search(r"data\.\.\.\s+<path> \.\.\.", text)
    assert re.search(r"--set\s+<str> \(repeatable\)", text)


def test_fit_help_lists_every_kind_of_the_registry(capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "250")
    from mrdamper.kinds import KINDS

    text = " ".join(_help(["fit"], capsys).split())
    # every kind of the kind table (test doubles registered later by other test modules aside)
    listed = text.split("Model kind:", 1)[1]
    for row in KINDS:
        assert f" {row.kind}," in listed or f" {row.kind}." in listed, row.kind
    assert "narx" in known_kinds()


@pytest.mark.parametrize(
    ("command", "after"), [("quartercar", "any kind:"), ("export", "any kind (")]
)
def test_model_file_help_lists_the_kind_table(command, after, capsys, monkeypatch) -> None:
    # every kind runs in the quarter car and exports as C and FMU: the help says so from the
    # kind table, not from a list typed once ("lpv, sp1..sp4, bingham")
    monkeypatch.setenv("COLUMNS", "250")
    from mrdamper.cli.export import FORMATS
    from mrdamper.kinds import KINDS

    text = " ".join(_help([command], capsys).split())
    listed = text.split(after, 1)[1].split(")", 1)[0]
    assert [k.strip() for k in listed.split(",")][: len(KINDS)] == [row.kind for row in KINDS]
    assert "sp1..sp4" not in text and "LPV or LTI model file" not in text
    if command == "export":
        assert " | ".join(FORMATS) in text


def test_the_fmu_extra_installs_fmpy_and_all_includes_it() -> None:
    import tomllib

    from tests.conftest import REPO_ROOT

    extras = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    assert any(req.startswith("fmpy") for req in extras["fmu"])
    [everything] = extras["all"]
    inside = everything.split("[", 1)[1].rstrip("]").split(",")
    assert set(inside) == set(extras) - {"all", "dev"}  # every other extra, fmu among them
    readme = (REPO_ROOT / "README.md").read_text()
    assert "--format fmu" in readme and "`[fmu]`" in readme


# ----------------------------------------------------------------------------- notes once
def _rounded_time_folder(path):
    """Records whose time column is rounded to 0.1 ms: each read gives the time-column note."""
    path.mkdir()
    for k, cur in enumerate((0.0, 0.5, 1.0)):
        df = _sine(f"r{k}", cur, fs=300.0, seconds=6.0).to_frame()
        df["t"] = np.round(df["t"], 4)
        df.to_csv(path / f"r{k}.csv", index=False)
    return path


@pytest.mark.slow
def test_a_reading_note_appears_once_in_a_study(tmp_path, capsys) -> None:
    data = _rounded_time_folder(tmp_path / "rounded")
    code, _o, err = _run(
        ["study", str(data), "--out", str(tmp_path / "out"), "--models", "sp2", "--no-progress"],
        capsys,
    )
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if "time column of" in ln]
    for k in range(3):  # the first note in full, the others named in one line that counts them
        assert sum(f"r{k}.csv" in ln for ln in lines) == 1, err


def test_info_prints_a_note_once_and_points_to_it(tmp_path, capsys) -> None:
    data = _rounded_time_folder(tmp_path / "rounded")
    code, out, err = _run(["info", str(data / "r0.csv")], capsys)
    assert code == 0, err
    assert err.count("note: time column of") == 1
    assert "time column of" not in out and "repaired: see the note above" in out


def test_notes_that_differ_in_a_name_and_figures_print_once_then_counted(tmp_path, capsys) -> None:
    # one note per record would be one line per record: the first prints in full, then one
    # line counts the others and names them
    data = _rounded_time_folder(tmp_path / "rounded")
    code, _out, err = _run(["info", str(data)], capsys)
    assert code == 0, err
    notes = [ln for ln in err.splitlines() if ln.startswith("note: ")]
    assert len(notes) == 2, err
    assert notes[0].startswith(f"note: time column of {data / 'r0.csv'} is not uniform")
    assert notes[1].startswith("note: 2 more like 'time column of ... is not uniform")
    assert notes[1].endswith(f"with other figures: {data / 'r1.csv'}, {data / 'r2.csv'}")


def test_an_unchanged_folder_reads_without_notes(tmp_path, capsys) -> None:
    code, _out, err = _run(["info", str(_folder(tmp_path / "d"))], capsys)
    assert code == 0 and "note:" not in err
