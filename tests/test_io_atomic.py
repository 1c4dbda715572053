"""Atomic writes never leave a partial file and never overwrite without force."""

from __future__ import annotations

import json

import pytest

from mrdamper import OutputExistsError
from mrdamper._io import MARK_NAME, atomic_write_text, atomic_write_with


def test_refuses_overwrite_and_forces(tmp_path) -> None:
    p = atomic_write_text(tmp_path / "a.txt", "one")
    with pytest.raises(OutputExistsError, match="force"):
        atomic_write_text(p, "two")
    assert p.read_text() == "one"
    atomic_write_text(p, "two", force=True)
    assert p.read_text() == "two"


def test_failure_leaves_nothing(tmp_path) -> None:
    def boom(tmp):
        tmp.write_text("partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write_with(tmp_path / "b.txt", boom)
    assert list(tmp_path.iterdir()) == []


def test_written_files_get_the_umask_mode(tmp_path) -> None:
    import os

    umask = os.umask(0o022)
    try:
        p = atomic_write_text(tmp_path / "c.txt", "x")
    finally:
        os.umask(umask)
    assert (p.stat().st_mode & 0o777) == 0o644


def _build(files: dict[str, str]):
    def build(tmp) -> None:
        for name, text in files.items():
            atomic_write_text(tmp / name, text)

    return build


def test_folder_replace_and_merge(tmp_path) -> None:
    from mrdamper._io import write_folder

    out = tmp_path / "out"
    write_folder(out, _build({"a.txt": "1", "b.txt": "1"}))
    with pytest.raises(OutputExistsError):
        write_folder(out, _build({"a.txt": "2"}))
    write_folder(out, _build({"a.txt": "2"}), force=True, mode="merge")
    files = {p.name: p.read_text() for p in out.iterdir() if p.name != MARK_NAME}
    assert files == {"a.txt": "2", "b.txt": "1"}
    assert sorted(json.loads((out / MARK_NAME).read_text())["entries"]) == ["a.txt", "b.txt"]
    write_folder(out, _build({"c.txt": "3"}), force=True, mode="replace")
    assert sorted(p.name for p in out.iterdir()) == [MARK_NAME, "c.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary left


def test_folder_failure_leaves_target_untouched(tmp_path) -> None:
    from mrdamper._io import write_folder

    out = tmp_path / "out"
    write_folder(out, _build({"a.txt": "1"}))

    def boom(tmp) -> None:
        atomic_write_text(tmp / "a.txt", "partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_folder(out, boom, force=True)
    assert (out / "a.txt").read_text() == "1"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_folder_gets_the_mode_of_an_ordinary_folder(tmp_path) -> None:
    import os

    from mrdamper._io import write_folder

    umask = os.umask(0o027)
    try:
        out = write_folder(tmp_path / "out", _build({"a.txt": "1"}))
    finally:
        os.umask(umask)
    assert (out.stat().st_mode & 0o777) == 0o750
    assert ((out / "a.txt").stat().st_mode & 0o777) == 0o640


def test_a_file_is_written_in_a_private_folder_carrying_its_temporary_mark(tmp_path) -> None:
    import os

    from mrdamper._io.mark import read_temporary_mark

    target = tmp_path / "a.txt"
    seen: list[int | None] = []

    def writer(tmp) -> None:
        seen.append(read_temporary_mark(tmp.parent, target))
        tmp.write_text("x")

    atomic_write_with(target, writer)
    assert seen == [os.getpid()] and target.read_text() == "x"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]
