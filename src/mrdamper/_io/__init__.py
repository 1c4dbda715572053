"""Private file helpers shared by writers.

Atomic files and folders that never overwrite silently.
"""

from mrdamper._io.atomic import (
    atomic_write_bytes,
    atomic_write_text,
    atomic_write_with,
    check_writable,
)
from mrdamper._io.folder import FolderMode, ordinary_folder_mode, write_folder
from mrdamper._io.safety import check_output, protected_paths

__all__ = [
    "FolderMode",
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_with",
    "check_output",
    "check_writable",
    "ordinary_folder_mode",
    "protected_paths",
    "write_folder",
]
