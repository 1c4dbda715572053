"""Where an output may go, and what ``--force`` may replace: the one place this is decided.

Every writer (model files, CSV, study folders, DoE folders, figures, C code) calls
:func:`check_output` before any computing, so a bad ``--out`` fails at once with one line naming
it and nothing is lost:

* never, with or without ``force``: onto an input or a folder holding one, the current working
  folder or one of its ancestors, the home folder, or the root of a repository (a folder holding
  ``.git``);
* an existing target must be a regular file (file outputs) or a folder (folder outputs); device
  nodes, pipes and sockets are refused even with ``force``;
* an existing file needs ``force``, and is then replaced only when it is of the kind the command
  writes (:class:`~mrdamper._io.kinds.FileKind`: a model file, a table with the command's
  columns, ...);
* an existing non-empty folder needs ``force``, and is then replaced (or merged into) only when
  mrdamper wrote it: it carries the mark file :data:`MARK_NAME` (written by
  :func:`mrdamper._io.write_folder`) for this very path, and holds nothing, at any depth, that the
  mark does not list with the same content (:mod:`mrdamper._io.mark`);
* the nearest existing ancestor folder must accept a new file (checked by creating and removing
  an empty temporary file, which also detects read-only file systems).

Paths that cannot be resolved (a symbolic link loop, a dangling link) are one-line errors.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Literal

from mrdamper._io.kinds import FileKind
from mrdamper._io.mark import MARK_NAME, foreign_entries
from mrdamper._io.paths import resolved
from mrdamper.errors import OutputError, OutputExistsError

__all__ = [
    "MARK_NAME",
    "FolderMode",
    "check_output",
    "protected_paths",
    "resolved",
]

#: What ``force`` does to an existing non-empty target folder: ``"replace"`` it, ``"merge"`` the
#: new files into it, or ``"add"`` named files to a folder whose other contents are kept (and
#: may be anything: only the files written are checked).
FolderMode = Literal["replace", "merge", "add"]


def protected_paths(inputs: Iterable[str | os.PathLike[str]] = ()) -> list[Path]:
    """Resolved paths an output must never replace: the inputs, the current working folder and
    the home folder."""
    out = [resolved(p, "input") for p in inputs if str(p)]
    out.append(resolved(Path.cwd()))
    out.append(_home())
    return out


def _home() -> Path:
    try:
        return resolved(Path.home())
    except (RuntimeError, KeyError, OutputError):  # no home folder known
        return Path("/")


def _overlap(target: Path, inputs: list[Path], cwd: Path) -> str | None:
    if target == cwd or target in cwd.parents:
        return "is the current folder or one of its ancestors"
    if target == _home():
        return "is the home folder"
    for inp in inputs:
        if target == inp:
            return f"is an input ({inp})"
        if target in inp.parents:
            return f"contains an input ({inp})"
    if os.path.lexists(target / ".git"):
        return "is the root of a repository (it holds .git)"
    return None


def _nearest_existing(p: Path) -> Path:
    cur = p
    while not os.path.lexists(cur) and cur != cur.parent:
        cur = cur.parent
    return cur


def _check_replaceable_folder(p: Path, option: str) -> None:
    """Raise unless everything in the non-empty folder ``p``, at every depth, is what mrdamper
    wrote for this path (:func:`mrdamper._io.mark.foreign_entries`)."""
    why, foreign = foreign_entries(p)
    if why is not None:
        raise OutputError(
            f"{option}: {p} is a non-empty folder mrdamper did not write ({why}); it is never "
            "replaced, even with --force; choose another output location"
        )
    if foreign:
        shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
        raise OutputError(
            f"{option}: {p} holds files mrdamper did not write or that changed since ({shown}); "
            "it is never replaced, even with --force; choose another output location"
        )


def _check_existing_file(
    p: Path, mode: int, force: bool, kind: FileKind | None, option: str
) -> None:
    if stat.S_ISDIR(mode):
        raise OutputError(f"{option}: {p} is a folder, expected a file path")
    if not stat.S_ISREG(mode):
        raise OutputError(
            f"{option}: {p} is not a regular file (device, pipe or socket); it is never replaced"
        )
    if not force:
        raise OutputExistsError(
            f"{p}: already exists; pass --force (Python: force=True) to overwrite"
        )
    if kind is not None and not kind.matches(p):
        raise OutputError(
            f"{option}: {p} is not a {kind.what}; it is never replaced, even with --force; "
            "choose another output location"
        )
    changed = _changed_in_marked_folder(p)
    if changed:
        raise OutputError(
            f"{option}: {p} {changed}; it is never replaced, even with --force; choose another "
            "output location"
        )


def _changed_in_marked_folder(p: Path) -> str | None:
    """Why the existing file ``p`` inside a folder mrdamper marked (the nearest ancestor with a
    mark) is not the file it wrote there (not listed, or another content), or None (listed
    unchanged, or no marked folder around it)."""
    from mrdamper._io.mark import read_mark, scan_file

    target = resolved(p)
    for folder in target.parents:
        if not os.path.lexists(folder / MARK_NAME):
            continue
        mark = read_mark(folder)
        if mark is None or mark["path"] != str(folder):
            return None
        listed = mark["entries"].get(target.relative_to(folder).as_posix())
        if listed is None:
            return f"is not a file mrdamper wrote in {folder} (its {MARK_NAME} does not list it)"
        if listed != scan_file(p):
            return "changed since mrdamper wrote it"
        return None
    return None


def check_output(
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    folder: bool = False,
    option: str = "--out",
    kind: FileKind | None = None,
    mode: FolderMode = "replace",
) -> Path:
    """Check that ``path`` may be written; return it as a Path.

    Parameters
    ----------
    path : path-like
        Output file, or folder when ``folder``.
    force : bool
        Allow replacing an existing file of ``kind`` / a non-empty folder mrdamper wrote.
    inputs : iterable of path-like
        Files and folders read by the same command; the output may not be or contain any of them.
    folder : bool
        The output is a folder (else a file).
    option : str
        Name of the option in messages.
    kind : FileKind, optional
        File outputs: the kind of file the command writes; with ``force`` an existing file is
        replaced only if it is of this kind (None: any regular file).
    mode : {"replace", "merge", "add"}
        Folder outputs: ``"add"`` keeps the folder's other contents (only the files written are
        checked, by the caller), so a non-empty folder is accepted without ``force`` or a mark.

    Raises
    ------
    OutputError
        The target is an input, contains one, is the working folder or an ancestor, the home
        folder or a repository root, is not a regular file / folder, is an existing file not of
        ``kind`` or a folder mrdamper did not write, is a link loop, or its location cannot be
        written.
    OutputExistsError
        The target exists (file, or non-empty folder outside ``"add"``) and ``force`` is false.
    """
    p = Path(path)
    if not str(path):
        raise OutputError(f"{option}: expected a path, got an empty string")
    target = resolved(p, option)
    cwd = resolved(Path.cwd())
    why = _overlap(target, [resolved(i, "input") for i in inputs if str(i)], cwd)
    if why is not None:
        raise OutputError(f"{option}: {p} {why}; choose another output location")
    if os.path.lexists(p):
        try:
            st_mode = os.stat(p).st_mode
        except OSError:  # broken symbolic link: writing would go through it
            raise OutputError(
                f"{option}: {p} is a broken symbolic link; choose another output location"
            ) from None
        if not folder:
            _check_existing_file(p, st_mode, force, kind, option)
        elif not stat.S_ISDIR(st_mode):
            raise OutputError(
                f"{option}: {p} exists and is not a folder; choose another output location"
            )
        elif mode != "add" and any(p.iterdir()):
            if not force:
                raise OutputExistsError(
                    f"{p}: folder exists and is not empty; pass --force (Python: force=True) to "
                    "replace it or choose another output location"
                )
            _check_replaceable_folder(p, option)
    base = _nearest_existing(target.parent)
    if not base.is_dir():
        raise OutputError(f"{option}: {base} is not a folder, so {p} cannot be created")
    try:
        _probe(base)
    except OSError as exc:
        raise OutputError(f"{option}: cannot write in {base} ({exc.strerror or exc})") from None
    return p


def _probe(folder: Path) -> None:
    """Create and remove an empty file in ``folder``; raises OSError if it cannot be written."""
    with tempfile.TemporaryFile(dir=folder, prefix=".mrdamper-check-"):
        pass
