"""Private file helpers shared by writers: atomic writes that never overwrite silently."""

from mrdamper._io.atomic import (
    atomic_write_bytes,
    atomic_write_text,
    atomic_write_with,
    check_writable,
)
from mrdamper._io.safety import check_output, protected_paths

__all__ = [
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_with",
    "check_output",
    "check_writable",
    "protected_paths",
]
