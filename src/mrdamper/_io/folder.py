"""Write a whole output folder atomically: build it privately beside the target, then swap it in.

:func:`write_folder` is the one way a command writes a folder of results (a study, a DoE). The
caller's ``build`` function fills a private temporary folder created next to the target (same
file system, hidden name, mode 0700 while it is incomplete). When ``build`` returns, the folder
gets the permissions of an ordinary new folder and is renamed into place; a failure or an
interruption removes it and leaves the target as it was.

An existing non-empty target needs ``force`` (and, checked by :func:`mrdamper._io.check_output`,
mrdamper's mark), and then ``mode`` says what happens to it:

* ``"replace"``: the old folder is moved aside and removed once the new one is in place (a study:
  stale files of an earlier run must not look like part of this one);
* ``"merge"``: the new files are moved into the existing folder, replacing files of the same
  name and keeping the others (a DoE written again into its folder);
* ``"add"``: as ``"merge"``, into a folder that may hold anything else (quarter-car figures, C
  code): the caller checked each file it writes, and a folder mrdamper did not write gets no mark.

Every folder written gets the mark file :data:`~mrdamper._io.mark.MARK_NAME` (JSON: written by
mrdamper, the path it was written for, every file and folder it wrote at every depth with each
file's checksum, :mod:`mrdamper._io.mark`), which later lets ``force`` replace those and nothing
else. The private folder is named ``.NAME.partial-<pid>-<random>`` and carries a temporary mark
(the target, the process) from its creation; a run that was killed leaves it behind, and the next
write of the same target removes it when its mark says so (:mod:`mrdamper._io.stale`).

Permissions are obtained portably, without reading the process umask: the mode an ordinary new
folder gets is read from a probe folder created with :func:`os.mkdir` inside the private folder.
"""

from __future__ import annotations

import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

from mrdamper._io.kinds import FileKind
from mrdamper._io.mark import (
    MARK_NAME,
    foreign_entries,
    read_mark,
    scan,
    write_mark,
    write_temporary_mark,
)
from mrdamper._io.safety import FolderMode, resolved
from mrdamper._io.stale import missing_parents, remove_created, remove_stale, temp_prefix
from mrdamper.errors import OutputError, OutputExistsError

__all__ = [
    "FolderMode",
    "ordinary_folder_mode",
    "write_files",
    "write_folder",
    "write_mark",
]


def ordinary_folder_mode(parent: Path) -> int:
    """Permission bits [octal] a folder created with a plain :func:`os.mkdir` in ``parent`` gets.

    Parameters
    ----------
    parent : Path
        An existing writable folder (a probe folder is created in it and removed).

    Returns
    -------
    int
        The permission bits, for example ``0o755`` under the usual umask 022.
    """
    probe = _new_entry(parent, ".mode-probe-", lambda p: os.mkdir(p))
    try:
        return stat.S_IMODE(probe.stat().st_mode)
    finally:
        probe.rmdir()


def _new_entry(parent: Path, prefix: str, create: Callable[[Path], object]) -> Path:
    """Create a new entry with an unused random name in ``parent`` by ``create(path)``."""
    for _ in range(100):
        p = parent / f"{prefix}{secrets.token_hex(6)}"
        try:
            create(p)
        except FileExistsError:
            continue
        return p
    raise FileExistsError(f"{parent}: no free temporary name")  # pragma: no cover


def _merge(src: Path, dst: Path, force: bool) -> None:
    """Move every entry of ``src`` into the existing folder ``dst`` (files of the same name are
    replaced when ``force``; folders present in both are merged)."""
    for entry in sorted(src.iterdir()):
        target = dst / entry.name
        if entry.is_dir() and not entry.is_symlink() and target.is_dir():
            _merge(entry, target, force)
        elif os.path.lexists(target) and not force and entry.name != MARK_NAME:
            raise OutputExistsError(
                f"{target}: appeared while writing; pass force=True to write it"
            )
        else:
            os.replace(entry, target)


def _mark(tmp: Path, out: Path, mode: FolderMode) -> None:
    """Mark the built folder ``tmp`` (to become ``out``): every entry it holds with its checksum,
    plus (merge / add) the entries of ``out``'s valid mark that are still as written; no mark
    when adding to a folder mrdamper did not write."""
    new = scan(tmp)
    if mode == "replace" or not out.is_dir() or not any(out.iterdir()):
        write_mark(tmp, out, new)
        return
    old = read_mark(out)
    if old is None or old["path"] != str(resolved(out)):
        (tmp / MARK_NAME).unlink(missing_ok=True)  # the temporary mark: not carried into out
        return
    found = scan(out)
    kept = {k: v for k, v in old["entries"].items() if found.get(k) == v}
    write_mark(tmp, out, kept | new)


def _recheck(out: Path) -> None:
    """Refuse to replace / merge into ``out`` if something not mrdamper's appeared in it while
    the new folder was built (checked again just before the swap)."""
    why, foreign = foreign_entries(out)
    if why is not None or foreign:
        raise OutputError(
            f"--out: {out} changed while writing ({why or ', '.join(foreign[:3])}); it is never "
            "replaced, even with --force; nothing was written"
        )


def _swap(tmp: Path, out: Path, force: bool, mode: FolderMode) -> None:
    if not out.exists():
        os.replace(tmp, out)
        return
    if not any(out.iterdir()):
        out.rmdir()
        os.replace(tmp, out)
        return
    if mode == "add":
        _merge(tmp, out, force)
        return
    if not force:  # re-check: the folder may have been filled while this one was built
        raise OutputExistsError(f"{out}: folder filled while writing; pass force=True to write it")
    _recheck(out)
    if mode == "merge":
        _merge(tmp, out, force)
        return
    trash = Path(tempfile.mkdtemp(prefix=temp_prefix(out, "old-"), dir=out.parent))
    write_temporary_mark(trash, out)
    os.replace(out, trash / out.name)
    os.replace(tmp, out)
    shutil.rmtree(trash, ignore_errors=True)


def write_folder(
    out: str | os.PathLike[str],
    build: Callable[[Path], object],
    *,
    force: bool = False,
    mode: FolderMode = "replace",
) -> Path:
    """Build a folder with ``build(tmp)`` in a private sibling folder, then move it to ``out``.

    The caller checks ``out`` first (:func:`mrdamper._io.check_output`): this function only
    re-checks that an existing folder did not fill up in the meantime.

    Parameters
    ----------
    out : path-like
        Target folder: absent, empty, or (with ``force``) replaced / merged into per ``mode``.
    build : callable
        ``build(tmp)`` writes every output file into the folder ``tmp``.
    force : bool
        Allow an existing non-empty target (``"add"``: replacing files of the same name).
    mode : {"replace", "merge", "add"}
        With ``force``: replace the old folder, or move the new files into it (same-name files
        replaced, others kept); ``"add"``: move them into a folder whose other contents may be
        anything.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    OutputExistsError
        The target is a non-empty folder and ``force`` is false.
    OSError
        Writing failed; the error names ``out``, not the temporary folder, and nothing of the
        partial output is left.
    """
    if mode not in ("replace", "merge", "add"):
        raise ValueError(f"mode: expected 'replace', 'merge' or 'add', got {mode!r}")
    target = Path(os.path.abspath(out))  # "." and ".." have no name to swap with
    created = missing_parents(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(target)
    tmp = Path(tempfile.mkdtemp(prefix=temp_prefix(target, "partial-"), dir=target.parent))
    done = False
    try:
        write_temporary_mark(tmp, target)
        build(tmp)
        _mark(tmp, target, mode)
        tmp.chmod(ordinary_folder_mode(tmp))
        _swap(tmp, target, force, mode)
        done = True
    except OSError as exc:
        if isinstance(exc, FileExistsError) or exc.errno is None:
            raise
        raise OSError(exc.errno, exc.strerror, str(target)) from exc  # name the output folder
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if not done:
            remove_created(created)
    return Path(out)


def write_files(
    out: str | os.PathLike[str],
    files: Mapping[str, tuple[FileKind | None, Callable[[Path], object]]],
    *,
    force: bool = False,
) -> Path:
    """Write named files into the folder ``out``, all or none; its other contents are kept.

    Each file is checked first (absent, or with ``force`` of its kind, see
    :func:`mrdamper._io.check_output`); then every file is written into a private folder beside
    ``out`` and moved in together (:func:`write_folder`, ``mode="add"``), so a failure leaves
    none of them, and no folder it created.

    Parameters
    ----------
    out : path-like
        Target folder (created if missing; checked by the caller with ``mode="add"``).
    files : mapping
        File name -> (kind of file, or None for any; ``writer(path)`` that writes it).
    force : bool
        Replace existing files of the same names (of their kind).

    Returns
    -------
    Path
        ``out``.
    """
    from mrdamper._io.atomic import atomic_write_with, check_writable

    folder = Path(out)
    for name, (kind, _) in files.items():
        check_writable(folder / name, force, kind=kind)

    def build(tmp: Path) -> None:
        for name, (_, writer) in files.items():
            atomic_write_with(tmp / name, writer)

    return write_folder(folder, build, force=force, mode="add")
