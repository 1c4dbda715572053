"""The catalogue of faults, third part: the surfaces of the FMU, ``--plant``, the loop model and the
output mark. One test per case, each a clear error or a correct answer:

* data loss: a crafted FMU cannot write outside its private folder; ``--force`` replaces only what
  the mark lists (every file and folder at every depth, with its checksum, for this path): a user
  file in a subfolder, an edited file, a copied or forged mark keep the folder out of reach;
  folders that only look like a dead run's temporaries are left alone;
* silent wrong answers: ``quartercar --plant`` honours the car and the gains (checked as without
  it); the FMU export warns about an unstable model; a model trained at one current is refused
  with ``--plant`` and as ``--loop-model``; a fit that explains nothing warns;
* errors where warnings were: every loop of an unstable plant diverging is an error, the warnings
  of ``--plant`` go to standard error; an absurd sample (``x = 1e300`` m) is one line.

The commands run in-process on tiny synthetic records and models (helpers of
:mod:`tests.test_bad_inputs`); the refusals happen before any computing.
"""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

from mrdamper._io import MARK_NAME, atomic_write_text, check_output, write_files, write_folder
from mrdamper.data import Experiment, write_csv
from mrdamper.errors import DataValidationError, OutputError
from mrdamper.models.semiphenomenological import SP3Model
from tests.test_bad_inputs import FS, _folder, _lpv_model, _one_line_error, _run, _sine
from tests.test_failure_catalogue import SP3

#: SP3 trained at one current: its force does not depend on the current.
ONE_LEVEL = SP3Model(S=SP3.S, f0=SP3.f0, input_range=(0.5, 0.5))
#: An LPV model whose frozen poles leave the unit circle (largest modulus 1.85).
UNSTABLE = dataclasses.replace(
    _lpv_model(), alpha=np.array([[-2.5, 0.1, -0.02], [1.2, -0.05, 0.01]])
)


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


# ----------------------------------------------------------------------------- data loss
def _evil_fmu(path: Path, ident: str) -> Path:
    """An FMU whose modelIdentifier is a path (with a binary stored under that name)."""
    xml = (
        '<fmiModelDescription fmiVersion="2.0" modelName="d" guid="{0}">'
        f'<CoSimulation modelIdentifier="{ident}"/>'
        '<VendorAnnotations><Tool name="mrdamper"><Model kind="sp3" input="i" inputMin="0" '
        'inputMax="1" sampleTime="0.001"/></Tool></VendorAnnotations></fmiModelDescription>'
    )
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", xml)
        z.writestr(f"binaries/linux64/{ident}.so", b"\x7fELF evil")
    return path


def test_a_crafted_fmu_writes_nothing_outside_its_private_folder(tmp_path, capsys) -> None:
    victim = tmp_path / "victim_dir"
    victim.mkdir()
    (victim / "x.so").write_bytes(b"precious")
    model = SP3.save(tmp_path / "sp3.json")
    for ident in ("../../victim_dir/x", str(victim / "x"), "x/../../y", "int"):
        fmu = _evil_fmu(tmp_path / "evil.fmu", ident)
        args = ["quartercar", str(model), "--plant", str(fmu), "--out", str(tmp_path / "o")]
        line = _one_line_error(*_run(args, capsys)[::2])
        assert "--plant: evil.fmu: modelIdentifier" in line and "not a C identifier" in line
        assert (victim / "x.so").read_bytes() == b"precious"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.fmu", "sp3.json", "victim_dir"]


def _study_like(out: Path) -> Path:
    """A folder written by mrdamper with subfolders, as a study writes it."""

    def build(tmp: Path) -> None:
        for rel in ("results.csv", "figures/a.png", "models/sp1.json", "analysis/zones.csv"):
            (tmp / rel).parent.mkdir(exist_ok=True)
            atomic_write_text(tmp / rel, rel)

    return write_folder(out, build)


@pytest.mark.parametrize("where", ["figures/notes.txt", "models/mine.json", "analysis/x/keep.md"])
def test_force_refuses_a_folder_with_a_user_file_at_any_depth(where, tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    out = _study_like(tmp_path / "st")
    check_output(out, force=True, folder=True)  # all mrdamper's: --force may replace it
    (out / where).parent.mkdir(parents=True, exist_ok=True)
    (out / where).write_text("mine")
    args = ["study", str(data), "--out", str(out), "--models", "sp2", "--workers", "1", "--force"]
    line = _one_line_error(*_run(args, capsys)[::2])
    assert "mrdamper did not write" in line and where.split("/")[0] in line
    assert (out / where).read_text() == "mine"


def test_force_refuses_an_edited_file_and_a_copied_or_forged_mark(tmp_path) -> None:
    out = _study_like(tmp_path / "st")
    (out / "models" / "sp1.json").write_text("edited by the user")
    with pytest.raises(OutputError, match=r"changed since \(models/sp1.json\)"):
        check_output(out, force=True, folder=True)
    mine = tmp_path / "mine"  # a user's folder with a mark copied from an output
    mine.mkdir()
    (mine / "results.csv").write_text("results.csv")
    shutil.copy(_study_like(tmp_path / "st2") / MARK_NAME, mine / MARK_NAME)
    with pytest.raises(OutputError, match="a copied or moved mark"):
        check_output(mine, force=True, folder=True)
    forged = _study_like(tmp_path / "st3")
    mark = json.loads((forged / MARK_NAME).read_text())
    mark["entries"].update({"../victim": "folder", "/etc": "folder"})
    (forged / MARK_NAME).write_text(json.dumps(mark))
    with pytest.raises(OutputError, match="mark is not valid"):
        check_output(forged, force=True, folder=True)
    with pytest.raises(OutputError, match="mark is not valid"):  # merging: checked again
        write_folder(forged, lambda tmp: (tmp / "b.txt").write_text("b"), force=True, mode="merge")
    assert not (forged / "b.txt").exists()
    # adding files to it keeps the forged entries out of any mark mrdamper writes
    write_files(forged, {"c.txt": (None, lambda p: p.write_text("c"))})
    assert json.loads((forged / MARK_NAME).read_text()) == mark
    # an edited file inside a marked folder is not replaced by a single-file write either
    with pytest.raises(OutputError, match="changed since mrdamper wrote it"):
        atomic_write_text(out / "models" / "sp1.json", "new", force=True)


def test_folders_that_only_look_like_temporaries_are_kept(tmp_path) -> None:
    pid = _dead_pid()
    look = [tmp_path / f".st.{tag}{pid}-keep" for tag in ("partial-", "old-")]
    for folder in look:
        folder.mkdir()
        (folder / "mine.txt").write_text("precious")
    forged = tmp_path / f".st.partial-{pid}-forged"  # a mark, but not this folder's own
    forged.mkdir()
    (forged / MARK_NAME).write_text(json.dumps({"written_by": "mrdamper", "pid": pid}))
    _study_like(tmp_path / "st")
    assert all((f / "mine.txt").read_text() == "precious" for f in look) and forged.is_dir()


# ----------------------------------------------------------------------------- silent answers
def test_quartercar_plant_honours_and_checks_car_and_gains(tmp_path, capsys) -> None:
    model = SP3.save(tmp_path / "sp3.json")
    base = ["quartercar", str(model), "--plant", "rig", "--roads", "B", "--duration", "2"]
    base += ["--controllers", "skyhook"]
    tables = []
    for k, extra in enumerate(([], ["--car", "m_s=300", "--c-sky", "1000", "--reg", "50"])):
        code, _out, err = _run([*base, "--out", str(tmp_path / f"o{k}"), *extra], capsys)
        assert code == 0, err
        tables.append((tmp_path / f"o{k}" / "closed_loop.csv").read_text())
    assert tables[0] != tables[1]
    for bad, what in (
        (["--car", "m_s=-300"], "m_s: expected a finite value > 0"),
        (["--car", "wheels=4"], "--car: unknown parameter(s) ['wheels']"),
        (["--alpha", "2"], "alpha: expected 0 <= alpha <= 1"),
        (["--bump-height", "0.1"], "--bump-height: not with --plant"),
    ):
        line = _one_line_error(*_run([*base, "--out", str(tmp_path / "x"), *bad], capsys)[::2])
        assert what in line, line
    assert not (tmp_path / "x").exists()


def test_every_export_warns_about_an_unstable_model(tmp_path, capsys) -> None:
    from mrdamper.control.export.matrices import warn_if_unstable
    from mrdamper.models.phenomenological import P15Model

    with pytest.warns(RuntimeWarning, match="p15: model is not stable by construction"):
        warn_if_unstable(P15Model(input_range=(0.0, 1.0)))
    model = UNSTABLE.save(tmp_path / "lpv.json")
    warnings.simplefilter("always", RuntimeWarning)  # one process runs several commands here
    formats = ["mat", "json", *(["fmu"] if shutil.which("gcc") else [])]
    for fmt in formats:
        args = ["export", str(model), "--format", fmt, "--out", str(tmp_path / f"m.{fmt}")]
        code, _out, err = _run(args, capsys)
        assert code == 0, err
        assert "warning: lpv: model is not frozen-stable" in err and "1.8521" in err


def test_a_model_trained_at_one_current_is_refused_with_plant_and_as_loop_model(
    tmp_path, capsys
) -> None:
    one = ONE_LEVEL.save(tmp_path / "one.json")
    out = tmp_path / "o"
    for args, field in (
        (["quartercar", str(one), "--plant", "rig", "--out", str(out)], "model"),
        (["quartercar", str(SP3.save(tmp_path / "sp3.json")), "--plant", str(one)], "plant"),
        (["rig", "doe", "--extension", "control", "--loop-model", str(one)], "--loop-model"),
    ):
        line = _one_line_error(*_run([*args, "--out", str(out)], capsys)[::2])
        assert line.startswith(f"error: {field}: the sp3 model was identified at one i level")
    data = _folder(tmp_path / "d")
    args = ["inverse", str(one), str(data / "rec_a.csv"), "--out", str(tmp_path / "i.csv")]
    line = _one_line_error(*_run(args, capsys)[::2])
    assert "model: the sp3 model was identified at one i level (0.5 A)" in line
    assert not out.exists() and not (tmp_path / "i.csv").exists()


def test_a_loop_model_that_fails_is_named_as_loop_model(tmp_path, capsys, monkeypatch) -> None:
    import mrdamper.control.loop.doe_extension as ext
    from mrdamper.data import ExperimentSet
    from mrdamper.errors import SimulationDivergedError
    from mrdamper.rig import doe

    model = SP3.save(tmp_path / "sp3.json")
    monkeypatch.setattr(doe, "table_ii", lambda **_: ExperimentSet([_sine("a", 0.5)], name="t"))
    for exc in (
        DataValidationError("MODEL", "kind 'narx' has no inverse"),
        SimulationDivergedError("narx", 869, "the narx plant's step failed"),
    ):

        def fail(*_a, exc=exc, **_k):
            raise exc

        monkeypatch.setattr(ext, "control_extension", fail)
        args = ["rig", "doe", "--extension", "control", "--loop-model", str(model)]
        line = _one_line_error(*_run([*args, "--out", str(tmp_path / "o")], capsys)[::2])
        assert line.startswith("error: --loop-model: the quarter-car loop of sp3.json failed")


def test_a_fit_that_explains_nothing_warns(tmp_path, capsys) -> None:
    rng = np.random.default_rng(0)
    n = 2000
    t = np.arange(n) / FS
    data = tmp_path / "quiet"
    data.mkdir()
    for k, cur in enumerate((0.0, 0.5, 1.0)):
        v = 8e-5 * rng.standard_normal(n)  # the damper barely moves: velocity noise only
        F = 100.0 * cur + 20.0 * rng.standard_normal(n)
        rec = Experiment(t=t, x=np.cumsum(v) / FS, v=v, F=F, i=np.full(n, cur), name=f"q{k}")
        write_csv(rec, data / f"q{k}.csv")
    code, _out, err = _run(["fit", "bingham", str(data), "--out", str(tmp_path / "m.json")], capsys)
    assert code == 0, err
    assert "warning: bingham: the fit explains almost nothing of its training force" in err
    saved = json.loads((tmp_path / "m.json").read_text())["provenance"]["training_fit"]
    assert saved["training_esr"] >= 0.9
    # every command that uses the model says so again, on standard error
    _code, out, err = _run(["score", str(tmp_path / "m.json"), str(data / "q0.csv")], capsys)
    assert "warning: m.json: bingham: the fit explains almost nothing" in err
    assert "warning" not in out
    with warnings.catch_warnings():  # a fit on moving records says nothing of the kind
        warnings.simplefilter("error")
        from mrdamper.models import get_estimator

        get_estimator("bingham").fit([_sine(f"r{k}", c, seed=k) for k, c in enumerate((0, 0.5, 1))])


# ----------------------------------------------------------------------------- errors
@pytest.mark.slow
def test_an_unstable_plant_is_an_error_and_plant_warnings_go_to_stderr(tmp_path, capsys) -> None:
    model = SP3.save(tmp_path / "sp3.json")
    bad = UNSTABLE.save(tmp_path / "unstable.json")
    base = ["quartercar", str(model), "--roads", "B", "--duration", "2", "--controllers", "soft"]
    line = _one_line_error(
        *_run([*base, "--plant", str(bad), "--out", str(tmp_path / "u")], capsys)[::2]
    )
    assert line.startswith("error: plant: every loop with the lpv plant as damper failed")
    assert not (tmp_path / "u").exists()
    tune = ["quartercar", str(bad), "--tune", "--roads", "B", "--duration", "2"]
    line = _one_line_error(*_run([*tune, "--out", str(tmp_path / "t")], capsys)[::2])
    assert line.startswith("error: model: every loop with the lpv model as damper failed")
    assert not (tmp_path / "t").exists()
    code, out, err = _run([*base, "--plant", "rig", "--out", str(tmp_path / "ok")], capsys)
    assert code == 0 and "warning: the sp3 model carries no training envelope" in err
    assert "warning" not in out


def test_an_absurd_sample_is_one_line_without_numpy_warnings(tmp_path, capsys) -> None:
    rec = _sine("absurd", 0.5)
    x = rec.x.copy()
    x[100] = 1e300
    write_csv(rec.replace(x=x), tmp_path / "absurd.csv")
    model = SP3.save(tmp_path / "sp3.json")
    for args in (
        ["score", str(model), str(tmp_path / "absurd.csv")],
        ["fit", "sp1", str(tmp_path / "absurd.csv"), "--out", str(tmp_path / "m.json")],
    ):
        line = _one_line_error(*_run(args, capsys)[::2])
        assert "x: sample 100 of " in line and "absurd.csv is 1e+300 m, beyond any damper" in line
        assert not re.search(r"\d{20}", line)  # no 300-digit factor
    with warnings.catch_warnings(record=True) as caught:  # from Python: no reader in between
        warnings.simplefilter("always")
        with pytest.raises(DataValidationError, match="beyond any force that can be scored"):
            SP3.score(rec.replace(x=x))
    assert all(not re.search(r"\d{20}", str(w.message)) for w in caught)
    assert not [w for w in caught if "overflow" in str(w.message)]
