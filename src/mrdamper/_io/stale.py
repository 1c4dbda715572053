"""Leftovers of an earlier run that died: private temporaries whose owner process is gone.

Every temporary a writer makes beside its target carries the id of the process that made it
(``.NAME.partial-<pid>-<random>``, ``.NAME.old-<pid>-<random>``, ``.NAME.<pid>-<random>.part``).
A process that ends normally, fails, is interrupted (Ctrl-C) or terminated (SIGTERM) removes its
own; one killed outright (SIGKILL, power loss) cannot. :func:`remove_stale` removes, before a new
write of the same target, the temporaries of that target whose process no longer runs, so a
rerun never leaves a hidden partial folder behind. Temporaries of a running process (another
mrdamper writing the same target) are left alone.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["missing_parents", "owner_alive", "remove_created", "remove_stale", "temp_prefix"]


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


def remove_stale(target: Path, tags: tuple[str, ...] = ("partial-", "old-", "")) -> list[Path]:
    """Remove the temporaries of ``target`` left by processes that no longer run.

    Parameters
    ----------
    target : Path
        The output (file or folder) whose temporaries are looked for in its parent folder.
    tags : tuple of str
        Kinds of temporaries: ``"partial-"`` (folders being built), ``"old-"`` (folders being
        replaced) and ``""`` (``.part`` files).

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
    base = f".{target.name}."
    for entry in entries:
        name = entry.name
        if not name.startswith(base):
            continue
        rest = name[len(base) :]
        for tag in tags:
            if not rest.startswith(tag):
                continue
            pid_text = rest[len(tag) :].split("-", 1)[0]
            if not pid_text.isdigit() or "-" not in rest[len(tag) :]:
                continue
            if tag == "" and not name.endswith(".part"):
                continue
            if owner_alive(int(pid_text)):
                break
            path = Path(entry.path)
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(path, ignore_errors=True)
            elif tag == "":
                path.unlink(missing_ok=True)
            else:
                break
            removed.append(path)
            break
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
