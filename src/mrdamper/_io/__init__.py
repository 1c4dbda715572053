"""Private file helpers shared by writers.

Atomic files and folders that never overwrite silently, and the one place that decides where an
output may go and what ``force`` may replace (:mod:`mrdamper._io.safety`).
"""

from mrdamper._io.atomic import (
    atomic_write_bytes,
    atomic_write_text,
    atomic_write_with,
    check_writable,
)
from mrdamper._io.folder import FolderMode, ordinary_folder_mode, write_files, write_folder
from mrdamper._io.kinds import FileKind, c_code_kind, csv_kind, json_kind, mat_kind, png_kind
from mrdamper._io.safety import MARK_NAME, check_output, protected_paths

__all__ = [
    "MARK_NAME",
    "FileKind",
    "FolderMode",
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_with",
    "c_code_kind",
    "check_output",
    "check_writable",
    "csv_kind",
    "json_kind",
    "mat_kind",
    "ordinary_folder_mode",
    "png_kind",
    "protected_paths",
    "write_files",
    "write_folder",
]
