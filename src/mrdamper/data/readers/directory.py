"""Read a folder of records into an ExperimentSet, with metadata parsed from file names, and
the generic :func:`read` that dispatches on the file suffix."""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mrdamper.data.experiment import Experiment
from mrdamper.data.experiment_set import ExperimentSet
from mrdamper.data.readers._build import missing
from mrdamper.data.readers.csv_reader import read_csv
from mrdamper.data.readers.mat_reader import read_mat
from mrdamper.data.readers.parquet_reader import read_parquet
from mrdamper.data.units import UNITS
from mrdamper.errors import DataValidationError

__all__ = [
    "DEFAULT_PATTERN",
    "SUFFIX_READERS",
    "directory_files",
    "parse_file_name",
    "read",
    "read_directory",
    "read_file",
]

#: File-name pattern of the constant-current sine records (``sine_5mm_3Hz_0.5A.csv``).
DEFAULT_PATTERN = (
    r"sine_(?P<condition>(?P<amplitude_mm>[\d.]+)mm_(?P<frequency>[\d.]+)Hz)"
    r"_(?P<current>[\d.]+)A\.csv"
)

#: File suffix (lower case) -> reader.
SUFFIX_READERS: dict[str, Any] = {
    ".csv": read_csv,
    ".txt": read_csv,
    ".tsv": read_csv,
    ".dat": read_csv,
    ".parquet": read_parquet,
    ".pq": read_parquet,
    ".mat": read_mat,
}

#: Options that only some file formats have: option -> suffixes whose reader takes it. A folder
#: may mix formats, so these are passed only to the readers that take them.
FORMAT_OPTIONS: dict[str, tuple[str, ...]] = {
    "sep": (".csv", ".txt", ".tsv", ".dat"),
    "decimal": (".csv", ".txt", ".tsv", ".dat"),
    "comment": (".csv", ".txt", ".tsv", ".dat"),
    "struct": (".mat",),
}

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")

#: Group-name suffix -> factor to SI (``amplitude_mm`` -> ``amplitude`` [m]); "/" becomes "_per_".
_SUFFIX_FACTORS: dict[str, float] = {
    u.replace("/", "_per_"): f for table in UNITS.values() for u, f in table.items()
}
_SUFFIX_FACTORS["Hz"] = 1.0
_SUFFIXES_LONGEST_FIRST = sorted(_SUFFIX_FACTORS, key=len, reverse=True)


def parse_file_name(file_name: str, pattern: str | re.Pattern[str]) -> dict[str, Any] | None:
    """Return the metadata encoded in ``file_name`` by the named groups of ``pattern``.

    The whole name must match. Group values that look like numbers become floats; a group name
    ending in ``_<unit>`` of the unit table (``_mm``, ``_kN``, ``_mm_per_s`` for mm/s, ``_Hz``)
    is stored without the suffix and converted to SI (``amplitude_mm="5"`` gives
    ``amplitude=0.005``). Groups that did not take part in the match are left out.

    Parameters
    ----------
    file_name : str
        File name (without folder).
    pattern : str or re.Pattern
        Regular expression with named groups that must match the whole name.

    Returns
    -------
    dict or None
        The metadata, or None if the name does not match.

    Examples
    --------
    >>> parse_file_name("sine_5mm_3Hz_0.5A.csv", DEFAULT_PATTERN)
    {'condition': '5mm_3Hz', 'amplitude': 0.005, 'frequency': 3.0, 'current': 0.5}
    """
    rx = _compile(pattern)
    m = rx.fullmatch(file_name)
    if m is None:
        return None
    out: dict[str, Any] = {}
    for key, text in m.groupdict().items():
        if text is None:
            continue
        factor = None
        for suffix in _SUFFIXES_LONGEST_FIRST:
            if key.endswith("_" + suffix) and len(key) > len(suffix) + 1:
                key, factor = key[: -len(suffix) - 1], _SUFFIX_FACTORS[suffix]
                break
        if _NUMBER.fullmatch(text):
            value: Any = float(text) * (factor if factor is not None else 1.0)
        elif factor is not None:
            raise DataValidationError(
                key,
                f"file name {file_name!r} gives {text!r}, expected a number "
                "(unit suffix in group name)",
            )
        else:
            value = text
        out[key] = value
    return out


def _compile(pattern: str | re.Pattern[str]) -> re.Pattern[str]:
    if isinstance(pattern, re.Pattern):
        return pattern
    try:
        return re.compile(pattern)
    except re.error as exc:
        raise DataValidationError(
            "pattern", f"{pattern!r} is not a valid regular expression ({exc})"
        ) from None


def _natural_key(text: str) -> list[Any]:
    return [
        (0, float(tok), "") if tok[0].isdigit() else (1, 0.0, tok)
        for tok in re.findall(r"\d+(?:\.\d+)?|\D+", text)
    ]


def read_file(path: str | os.PathLike[str], **kwargs: Any) -> Experiment:
    """Read one file with the reader for its suffix (see :data:`SUFFIX_READERS`).

    Parameters
    ----------
    path : path-like
        The file (``.csv/.txt/.tsv/.dat``, ``.parquet/.pq`` or ``.mat``).
    **kwargs
        Options of that reader (see :func:`~mrdamper.data.readers.read_csv`). Format-specific
        options (:data:`FORMAT_OPTIONS`: ``sep``, ``decimal``, ``comment`` for text, ``struct``
        for MATLAB) are passed only to the readers of those formats.

    Returns
    -------
    Experiment
        The record in SI units.

    Raises
    ------
    DataValidationError
        If the suffix is not known.
    """
    p = Path(path)
    reader = SUFFIX_READERS.get(p.suffix.lower())
    if reader is None:
        raise DataValidationError(
            "path", f"{p}: unknown file type {p.suffix!r}; expected one of {sorted(SUFFIX_READERS)}"
        )
    kw = {
        k: v
        for k, v in kwargs.items()
        if k not in FORMAT_OPTIONS or p.suffix.lower() in FORMAT_OPTIONS[k]
    }
    return reader(p, **kw)


def read_directory(
    path: str | os.PathLike[str],
    pattern: str | re.Pattern[str] = DEFAULT_PATTERN,
    *,
    recursive: bool = False,
    name: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    **read_kwargs: Any,
) -> ExperimentSet:
    """Read every file of a folder whose name matches ``pattern`` into an ExperimentSet.

    Parameters
    ----------
    path : path-like
        The folder.
    pattern : str or compiled regex
        Regular expression that the whole file name must match; its named groups become record
        metadata (see :func:`parse_file_name`). Files that do not match are skipped. The default
        reads the constant-current sine records ``sine_{amplitude}mm_{frequency}Hz_{current}A.csv``
        into ``condition``, ``amplitude`` [m], ``frequency`` [Hz] and ``current`` [A].
    recursive : bool
        Also search sub-folders (names are then relative paths without suffix).
    name : str, optional
        Name of the set (default: the folder name).
    metadata : mapping, optional
        Metadata added to every record; values parsed from a file name take precedence.
    **read_kwargs
        Passed to the file reader (``units``, ``columns``, ``nan_policy``, ``fs``, ...).

    Returns
    -------
    ExperimentSet
        Records in natural order of their names (numbers compared as numbers:
        ``sine_2mm`` before ``sine_10mm``); each record's name is its file stem.

    Raises
    ------
    FileNotFoundError
        If the folder does not exist.
    DataValidationError
        If ``path`` is not a folder, the pattern is invalid, no file matches it, or a matching
        name is a broken symbolic link; errors of a file's reader are raised as they are (their
        message names the file).

    Examples
    --------
    >>> s = read_directory("data/quiroz2022_utfsm/sine_unfiltered")  # doctest: +SKIP
    >>> s.filter(current=0.5, frequency=3.0).names  # doctest: +SKIP
    ['sine_5mm_3Hz_0.5A']
    """
    root = Path(path)
    records = [
        read_file(f, name=rec_name, metadata={**dict(metadata or {}), **meta}, **read_kwargs)
        for rec_name, f, meta in directory_files(root, pattern, recursive=recursive)
    ]
    return ExperimentSet(records, name=name or root.name)


def directory_files(
    path: str | os.PathLike[str],
    pattern: str | re.Pattern[str] = DEFAULT_PATTERN,
    *,
    recursive: bool = False,
) -> list[tuple[str, Path, dict[str, Any]]]:
    """The files :func:`read_directory` reads, without reading them.

    Parameters
    ----------
    path : path-like
        The folder.
    pattern : str or compiled regex
        Regular expression the whole file name must match (named groups become metadata).
    recursive : bool
        Also search sub-folders.

    Returns
    -------
    list of (str, Path, dict)
        ``(record name, file, metadata from the name)`` in natural order of the names.

    Raises
    ------
    FileNotFoundError
        If the folder does not exist.
    DataValidationError
        If ``path`` is not a folder, the pattern is invalid, no file matches it, or a matching
        name is a broken symbolic link.
    """
    root = Path(path)
    if not root.exists():
        raise FileNotFoundError(f"{root}: no such folder")
    if not root.is_dir():
        raise DataValidationError("path", f"{root} is not a folder")
    rx = _compile(pattern)
    files = root.rglob("*") if recursive else root.iterdir()
    found: list[tuple[str, Path, dict[str, Any]]] = []
    others: list[str] = []
    for f in files:
        if f.is_symlink() and not f.exists():
            if parse_file_name(f.name, rx) is not None:
                raise DataValidationError(
                    "path",
                    f"{f} is a broken symbolic link (its target {os.readlink(f)!r} does not exist)",
                )
            continue
        if not f.is_file():
            continue
        meta = parse_file_name(f.name, rx)
        if meta is None:
            others.append(f.name)
            continue
        rel = f.relative_to(root).with_suffix("")
        found.append((rel.as_posix(), f, meta))
    if not found:
        raise DataValidationError(
            "pattern",
            f"no file in {root} matches {rx.pattern!r} (files found: {sorted(others)[:5]}"
            f"{' ...' if len(others) > 5 else ''})",
        )
    found.sort(key=lambda item: _natural_key(item[0]))
    return found


def read(path: str | os.PathLike[str], **kwargs: Any) -> Experiment | ExperimentSet:
    """Read a file (by suffix) or a folder (with :func:`read_directory`).

    Parameters
    ----------
    path : path-like
        A ``.csv/.txt/.tsv/.dat``, ``.parquet/.pq`` or ``.mat`` file, or a folder.
    **kwargs
        Passed to the reader (for a folder: ``pattern``, ``recursive`` and reader options).

    Returns
    -------
    Experiment or ExperimentSet
        One record for a file, a set for a folder.
    """
    p = Path(path)
    if not p.exists():
        raise missing(p, "file or folder")
    if p.is_dir():
        return read_directory(p, **kwargs)
    return read_file(p, **kwargs)
