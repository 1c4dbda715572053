"""Experiment records, collections, readers, writers, units and preprocessing."""

from mrdamper.data.experiment import CHANNELS, Experiment
from mrdamper.data.experiment_set import ExperimentSet, as_experiment_set
from mrdamper.data.readers import (
    COLUMN_ALIASES,
    read,
    read_csv,
    read_directory,
    read_mat,
    read_parquet,
)
from mrdamper.data.writers import write_csv, write_parquet

__all__ = [
    "CHANNELS",
    "COLUMN_ALIASES",
    "Experiment",
    "ExperimentSet",
    "as_experiment_set",
    "read",
    "read_csv",
    "read_directory",
    "read_mat",
    "read_parquet",
    "write_csv",
    "write_parquet",
]
