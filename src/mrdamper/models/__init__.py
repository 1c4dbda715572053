"""Damper model families: estimators that identify them and immutable fitted models."""

from mrdamper.models.base import (
    Estimator,
    FittedModel,
    Identified,
    RangePolicy,
    SimulationResult,
    TrainingData,
    check_input_range,
)
from mrdamper.models.protocols import InvertibleModel, ScheduledForm, StaticMapForm
from mrdamper.models.registry import (
    available_models,
    get_estimator,
    known_kinds,
    load_model,
    model_class,
    model_from_dict,
    register,
)

__all__ = [
    "Estimator",
    "FittedModel",
    "Identified",
    "InvertibleModel",
    "RangePolicy",
    "ScheduledForm",
    "SimulationResult",
    "StaticMapForm",
    "TrainingData",
    "available_models",
    "check_input_range",
    "get_estimator",
    "known_kinds",
    "load_model",
    "model_class",
    "model_from_dict",
    "register",
]
