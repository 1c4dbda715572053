"""Where an output may go: never onto an input, the working folder or its ancestors, or a device.

Every writer (model files, CSV, study folders, DoE folders) calls :func:`check_output` before any
computing, so a bad ``--out`` fails at once with one line and nothing is lost:

* the target must not be, or contain, one of the inputs (``inputs``), nor be the current working
  folder or one of its ancestors — with or without ``force``;
* an existing target must be a regular file (file outputs) or a folder (folder outputs); device
  nodes, pipes and sockets are refused even with ``force``;
* an existing non-empty target needs ``force``;
* the nearest existing ancestor folder must accept a new file (checked by creating and removing
  an empty temporary file, which also detects read-only file systems).
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from mrdamper.errors import OutputError, OutputExistsError

__all__ = ["check_output", "protected_paths"]


def _resolved(p: str | os.PathLike[str]) -> Path:
    return Path(os.path.abspath(Path(p).expanduser())).resolve(strict=False)


def protected_paths(inputs: Iterable[str | os.PathLike[str]] = ()) -> list[Path]:
    """Resolved paths an output must never replace: the inputs and the current working folder."""
    out = [_resolved(p) for p in inputs if str(p)]
    out.append(_resolved(Path.cwd()))
    return out


def _overlap(target: Path, inputs: list[Path], cwd: Path) -> str | None:
    if target == cwd or target in cwd.parents:
        return "is the current folder or one of its ancestors"
    for inp in inputs:
        if target == inp:
            return f"is an input ({inp})"
        if target in inp.parents:
            return f"contains an input ({inp})"
    return None


def _nearest_existing(p: Path) -> Path:
    cur = p
    while not cur.exists() and cur != cur.parent:
        cur = cur.parent
    return cur


def check_output(
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    folder: bool = False,
    option: str = "--out",
) -> Path:
    """Check that ``path`` may be written; return it as a Path.

    Parameters
    ----------
    path : path-like
        Output file, or folder when ``folder``.
    force : bool
        Allow replacing an existing regular file / non-empty folder.
    inputs : iterable of path-like
        Files and folders read by the same command; the output may not be or contain any of them.
    folder : bool
        The output is a folder (else a file).
    option : str
        Name of the option in messages.

    Raises
    ------
    OutputError
        The target is an input, contains one, is the working folder or an ancestor, is not a
        regular file / folder, or its location cannot be written.
    OutputExistsError
        The target exists (non-empty folder) and ``force`` is false.
    """
    p = Path(path)
    if not str(path):
        raise OutputError(f"{option}: expected a path, got an empty string")
    target = _resolved(p)
    cwd = _resolved(Path.cwd())
    why = _overlap(target, [_resolved(i) for i in inputs if str(i)], cwd)
    if why is not None:
        raise OutputError(f"{option}: {p} {why}; choose another output location")
    if os.path.lexists(p):
        try:
            mode = os.stat(p).st_mode
        except OSError:  # broken symbolic link: writing would go through it
            raise OutputError(
                f"{option}: {p} is a broken symbolic link; choose another output location"
            ) from None
        if folder:
            if not stat.S_ISDIR(mode):
                raise OutputError(
                    f"{option}: {p} exists and is not a folder; choose another output location"
                )
            if any(p.iterdir()) and not force:
                raise OutputExistsError(
                    f"{p}: folder exists and is not empty; pass --force (Python: force=True) to "
                    "replace it or choose another output location"
                )
        else:
            if stat.S_ISDIR(mode):
                raise OutputError(f"{option}: {p} is a folder, expected a file path")
            if not stat.S_ISREG(mode):
                raise OutputError(
                    f"{option}: {p} is not a regular file (device, pipe or socket); it is never "
                    "replaced"
                )
            if not force:
                raise OutputExistsError(
                    f"{p}: already exists; pass --force (Python: force=True) to overwrite"
                )
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
