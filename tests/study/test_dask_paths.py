"""``mrdamper study --scheduler`` with workers that do not share the client's view of the files.

Each test starts a scheduler in this process and one worker in a separate process (``dask
worker``) whose working folder is another folder than the client's:

* records given as a relative path: the workers receive absolute paths, every fit succeeds;
* a worker that cannot read the record files (its ``open`` refuses them, as on a machine that
  does not mount them): the study notices once, in one ``note:`` line, reads the records itself
  and sends them; every fit succeeds.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pandas as pd
import pytest

from tests.cli.test_study_cli import _run, _write_sine_folder
from tests.conftest import REPO_ROOT

distributed = pytest.importorskip("distributed")

#: Preloaded by the worker: files under $MRDAMPER_TEST_HIDDEN cannot be opened there.
_HIDE = """
import builtins, os

_hidden = os.environ["MRDAMPER_TEST_HIDDEN"]
_open = getattr(builtins, "_unguarded_open", builtins.open)  # the module may be loaded twice
builtins._unguarded_open = _open


def _guarded(file, *args, **kwargs):
    if isinstance(file, (str, os.PathLike)) and os.fspath(file).startswith(_hidden):
        raise PermissionError(13, "Permission denied", os.fspath(file))
    return _open(file, *args, **kwargs)


builtins.open = _guarded
"""


@contextlib.contextmanager
def _cluster(cwd: Path, hidden: Path | None = None) -> Iterator[str]:
    """A scheduler here and one worker process started in ``cwd``; yields the address."""
    cwd.mkdir(exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(REPO_ROOT / "src"), str(REPO_ROOT), env.get("PYTHONPATH", "")]
    )
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    extra: list[str] = []
    if hidden is not None:
        hide = cwd / "hide_files.py"
        hide.write_text(_HIDE)
        env["MRDAMPER_TEST_HIDDEN"] = str(hidden)
        extra = ["--preload", str(hide)]
    with (
        distributed.LocalCluster(
            n_workers=0, processes=False, protocol="tcp", host="127.0.0.1", dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        addr = cluster.scheduler_address
        cmd = [sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1"]
        proc = subprocess.Popen(
            [*cmd, "--no-dashboard", *extra],
            cwd=cwd,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            client.wait_for_workers(1, timeout=120)
            yield addr
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def _study(addr: str, data: str, out: Path, capsys) -> tuple[int, str]:
    code, _stdout, stderr = _run(
        ["study", data, "--out", str(out), "--models", "sp2", "--scheduler", addr, "--no-progress"],
        capsys,
    )
    return code, stderr


@pytest.mark.slow
def test_worker_in_another_folder_gets_absolute_paths(tmp_path, capsys, monkeypatch) -> None:
    client_dir = tmp_path / "client"
    client_dir.mkdir()
    _write_sine_folder(client_dir / "sine")
    monkeypatch.chdir(client_dir)
    with _cluster(tmp_path / "worker_home") as addr:
        code, stderr = _study(addr, "sine", tmp_path / "out", capsys)  # a relative path
    assert code == 0, stderr
    assert "note:" not in stderr  # the worker reads the files itself
    res = pd.read_csv(tmp_path / "out" / "results.csv")
    assert len(res) == 6 and set(res["status"]) == {"ok"}


@pytest.mark.slow
def test_worker_that_cannot_read_the_files_gets_them_shipped(tmp_path, capsys) -> None:
    data = tmp_path / "private" / "sine"
    data.parent.mkdir()
    _write_sine_folder(data)
    with _cluster(tmp_path / "worker_home", hidden=tmp_path / "private") as addr:
        code, stderr = _study(addr, str(data), tmp_path / "out", capsys)
    assert code == 0, stderr
    notes = [ln for ln in stderr.splitlines() if ln.startswith("note: ")]
    assert len(notes) == 1, stderr
    assert "cannot read 6 of the 6 record files" in notes[0]
    assert "the records are read here and sent to the workers" in notes[0]
    res = pd.read_csv(tmp_path / "out" / "results.csv")
    assert len(res) == 6 and set(res["status"]) == {"ok"}
