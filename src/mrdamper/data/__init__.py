"""Experiment records, collections, readers, writers, units and preprocessing."""

from mrdamper.data.experiment import CHANNELS, Experiment
from mrdamper.data.experiment_set import ExperimentSet, as_experiment_set
from mrdamper.data.readers import (
    COLUMN_ALIASES,
    RecordSource,
    SourceSet,
    read,
    read_csv,
    read_directory,
    read_mat,
    read_parquet,
    read_records,
    record_sources,
)
from mrdamper.data.writers import write_csv, write_parquet

__all__ = [
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
