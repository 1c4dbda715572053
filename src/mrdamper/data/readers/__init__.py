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
    directory_files,
    parse_file_name,
    read,
    read_directory,
    read_file,
)
from mrdamper.data.readers.manifest import is_doe_folder
from mrdamper.data.readers.mat_reader import read_mat
from mrdamper.data.readers.parquet_reader import read_parquet
from mrdamper.data.readers.records import (
    ANY_RECORD_FILE,
    RecordFile,
    RecordSource,
    SourceSet,
    read_records,
    record_files,
    record_sources,
)

__all__ = [
    "ANY_RECORD_FILE",
    "COLUMN_ALIASES",
    "DEFAULT_PATTERN",
    "RecordFile",
    "RecordSource",
    "SourceSet",
    "directory_files",
    "is_doe_folder",
    "parse_file_name",
    "read",
    "read_csv",
    "read_directory",
    "read_file",
    "read_mat",
    "read_parquet",
    "read_records",
    "record_files",
    "record_sources",
]
