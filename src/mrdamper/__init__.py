"""mrdamper: identify, compare and export control-oriented models of MR dampers.

The public API is listed in ``__all__``; everything else is private. Importing the package has no
side effects and loads no model module until one is asked for.
"""

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import (
    DataValidationError,
    IdentificationError,
    MrDamperError,
    OutOfRangeError,
    OutputExistsError,
    SchemaError,
    SimulationDivergedError,
    UnitError,
)
from mrdamper.metrics import Scores, esr, fit_percent, nrmse, ssse
from mrdamper.models import (
    Estimator,
    FittedModel,
    SimulationResult,
    available_models,
    get_estimator,
    load_model,
)

__version__ = "0.1.0"

__all__ = [
    "DataValidationError",
    "Estimator",
    "Experiment",
    "ExperimentSet",
    "FittedModel",
    "IdentificationError",
    "MrDamperError",
    "OutOfRangeError",
    "OutputExistsError",
    "SchemaError",
    "Scores",
    "SimulationDivergedError",
    "SimulationResult",
    "UnitError",
    "__version__",
    "available_models",
    "esr",
    "fit_percent",
    "get_estimator",
    "load_model",
    "nrmse",
    "ssse",
]
