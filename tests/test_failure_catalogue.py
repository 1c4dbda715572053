"""The catalogue of faults a careful (and an unlucky) user meets, one class per section.

* data loss: no command with ``--force`` destroys anything in a sandboxed home full of precious
  files; ``--force`` replaces only what mrdamper wrote;
* malformed model files and unresolvable paths: one line naming the field or the path;
* failures leave nothing behind (partial folders of dead runs are removed by a rerun, quartercar
  and the C export write all their files or none), SIGTERM is handled like Ctrl-C and no worker
  process outlives the command; each exit status (0, 1, 2, 130, 143) is checked;
* unclear errors: the bad file among good ones is named, Ctrl-C while reading does not blame a
  file, an impossible number of folds is one line.

The commands run in-process on tiny synthetic records (helpers of :mod:`tests.test_bad_inputs`);
the orphan-worker case runs the command line in a child process.
"""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from mrdamper._io import MARK_NAME
from mrdamper.data import write_csv
from mrdamper.models.semiphenomenological import SP3Model
from tests.test_bad_inputs import _folder, _lpv_model, _one_line_error, _run, _sine

SP3 = SP3Model(S=(800.0, 200.0, 60.0, -1000.0, 900.0, 4000.0), f0=10.0, input_range=(0.0, 1.0))
SRC = Path(__file__).resolve().parents[1] / "src"


def _snapshot(root: Path) -> dict[str, bytes | None]:
    """Every entry under ``root``: file bytes, or None for a folder."""
    out: dict[str, bytes | None] = {}
    for p in sorted(root.rglob("*")):
        if p.is_symlink():
            out[str(p.relative_to(root))] = os.readlink(p).encode()
        else:
            out[str(p.relative_to(root))] = None if p.is_dir() else p.read_bytes()
    return out


# ----------------------------------------------------------------------------- data loss
@pytest.fixture
def home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A sandboxed home folder full of precious files; the command runs in ``~/work``."""
    h = tmp_path / "home"
    (h / ".ssh").mkdir(parents=True)
    (h / ".ssh" / "id_ed25519").write_text("PRIVATE KEY")
    (h / ".bashrc").write_text("export PATH=$PATH:~/bin\n")
    (h / "notes.json").write_text('{"todo": ["everything"]}\n')
    (h / "project" / ".git").mkdir(parents=True)
    (h / "project" / ".git" / "config").write_text("[core]\n")
    write_csv(_sine("mine", 0.5), h / "project" / "data.csv")
    (h / "results").mkdir()
    (h / "results" / "thesis.tex").write_text("\\chapter{Results}\n")
    work = h / "work"
    _folder(work / "data")
    SP3.save(work / "sp3.json")
    _lpv_model().save(work / "lpv.json")
    monkeypatch.setenv("HOME", str(h))
    monkeypatch.chdir(work)
    return h


def _attempts(h: Path) -> list[list[str]]:
    """Every writing command, with --force, onto a precious place of the home ``h``."""
    rec = "data/rec_a.csv"
    out: list[list[str]] = []
    for target in (h, h / ".ssh", h / "project", h / "results"):
        out += [
            ["study", "data", "--out", str(target), "--models", "sp2", "--workers", "1"],
            ["demo", "--out", str(target), "--quick"],
            ["rig", "doe", "--out", str(target), "--scale", "0.07"],
        ]
    for target in (h, h / "project"):
        out += [
            ["quartercar", "sp3.json", "--out", str(target), "--duration", "2", "--roads", "B"],
            ["export", "lpv.json", "--format", "c", "--out", str(target)],
        ]
    for target in (h / ".bashrc", h / "notes.json", h / ".ssh" / "id_ed25519"):
        out += [
            ["fit", "sp1", "data", "--out", str(target)],
            ["export", "lpv.json", "--out", str(target)],
            ["export", "lpv.json", "--format", "json", "--out", str(target)],
        ]
    data_csv = str(h / "project" / "data.csv")
    out += [
        ["simulate", "sp3.json", rec, "--out", data_csv],
        ["inverse", "sp3.json", rec, "--out", data_csv],
        ["select", "data", "--csv", data_csv, "-m", "sp1"],
        ["fit", "sp1", "data", "--out", data_csv],
    ]
    return [[*a, "--force"] for a in out]


@pytest.mark.slow
def test_force_never_destroys_anything_in_a_sandboxed_home(home: Path, capsys) -> None:
    before = _snapshot(home)
    attempts = _attempts(home)
    for args in attempts:
        code, _out, err = _run(args, capsys)
        line = _one_line_error(code, err)
        assert "never" in line or "home folder" in line or "repository" in line, (args, line)
    after = _snapshot(home)
    lost = {k for k in before if k not in after or after[k] != before[k]}
    assert not lost, lost
    new = sorted(set(after) - set(before))
    assert new == [], new  # nothing written anywhere either (not even a hidden temporary)
    assert len(attempts) >= 25


def test_home_and_repository_root_are_named_in_one_line(home: Path, capsys, monkeypatch) -> None:
    data = str(home / "work" / "data")
    monkeypatch.chdir(home.parent)  # the home folder is not an ancestor of this one
    line = _one_line_error(*_run(["study", data, "--out", str(home), "--force"], capsys)[::2])
    assert f"{home} is the home folder" in line
    line = _one_line_error(
        *_run(["study", data, "--out", str(home / "project"), "--force"], capsys)[::2]
    )
    assert "is the root of a repository" in line and str(home / "project") in line
    line = _one_line_error(
        *_run(["study", data, "--out", str(home / "results"), "--force"], capsys)[::2]
    )
    assert f"{home / 'results'} is a non-empty folder mrdamper did not write" in line


@pytest.mark.slow
def test_force_replaces_what_mrdamper_wrote(tmp_path: Path, capsys) -> None:
    data = _folder(tmp_path / "d")
    model = tmp_path / "m.json"
    SP3.save(model)
    qc = ["quartercar", str(model), "--out", str(tmp_path / "qc"), "--duration", "2"]
    qc += ["--roads", "B", "--no-bump"]
    assert _run(qc, capsys)[0] == 0
    mark = json.loads((tmp_path / "qc" / MARK_NAME).read_text())
    assert mark["written_by"] == "mrdamper" and "quartercar.csv" in mark["entries"]
    assert _run([*qc, "--force"], capsys)[0] == 0
    doe = tmp_path / "doe"
    rig = ["rig", "doe", "--out", str(doe), "--scale", "0.07", "--fs", "200"]
    assert _run(rig, capsys)[0] == 0
    assert _run([*rig, "--force"], capsys)[0] == 0
    # a file the user added to an output folder makes it theirs: never replaced
    (doe / "my_notes.txt").write_text("mine")
    line = _one_line_error(
        *_run(["rig", "doe", "--out", str(doe), "--scale", "0.07", "--force"], capsys)[::2]
    )
    assert "my_notes.txt" in line and (doe / "my_notes.txt").read_text() == "mine"
    assert data.is_dir()


# ----------------------------------------------------------------------------- malformed models
def _malformed(d: dict[str, Any], case: str) -> Any:
    x = json.loads(json.dumps(d))
    if case == "null coefficient":
        x["parameters"]["alpha"]["__ndarray__"][0] = None
    elif case == "top-level list":
        return [x]
    elif case == "shape mismatch":
        x["parameters"]["alpha"]["shape"] = [4, 3]
    elif case == "wrong type":
        x["parameters"]["fs"] = "fast"
    elif case == "null number":
        x["parameters"]["offset"] = None
    elif case == "missing field":
        del x["parameters"]["beta"]
    elif case == "bad input range":
        x["input_range"] = "0..1"
    return x


CASES = {
    "null coefficient": "parameters.alpha: value 0 is None",
    "top-level list": "expected a JSON object",
    "shape mismatch": "parameters.alpha: shape [4, 3] needs 12 values",
    "wrong type": "parameters.fs: expected float, got 'fast'",
    "null number": "parameters.offset: expected float, got None",
    "missing field": "beta",
    "bad input range": "input_range: expected two numbers",
}


@pytest.mark.parametrize("case", list(CASES))
def test_malformed_model_file_is_one_line_naming_the_field(case, tmp_path, capsys) -> None:
    good = tmp_path / "lpv.json"
    _lpv_model().save(good)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(_malformed(json.loads(good.read_text()), case)))
    rec = str(write_csv(_sine("r", 0.5), tmp_path / "r.csv"))
    commands = [
        ["score", str(bad), rec],
        ["simulate", str(bad), rec, "--out", str(tmp_path / "s.csv")],
        ["quartercar", str(bad), "--out", str(tmp_path / "qc"), "--duration", "2"],
        ["export", str(bad), "--out", str(tmp_path / "e.mat")],
        ["export", str(bad), "--format", "c", "--out", str(tmp_path / "c")],
        ["inverse", str(bad), rec, "--out", str(tmp_path / "i.csv")],
    ]
    for args in commands:
        line = _one_line_error(*_run(args, capsys)[::2])
        assert CASES[case] in line and "bad.json" in line, (args, line)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "lpv.json", "r.csv"]


# ----------------------------------------------------------------------------- paths
def _path_commands(tmp: Path, inp: str, out: str) -> list[list[str]]:
    model, rec, data = str(tmp / "sp3.json"), str(tmp / "d" / "rec_a.csv"), str(tmp / "d")
    return [
        ["info", inp],
        ["fit", "sp1", inp, "--out", str(tmp / "m.json")],
        ["fit", "sp1", data, "--out", out],
        ["score", inp, rec],
        ["score", model, inp],
        ["simulate", model, inp, "--out", str(tmp / "s.csv")],
        ["simulate", model, rec, "--out", out],
        ["study", inp, "--out", str(tmp / "st")],
        ["study", data, "--out", out],
        ["select", inp],
        ["select", data, "--csv", out],
        ["export", inp, "--out", str(tmp / "e.mat")],
        ["export", str(tmp / "lpv.json"), "--out", out],
        ["export", str(tmp / "lpv.json"), "--format", "c", "--out", out],
        ["quartercar", inp, "--out", str(tmp / "qc")],
        ["quartercar", model, "--out", out],
        ["inverse", model, inp, "--out", str(tmp / "i.csv")],
        ["inverse", model, rec, "--out", out],
        ["rig", "doe", "--out", out],
        ["demo", "--out", out],
    ]


@pytest.mark.parametrize("kind", ["loop", "dangling"])
def test_unresolvable_paths_are_one_line_in_every_command(kind, tmp_path, capsys) -> None:
    _folder(tmp_path / "d")
    SP3.save(tmp_path / "sp3.json")
    _lpv_model().save(tmp_path / "lpv.json")
    bad = tmp_path / "bad"
    if kind == "loop":
        (tmp_path / "other").symlink_to(bad)
        bad.symlink_to(tmp_path / "other")
        words = "symbolic link loop"
    else:
        bad.symlink_to(tmp_path / "gone")
        words = "broken symbolic link"
    before = _snapshot(tmp_path)
    for args in _path_commands(tmp_path, str(bad), str(bad)):
        line = _one_line_error(*_run(args, capsys)[::2])
        assert words in line and "bad" in line, (args, line)
    assert _snapshot(tmp_path) == before


def test_permission_denied_is_one_line(tmp_path, capsys, monkeypatch) -> None:
    from mrdamper._io import safety

    data = _folder(tmp_path / "d")
    model = SP3.save(tmp_path / "sp3.json")
    real_open = open

    def guarded(file: Any, *args: Any, **kw: Any) -> Any:
        if str(file).endswith("rec_b.csv") or str(file).endswith("sp3.json"):
            raise PermissionError(errno.EACCES, "Permission denied", str(file))
        return real_open(file, *args, **kw)

    monkeypatch.setattr("builtins.open", guarded)
    monkeypatch.setattr(Path, "open", lambda self, *a, **k: guarded(self, *a, **k))
    line = _one_line_error(*_run(["info", str(data)], capsys)[::2])
    assert "Permission denied" in line and "rec_b.csv" in line
    line = _one_line_error(*_run(["score", str(model), str(data / "rec_a.csv")], capsys)[::2])
    assert "Permission denied" in line and "sp3.json" in line
    monkeypatch.undo()

    def denied(folder: Path) -> None:
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(safety, "_probe", denied)
    line = _one_line_error(
        *_run(["fit", "sp1", str(data), "--out", str(tmp_path / "ro" / "m.json")], capsys)[::2]
    )
    assert "cannot write in" in line and "Permission denied" in line


# ----------------------------------------------------------------------------- scheduler
@pytest.mark.parametrize("address", ["notaurl", "tcp://host", "http://host:8786", "host:0"])
def test_scheduler_address_form_is_checked_before_connecting(address, tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    line = _one_line_error(
        *_run(["study", str(data), "--out", str(tmp_path / "o"), "--scheduler", address], capsys)[
            ::2
        ]
    )
    assert line.startswith("error: --scheduler: ") and "tcp://HOST:8786" in line
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------------------- leftovers, signals
def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _killed_run_folder(parent: Path, target: str, tag: str, pid: int) -> Path:
    """The temporary folder a run of mrdamper killed outright leaves: its temporary mark."""
    from mrdamper._io.mark import write_temporary_mark

    folder = parent / f".{target}.{tag}{pid}-abc123"
    folder.mkdir()
    write_temporary_mark(folder, parent / target)
    mark = json.loads((folder / MARK_NAME).read_text())
    (folder / MARK_NAME).write_text(json.dumps({**mark, "pid": pid}))
    return folder


@pytest.mark.slow
def test_rerun_removes_partial_folders_of_dead_runs_only(tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    dead = _killed_run_folder(tmp_path, "o", "partial-", _dead_pid())
    (dead / "models").mkdir(parents=True)
    (dead / "results.csv").write_text("half")
    dead_old = _killed_run_folder(tmp_path, "o", "old-", _dead_pid())
    dead_file = _killed_run_folder(tmp_path, "o", "partial-", _dead_pid())  # a file's
    (dead_file / "o.part").write_text("half")
    alive = _killed_run_folder(tmp_path, "o", "partial-", os.getpid())  # a running writer
    mine = tmp_path / ".o.partial-notes"  # not a name mrdamper makes: left alone
    mine.mkdir()
    # named like a dead run's temporaries but without its mark: the user's, left alone
    look = [tmp_path / f".o.{tag}{_dead_pid()}-keep" for tag in ("partial-", "old-")]
    for folder in look:
        folder.mkdir()
        (folder / "mine.txt").write_text("precious")
    args = ["study", str(data), "--out", str(tmp_path / "o"), "--models", "sp2"]
    code, _, err = _run([*args, "--workers", "1", "--no-progress"], capsys)
    assert code == 0, err
    assert not dead.exists() and not dead_old.exists() and not dead_file.exists()
    assert alive.is_dir() and mine.is_dir()
    assert all((f / "mine.txt").read_text() == "precious" for f in look)
    hidden = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("."))
    assert hidden == sorted([alive.name, mine.name, *(f.name for f in look)])


@pytest.mark.slow
def test_quartercar_failure_leaves_no_table(tmp_path, capsys, monkeypatch) -> None:
    from matplotlib.figure import Figure

    model = SP3.save(tmp_path / "sp3.json")
    out = tmp_path / "qc"
    args = ["quartercar", str(model), "--out", str(out), "--duration", "2", "--roads", "B"]

    def full(*_: Any, **__: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full)
    line = _one_line_error(*_run(args, capsys)[::2], expected_code=1)
    assert "No space left on device" in line and not out.exists()
    monkeypatch.undo()
    # a name collision is found before anything is written, with and without --force
    out.mkdir()
    (out / "time_iso_b_20_m_s.png").write_text("my own figure")
    for extra in ([], ["--force"]):
        line = _one_line_error(*_run([*args, *extra], capsys)[::2])
        assert "time_iso_b_20_m_s.png" in line
        assert sorted(p.name for p in out.iterdir()) == ["time_iso_b_20_m_s.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["qc", "sp3.json"]


def test_c_export_onto_a_full_disk_leaves_nothing(tmp_path, capsys, monkeypatch) -> None:
    model = _lpv_model().save(tmp_path / "lpv.json")
    real = Path.write_text

    def full(self: Path, *args: Any, **kw: Any) -> int:
        if "mrd_damper.c" in self.name:
            raise OSError(errno.ENOSPC, "No space left on device", str(self))
        return real(self, *args, **kw)

    monkeypatch.setattr(Path, "write_text", full)
    out = tmp_path / "deep" / "c_code"
    code, _, err = _run(["export", str(model), "--format", "c", "--out", str(out)], capsys)
    assert "No space left on device" in _one_line_error(code, err, expected_code=1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lpv.json"]


@pytest.mark.slow
def test_each_exit_status(tmp_path, capsys, monkeypatch) -> None:
    import mrdamper.cli.models as cli_models
    from mrdamper.models.sp.model import _SPEstimator as SPEstimator

    data = _folder(tmp_path / "d")
    handler = signal.getsignal(signal.SIGTERM)
    assert _run(["info", str(data)], capsys)[0] == 0
    assert _run(["score", str(tmp_path / "nope.json"), str(data)], capsys)[0] == 2
    real = Path.write_bytes

    def full(self: Path, payload: bytes) -> int:
        if self.name.endswith(".part"):
            raise OSError(errno.ENOSPC, "No space left on device", str(self))
        return real(self, payload)

    with monkeypatch.context() as m:
        m.setattr(Path, "write_bytes", full)
        code, _, err = _run(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")], capsys)
        assert code == 1 and "No space left on device" in err

    def interrupt(*_: Any, **__: Any) -> Any:
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(cli_models, "get_estimator", interrupt)
        code, _, err = _run(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")], capsys)
        assert code == 130 and err.strip() == "interrupted"

    def terminate(*_: Any, **__: Any) -> Any:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler interrupts this sleep
        raise AssertionError("SIGTERM was not handled")

    with monkeypatch.context() as m:
        m.setattr(SPEstimator, "fit", terminate)
        out = tmp_path / "o"
        args = ["study", str(data), "--out", str(out), "--models", "sp2", "--workers", "1"]
        code, _, err = _run([*args, "--no-progress"], capsys)
        assert code == 143 and err.strip().splitlines()[-1] == "terminated"
    assert signal.getsignal(signal.SIGTERM) == handler  # the command line restores it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_a_stopped_pool_leaves_no_worker_and_no_management_thread() -> None:
    """``stop_pool`` returns with the workers and the pool's management thread ended, so the
    interpreter's exit hook cannot race the thread closing its wakeup pipe (a traceback after
    ``terminated`` on Python 3.11)."""
    import concurrent.futures as cf

    from mrdamper._io.processes import init_worker, stop_pool

    pool = cf.ProcessPoolExecutor(2, initializer=init_worker, initargs=(os.getpid(),))
    futures = [pool.submit(time.sleep, 60) for _ in range(4)]
    deadline = time.monotonic() + 30
    while sum(f.running() for f in futures) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    workers = list(pool._processes.values())
    manager = pool._executor_manager_thread
    assert len(workers) == 2 and manager is not None and manager.is_alive()
    stop_pool(pool)
    assert not any(p.is_alive() for p in workers)
    assert not manager.is_alive()
    assert all(f.cancelled() or f.done() for f in futures)


SLOW_STUDY = """
import sys, time
from mrdamper.models.sp.model import _SPEstimator
def slow(self, *args, **kw):
    with open(sys.argv[1], "a") as fh:
        fh.write("fit\\n")
    time.sleep(120)
_SPEstimator.fit = slow
from mrdamper.cli.launch import main
main(sys.argv[2:])
"""


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
@pytest.mark.slow
def test_a_stopped_study_leaves_no_worker_running(sig, tmp_path) -> None:
    """SIGTERM: handled like Ctrl-C (status 143, nothing written); SIGKILL cannot be handled,
    but the workers still end with their parent."""
    data = _folder(tmp_path / "d")
    started = tmp_path / "started.txt"
    script = tmp_path / "slow.py"
    script.write_text(SLOW_STUDY)
    out = tmp_path / "o"
    args = ["study", str(data), "--out", str(out), "--models", "sp2", "--workers", "2"]
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.Popen(
        [sys.executable, str(script), str(started), *args, "--no-progress"],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        deadline = time.monotonic() + 120
        while not (started.exists() and started.read_text()) and time.monotonic() < deadline:
            time.sleep(0.2)
        workers = _children(proc.pid)
        assert workers, "the study started no worker process"
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    if sig == signal.SIGTERM:
        assert proc.returncode == 143 and err.strip().splitlines()[-1] == "terminated", err
    else:
        assert proc.returncode == -signal.SIGKILL
    deadline = time.monotonic() + 10
    while any(_running(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [w for w in workers if _running(w)]
    for w in left:  # do not leave them behind when the test fails
        os.kill(w, signal.SIGKILL)
    assert not left, "worker processes outlived the study"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "slow.py", "started.txt"]


# ----------------------------------------------------------------------------- unclear errors
def _bad_file(path: Path, what: str) -> None:
    good = _sine("z", 0.25).to_frame()
    if what == "nan":
        good.loc[100:110, "F"] = np.nan
        good.to_csv(path, index=False)
    elif what == "binary":
        path.write_bytes(bytes(range(256)) * 20)
    elif what == "three samples":
        good.head(3).to_csv(path, index=False)
    else:
        path.write_text("hello world\nthis is not, data\n")


@pytest.mark.parametrize("what", ["nan", "binary", "three samples", "text"])
def test_one_bad_file_among_good_ones_is_named(what, tmp_path, capsys) -> None:
    data = _folder(tmp_path / "d")
    _bad_file(data / "zz_bad.csv", what)
    for args in (
        ["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")],
        ["study", str(data), "--out", str(tmp_path / "o"), "--models", "sp2", "--workers", "1"],
        ["info", str(data)],
    ):
        line = _one_line_error(*_run(args, capsys)[::2])
        assert "zz_bad.csv" in line, (args, line)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


def test_record_truncated_while_a_study_runs_is_named(tmp_path, capsys, monkeypatch) -> None:
    from mrdamper.data.readers.records import RecordSource

    data = _folder(tmp_path / "d")
    real = RecordSource.load

    def truncating(self: RecordSource) -> Any:
        p = Path(self.file.path)
        if p.name == "rec_b.csv" and p.stat().st_size > 2000:
            lines = p.read_text().splitlines()
            p.write_text("\n".join(lines[: len(lines) // 2]) + "\n0.5,0.001,\n")
        return real(self)

    monkeypatch.setattr(RecordSource, "load", truncating)
    out = tmp_path / "o"
    args = ["study", str(data), "--out", str(out), "--models", "sp2", "--workers", "1"]
    _code, _, err = _run([*args, "--no-progress"], capsys)
    failed = pd.read_csv(out / "fits.csv") if out.exists() else None
    text = err + ("" if failed is None else failed.to_csv())
    assert "rec_b.csv" in text, text
    assert "non-finite" in text or "samples" in text


def test_ctrl_c_while_reading_does_not_blame_a_valid_file(tmp_path, capsys, monkeypatch) -> None:
    from mrdamper.data.readers import csv_reader

    data = _folder(tmp_path / "d")

    def interrupted(*_: Any, **__: Any) -> Any:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:  # what the C parser does with Ctrl-C
            raise pd.errors.ParserError("Error tokenizing data. C error: interrupted") from exc

    monkeypatch.setattr(csv_reader.pd, "read_csv", interrupted)
    for args in (
        ["info", str(data)],
        ["fit", "sp1", str(data), "--out", str(tmp_path / "m.json")],
        ["study", str(data), "--out", str(tmp_path / "o"), "--workers", "1"],
    ):
        code, _, err = _run(args, capsys)
        assert code == 130 and err.strip() == "interrupted", (args, err)


def test_too_many_folds_is_one_line(tmp_path, capsys) -> None:
    rec = write_csv(_sine("one", 0.5), tmp_path / "one.csv")
    line = _one_line_error(*_run(["select", str(rec), "--n-folds", "5000"], capsys)[::2])
    assert line.startswith("error: n_folds: 5000 time blocks") and "at most 80 folds" in line
