"""What a command writes into a file, so that ``--force`` replaces only a file of that kind.

A :class:`FileKind` names the kind (for messages) and recognises an existing file of it by its
first bytes: a JSON file with a given ``schema``, a CSV table whose header starts with given
columns, a PNG image, C code whose first comment names the file, a MAT file with a given
``schema`` variable. :func:`mrdamper._io.check_output` refuses, even with ``force``, to replace an
existing file its kind does not recognise: a user's data file, notes or configuration is never
overwritten by a typo in ``--out``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["FileKind", "c_code_kind", "csv_kind", "json_kind", "mat_kind", "png_kind"]

#: How many bytes of an existing file are read to recognise it (JSON model files are read whole).
_HEAD = 4096


@dataclass(frozen=True)
class FileKind:
    """A kind of file a command writes.

    Attributes
    ----------
    what : str
        Name of the kind in messages, e.g. ``"mrdamper model file (JSON)"``.
    recognise : callable
        ``recognise(path)`` is True when the existing file ``path`` is of this kind.
    """

    what: str
    recognise: Callable[[Path], bool]

    def matches(self, path: Path) -> bool:
        """True when ``path`` is of this kind (False when it cannot be read)."""
        try:
            return bool(self.recognise(path))
        except Exception:  # noqa: BLE001 - unreadable or not of the kind (scipy, json, decoding)
            return False


def _head(path: Path, n: int = _HEAD) -> bytes:
    with open(path, "rb") as fh:
        return fh.read(n)


def json_kind(what: str, schema: str) -> FileKind:
    """JSON files whose top-level object has ``"schema": schema``."""

    def recognise(path: Path) -> bool:
        data = json.loads(path.read_text(encoding="utf-8"))
        return isinstance(data, dict) and data.get("schema") == schema

    return FileKind(what, recognise)


def csv_kind(what: str, first_columns: Sequence[str]) -> FileKind:
    """CSV tables whose header row starts with ``first_columns``."""
    want = [c.strip() for c in first_columns]

    def recognise(path: Path) -> bool:
        line = _head(path).decode("utf-8", errors="replace").splitlines()[:1]
        cols = [c.strip() for c in line[0].split(",")] if line else []
        return cols[: len(want)] == want

    return FileKind(what, recognise)


def png_kind(what: str = "PNG figure") -> FileKind:
    """PNG images (recognised by their signature)."""
    return FileKind(what, lambda path: _head(path, 8) == b"\x89PNG\r\n\x1a\n")


def c_code_kind(what: str = "C code exported by mrdamper") -> FileKind:
    """C files whose first comment starts with their own name (``/* NAME.h: ...``), as
    :func:`mrdamper.control.export.c_export.c_source` writes them."""
    return FileKind(what, lambda path: _head(path, 256).startswith(f"/* {path.name}: ".encode()))


def mat_kind(what: str, schema: str) -> FileKind:
    """MATLAB files holding a variable ``schema`` equal to ``schema``."""

    def recognise(path: Path) -> bool:
        from scipy.io import loadmat

        value = loadmat(path, variable_names=["schema"]).get("schema")
        return value is not None and schema in [str(v).strip() for v in value.ravel()]

    return FileKind(what, recognise)
