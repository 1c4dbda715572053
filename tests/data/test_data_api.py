"""Pin the public API of ``mrdamper.data`` and its readers: names and documented objects."""

from __future__ import annotations

import inspect

from mrdamper import data
from mrdamper.data import preprocessing, readers, units, writers


def test_data_exports() -> None:
    assert sorted(data.__all__) == sorted(
        [
            "CHANNELS",
            "COLUMN_ALIASES",
            "Experiment",
            "ExperimentSet",
            "RecordSource",
            "SourceSet",
            "as_experiment_set",
            "read",
            "read_csv",
            "read_directory",
            "read_mat",
            "read_parquet",
            "read_records",
            "record_sources",
            "write_csv",
            "write_parquet",
        ]
    )
    assert sorted(readers.__all__) == sorted(
        [
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
    )


def test_every_public_function_is_documented_with_its_parameters() -> None:
    for module in (data, readers, preprocessing, units, writers):
        for name in module.__all__:
            obj = getattr(module, name)
            if not callable(obj) or inspect.isclass(obj):
                continue
            if obj.__module__.endswith(("experiment", "experiment_set")):
                continue  # the record types are checked with their own tests
            doc = inspect.getdoc(obj) or ""
            assert doc, f"{module.__name__}.{name} has no docstring"
            for param in inspect.signature(obj).parameters:
                if param in ("kwargs", "kw"):
                    continue
                assert param in doc, f"{module.__name__}.{name}: parameter {param!r} not documented"
