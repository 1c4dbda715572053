"""Atomic writes never leave a partial file and never overwrite without force."""

from __future__ import annotations

import pytest

from mrdamper import OutputExistsError
from mrdamper._io import atomic_write_text, atomic_write_with


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
