"""Atomic file writes: write to a temporary file beside the target, then rename over it."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path

from mrdamper._io.kinds import FileKind
from mrdamper._io.mark import write_temporary_mark
from mrdamper._io.safety import check_output
from mrdamper._io.stale import missing_parents, remove_created, remove_stale, temp_prefix
from mrdamper.errors import OutputExistsError

__all__ = ["atomic_write_bytes", "atomic_write_text", "atomic_write_with", "check_writable"]


def check_writable(
    path: str | os.PathLike[str],
    force: bool,
    inputs: Iterable[str | os.PathLike[str]] = (),
    kind: FileKind | None = None,
    option: str = "--out",
) -> Path:
    """Return ``path`` as a Path after :func:`~mrdamper._io.safety.check_output` (file output;
    ``option`` names it in messages).

    Raises :class:`OutputExistsError` if it exists and not ``force``, and
    :class:`~mrdamper.errors.OutputError` if it is one of ``inputs``, not a regular file, not of
    ``kind`` (when given), or its folder cannot be written.
    """
    return check_output(path, force=force, inputs=inputs, kind=kind, option=option)


def atomic_write_with(
    path: str | os.PathLike[str],
    writer: Callable[[Path], object],
    *,
    force: bool = False,
    kind: FileKind | None = None,
) -> Path:
    """Call ``writer(tmp_path)`` then atomically move ``tmp_path`` to ``path``.

    ``tmp_path`` (``NAME.part``) lies in a private folder beside ``path`` that carries the
    temporary mark of this write (:func:`~mrdamper._io.mark.write_temporary_mark`), so a run
    killed outright leaves only a folder the next write of ``path`` recognises and removes. A
    failure or interruption leaves no partial file at ``path`` (and removes the temporary, and
    the folders created for it). With ``force`` an existing file is replaced only if it is of
    ``kind`` (when given; see :func:`~mrdamper._io.safety.check_output`).
    """
    p = check_writable(path, force, kind=kind)
    created = missing_parents(p)
    p.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(p, ("partial-",))
    tmp_path = _new_temp_file(p)
    try:
        writer(tmp_path)
        if p.exists() and not force:  # re-check: another process may have written meanwhile
            raise OutputExistsError(f"{p}: appeared while writing; pass force=True to overwrite")
        os.replace(tmp_path, p)
    except OSError as exc:
        shutil.rmtree(tmp_path.parent, ignore_errors=True)
        remove_created(created)
        if isinstance(exc, OutputExistsError) or exc.errno is None:
            raise
        raise OSError(
            exc.errno, exc.strerror, str(p)
        ) from exc  # name the output, not the temporary
    except BaseException:
        shutil.rmtree(tmp_path.parent, ignore_errors=True)
        remove_created(created)
        raise
    shutil.rmtree(tmp_path.parent, ignore_errors=True)
    return p


def _new_temp_file(target: Path) -> Path:
    """Create an empty ``NAME.part`` in a new private folder ``.NAME.partial-<pid>-<random>``
    beside ``target``, the folder carrying the temporary mark of this write.

    The file is created like a plain ``open`` would create it (mode 0666 filtered by the umask,
    by the operating system), so the finished file has ordinary permissions without reading the
    umask.
    """
    folder = Path(tempfile.mkdtemp(prefix=temp_prefix(target, "partial-"), dir=target.parent))
    try:
        write_temporary_mark(folder, target)
        tmp = folder / f"{target.name}.part"
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return tmp


def atomic_write_bytes(
    path: str | os.PathLike[str],
    data: bytes,
    *,
    force: bool = False,
    kind: FileKind | None = None,
) -> Path:
    """Write ``data`` to ``path`` atomically; refuse to overwrite unless ``force`` (and, when
    given, unless the existing file is of ``kind``)."""
    return atomic_write_with(path, lambda tmp: tmp.write_bytes(data), force=force, kind=kind)


def atomic_write_text(
    path: str | os.PathLike[str],
    text: str,
    *,
    force: bool = False,
    kind: FileKind | None = None,
) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically; refuse to overwrite unless ``force`` (and,
    when given, unless the existing file is of ``kind``)."""
    return atomic_write_bytes(path, text.encode("utf-8"), force=force, kind=kind)
