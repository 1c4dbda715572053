"""Read the records named on a command line: files, and folders of record files."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mrdamper.data import Experiment

__all__ = ["ANY_RECORD_FILE", "read_paths"]

#: Regex for any record file in a folder (used when the sine-record pattern matches nothing).
ANY_RECORD_FILE = r".*\.(csv|txt|tsv|dat|parquet|pq|mat)"


def read_paths(paths: list[Path], pattern: str | None, read_kw: Mapping[str, Any]) -> list[Experiment]:
    """Read every file and folder of ``paths`` into one list of records, in the order given.

    Parameters
    ----------
    paths : list of Path
        Record files and folders.
    pattern : str or None
        File-name regex for folders (named groups become metadata). When None, a folder uses the
        sine-record pattern if any of its file names matches it, else :data:`ANY_RECORD_FILE`.
    read_kw : mapping
        Options of the file readers (see :func:`mrdamper.data.readers.read_csv`).

    Returns
    -------
    list of Experiment

    Raises
    ------
    FileNotFoundError
        If a path does not exist.
    """
    from mrdamper.data.readers import DEFAULT_PATTERN, parse_file_name, read_directory, read_file

    records: list[Experiment] = []
    for p in paths:
        if not p.exists():
            raise FileNotFoundError(f"{p}: no such file or folder")
        if p.is_dir():
            pat = pattern
            if pat is None:
                matches = any(parse_file_name(f.name, DEFAULT_PATTERN) for f in p.iterdir())
                pat = DEFAULT_PATTERN if matches else ANY_RECORD_FILE
            records.extend(read_directory(p, pat, **read_kw))
        else:
            records.append(read_file(p, **read_kw))
    return records
