"""Leftovers of an earlier run that died: private temporaries whose owner process is gone.

Every temporary a writer makes beside its target is a folder named with the id of the process
that made it (``.NAME.partial-<pid>-<random>``: a folder being built, or holding the ``NAME.part``
of a file being written; ``.NAME.old-<pid>-<random>``: a folder being replaced).
A process that ends normally, fails, is interrupted (Ctrl-C) or terminated (SIGTERM) removes its
own; one killed outright (SIGKILL, power loss) cannot. :func:`remove_stale` removes, before a new
write of the same target, the temporaries of that target whose process no longer runs, so a
rerun never leaves a hidden partial folder behind. A folder is a temporary only when it carries
the temporary mark of a write of that target by that process (:mod:`mrdamper._io.mark`): a folder
that merely has such a name is the user's and is left alone, as are the temporaries of a running
process (another mrdamper writing the same target).
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

from mrdamper._io.mark import read_temporary_mark

__all__ = ["missing_parents", "owner_alive", "remove_created", "remove_stale", "temp_prefix"]


#: A temporary's name: ``.NAME.partial-<pid>-<random>`` / ``.NAME.old-<pid>-<random>`` (random
#: part by :func:`tempfile.mkdtemp`).
_TEMP_FOLDER = re.compile(r"\.(?P<name>.+)\.(?P<tag>partial-|old-)(?P<pid>\d+)-[A-Za-z0-9_]+")


def temp_prefix(target: Path, tag: str) -> str:
    """Prefix of this process's temporaries of ``target``: ``.NAME.<tag><pid>-``."""
    return f".{target.name}.{tag}{os.getpid()}-"


def owner_alive(pid: int) -> bool:
    """True if a process ``pid`` exists (it may belong to another user)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:  # pragma: no cover - platform without signals to processes
        return True
    return True


def remove_stale(target: Path, tags: tuple[str, ...] = ("partial-", "old-")) -> list[Path]:
    """Remove the temporaries of ``target`` left by processes that no longer run.

    A folder is removed only when it carries the temporary mark of a write of ``target``
    (:func:`mrdamper._io.mark.read_temporary_mark`: its own name, the target's path and the id of
    the process, the one in its name) and that process is gone. Anything else, whatever its name,
    is left alone.

    Parameters
    ----------
    target : Path
        The output (file or folder) whose temporaries are looked for in its parent folder.
    tags : tuple of str
        Kinds of temporaries: ``"partial-"`` (folders being built, or holding a file being
        written) and ``"old-"`` (folders being replaced).

    Returns
    -------
    list of Path
        What was removed.
    """
    parent = target.parent
    removed: list[Path] = []
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return removed
    for entry in entries:
        path = Path(entry.path)
        m = _TEMP_FOLDER.fullmatch(entry.name)
        if m is None or m["name"] != target.name or m["tag"] not in tags:
            continue
        pid = int(m["pid"])
        if (
            entry.is_dir(follow_symlinks=False)
            and read_temporary_mark(path, target) == pid
            and not owner_alive(pid)
        ):
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def missing_parents(target: Path) -> list[Path]:
    """The ancestors of ``target`` that do not exist yet, innermost first (the folders a write
    of ``target`` creates)."""
    return [p for p in Path(os.path.abspath(target)).parents if not os.path.lexists(p)]


def remove_created(folders: list[Path]) -> None:
    """Remove the folders a failed write created (innermost first), if they are still empty."""
    for p in folders:
        try:
            p.rmdir()
        except OSError:
            return
