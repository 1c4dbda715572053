"""Readers: CSV / text, Parquet, MATLAB v5 and v7.3, folders of records.

Every reader returns SI-unit :class:`~mrdamper.data.Experiment` records with their provenance in
``metadata`` (``source``, ``columns``, ``units``) and takes the same options: ``columns``,
``units``, ``nan_policy``, ``max_gap``, ``resample_fs``, ``fs``, ``derive_velocity``, ``name``,
``metadata``, ``time_tolerance``. See ``docs/data.md``.
"""

from mrdamper.data.readers._columns import COLUMN_ALIASES
from mrdamper.data.readers.csv_reader import read_csv
from mrdamper.data.readers.directory import (
    DEFAULT_PATTERN,
    parse_file_name,
    read,
    read_directory,
    read_file,
)
from mrdamper.data.readers.mat_reader import read_mat
from mrdamper.data.readers.parquet_reader import read_parquet

__all__ = [
    "COLUMN_ALIASES",
    "DEFAULT_PATTERN",
    "parse_file_name",
    "read",
    "read_csv",
    "read_directory",
    "read_file",
    "read_mat",
    "read_parquet",
]
