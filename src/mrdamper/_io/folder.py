"""Write a whole output folder atomically: build it privately beside the target, then swap it in.

:func:`write_folder` is the one way a command writes a folder of results (a study, a DoE). The
caller's ``build`` function fills a private temporary folder created next to the target (same
file system, hidden name, mode 0700 while it is incomplete). When ``build`` returns, the folder
gets the permissions of an ordinary new folder and is renamed into place; a failure or an
interruption removes it and leaves the target as it was.

An existing non-empty target needs ``force``, and then ``mode`` says what happens to it:

* ``"replace"``: the old folder is moved aside and removed once the new one is in place (a study:
  stale files of an earlier run must not look like part of this one);
* ``"merge"``: the new files are moved into the existing folder, replacing files of the same
  name and keeping the others (a DoE written into a folder of records).

Permissions are obtained portably, without reading the process umask: the mode an ordinary new
folder gets is read from a probe folder created with :func:`os.mkdir` inside the private folder.
"""

from __future__ import annotations

import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Literal

from mrdamper.errors import OutputExistsError

__all__ = ["FolderMode", "ordinary_folder_mode", "write_folder"]

#: What ``force`` does to an existing non-empty target folder.
FolderMode = Literal["replace", "merge"]


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


def _merge(src: Path, dst: Path) -> None:
    """Move every entry of ``src`` into the existing folder ``dst`` (files of the same name are
    replaced; folders present in both are merged)."""
    for entry in sorted(src.iterdir()):
        target = dst / entry.name
        if entry.is_dir() and not entry.is_symlink() and target.is_dir():
            _merge(entry, target)
        else:
            os.replace(entry, target)


def _swap(tmp: Path, out: Path, force: bool, mode: FolderMode) -> None:
    if not out.exists():
        os.replace(tmp, out)
        return
    if not any(out.iterdir()):
        out.rmdir()
        os.replace(tmp, out)
        return
    if not force:  # re-check: the folder may have been filled while this one was built
        raise OutputExistsError(f"{out}: folder filled while writing; pass force=True to write it")
    if mode == "merge":
        _merge(tmp, out)
        return
    trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
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
        Allow an existing non-empty target.
    mode : {"replace", "merge"}
        With ``force``: replace the old folder, or move the new files into it (same-name files
        replaced, others kept).

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
    if mode not in ("replace", "merge"):
        raise ValueError(f"mode: expected 'replace' or 'merge', got {mode!r}")
    target = Path(os.path.abspath(out))  # "." and ".." have no name to swap with
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
    try:
        build(tmp)
        tmp.chmod(ordinary_folder_mode(tmp))
        _swap(tmp, target, force, mode)
    except OSError as exc:
        if isinstance(exc, FileExistsError) or exc.errno is None:
            raise
        raise OSError(exc.errno, exc.strerror, str(target)) from exc  # name the output folder
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return Path(out)
