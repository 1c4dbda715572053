"""The mark of an output folder: what mrdamper wrote there, at every depth, and for which path.

Every folder mrdamper writes (:func:`mrdamper._io.write_folder`) carries the JSON file
:data:`MARK_NAME`::

    {"written_by": "mrdamper", "version": "...", "format": 2,
     "path": "/abs/path/the/folder/was/written/for",
     "entries": {"models": "folder", "models/sp1.json": "sha256:<hex>", ...}}

``entries`` lists every file and folder written, at every depth, as a relative POSIX path, with
the SHA-256 of each file's content. ``--force`` replaces a folder (:func:`foreign_entries` finds
nothing) only when the mark was written for this very path (a copied or moved mark authorises
nothing) and every entry in the folder is listed with the content it was written with: a file the
user added, edited or linked, at any depth, keeps the whole folder out of reach.

A mark is input to validate, not a path to trust: a mark whose entries are not plain relative
paths (``..``, ``/``, absolute paths, empty parts) is not a mark. The private temporaries of a
write carry a temporary mark (:func:`write_temporary_mark`: the target, the writing process and
the temporary's own name), so a clean-up (:mod:`mrdamper._io.stale`) removes only folders that
a run of mrdamper created for that target.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from pathlib import Path
from typing import Any

from mrdamper._io.paths import resolved

__all__ = [
    "FOLDER",
    "MARK_FORMAT",
    "MARK_NAME",
    "foreign_entries",
    "read_mark",
    "read_temporary_mark",
    "scan",
    "scan_file",
    "write_mark",
    "write_temporary_mark",
]

#: Name of the mark file every output folder mrdamper writes carries.
MARK_NAME = ".mrdamper-output"
#: Version of the mark's layout (1: top-level names only, no checksums: never trusted).
MARK_FORMAT = 2
#: Value of a folder in the mark's entries (files have ``sha256:<hex>``).
FOLDER = "folder"
#: Value of anything that is neither a regular file nor a folder (never written by mrdamper).
_OTHER = "other"
_DIGEST = re.compile(r"sha256:[0-9a-f]{64}")


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return f"sha256:{h.hexdigest()}"


def scan_file(path: Path) -> str:
    """``"folder"``, ``"sha256:<hex>"`` of a regular file or ``"other"`` (links not followed)."""
    mode = os.lstat(path).st_mode
    if stat.S_ISDIR(mode):
        return FOLDER
    return _digest(path) if stat.S_ISREG(mode) else _OTHER


def scan(folder: Path) -> dict[str, str]:
    """Every entry under ``folder`` at every depth (its top-level mark excluded): relative POSIX
    path -> ``"folder"``, ``"sha256:<hex>"`` of a regular file, or ``"other"`` (a symbolic link,
    device, pipe or socket; links are never followed)."""
    out: dict[str, str] = {}
    for root, dirs, files in os.walk(folder, followlinks=False):
        rel_root = Path(root).relative_to(folder)
        for name in sorted(dirs + files):
            rel = (rel_root / name).as_posix()
            if rel != MARK_NAME:
                out[rel] = scan_file(Path(root) / name)
    return out


def _plain(entry: Any) -> bool:
    """A relative POSIX path with no empty, ``.`` or ``..`` part (nothing a mark may point
    outside its folder with)."""
    if not (isinstance(entry, str) and entry and "\\" not in entry and "\0" not in entry):
        return False
    parts = entry.split("/")
    return entry != MARK_NAME and all(p not in ("", ".", "..") for p in parts)


def _target(folder: Path) -> str:
    return str(resolved(folder))


def _load(folder: Path) -> dict[str, Any] | None:
    try:
        data: Any = json.loads((folder / MARK_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not (isinstance(data, dict) and data.get("written_by") == "mrdamper"):
        return None
    return data


def read_mark(folder: Path) -> dict[str, Any] | None:
    """The valid mark of ``folder`` (``path``, ``entries``), or None when it has none.

    Not a mark: no file, unreadable JSON, not written by mrdamper, an earlier layout (no
    checksums), no ``path``, or an entry that is not a plain relative path or whose value is
    neither ``"folder"`` nor a SHA-256.
    """
    data = _load(folder)
    if data is None or data.get("format") != MARK_FORMAT or not isinstance(data.get("path"), str):
        return None
    entries = data.get("entries")
    if not isinstance(entries, dict):
        return None
    for name, value in entries.items():
        if not _plain(name) or not (value == FOLDER or _DIGEST.fullmatch(str(value))):
            return None
    return data


def foreign_entries(folder: Path) -> tuple[str | None, list[str]]:
    """Why ``--force`` may not replace ``folder`` (None if it may) and what is not mrdamper's.

    Returns
    -------
    why : str or None
        ``None`` when ``folder`` has a valid mark written for its own path; else the reason.
    foreign : list of str
        Entries (relative paths) not listed in the mark, or listed with another content or type
        (a file the user added or changed, a link); empty when nothing but mrdamper's files is
        there.
    """
    data = _load(folder)
    if data is None:
        return f"it has no {MARK_NAME} mark", []
    mark = read_mark(folder)
    if mark is None:
        why = f"its {MARK_NAME} mark is not valid (an earlier layout without checksums, or forged"
        return why + " entries)", []
    if mark["path"] != _target(folder):
        return f"its mark was written for {mark['path']} (a copied or moved mark)", []
    listed: dict[str, str] = mark["entries"]
    found = scan(folder)
    foreign = [name for name, value in found.items() if listed.get(name) != value]
    return None, foreign


def write_mark(folder: Path, target: Path, entries: dict[str, str] | None = None) -> Path:
    """Write the mark of ``folder`` (about to become ``target``) listing ``entries`` (default:
    everything in ``folder`` now, :func:`scan`)."""
    listed = scan(folder) if entries is None else entries
    data = {
        "written_by": "mrdamper",
        "version": _version(),
        "format": MARK_FORMAT,
        "path": _target(target),
        "entries": {k: v for k, v in sorted(listed.items()) if v != _OTHER},
    }
    path = folder / MARK_NAME
    path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    return path


def write_temporary_mark(folder: Path, target: Path) -> Path:
    """Mark the private temporary ``folder`` of a write of ``target`` by this process."""
    data = {
        "written_by": "mrdamper",
        "format": MARK_FORMAT,
        "temporary": folder.name,
        "path": _target(target),
        "pid": os.getpid(),
    }
    path = folder / MARK_NAME
    path.write_text(json.dumps(data) + "\n", encoding="utf-8")
    return path


def read_temporary_mark(folder: Path, target: Path) -> int | None:
    """The id of the process that made the temporary ``folder`` of ``target``, or None when
    ``folder`` does not carry its temporary mark (its own name, the target's path)."""
    data = _load(folder)
    if data is None or data.get("temporary") != folder.name:
        return None
    pid = data.get("pid")
    if not isinstance(pid, int) or data.get("path") != _target(target):
        return None
    return pid


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("mrdamper")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown"
