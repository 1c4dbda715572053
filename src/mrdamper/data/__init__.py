"""Experiment records, collections, readers, writers, units and preprocessing."""

from mrdamper.data.experiment import CHANNELS, Experiment
from mrdamper.data.experiment_set import ExperimentSet, as_experiment_set

__all__ = ["CHANNELS", "Experiment", "ExperimentSet", "as_experiment_set"]
