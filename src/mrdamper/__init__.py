"""mrdamper: identify, compare and export control-oriented models of MR dampers.

The public API is listed in ``__all__``; everything else is private. Importing the package has no
side effects. Names from the numba-backed parts (analysis, virtual rig, control export) are
re-exported lazily, so ``import mrdamper`` stays fast and loads no model module until one is asked
for.

Examples
--------
>>> import mrdamper
>>> "lpv" in mrdamper.known_kinds()
True
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.analysis import ZoneFit, ZoneLaws, fit_zone_laws, fit_zones
    from mrdamper.conformance import check_family
    from mrdamper.control import state_space, to_control
    from mrdamper.data import (
        Experiment,
        ExperimentSet,
        read,
        read_directory,
        write_csv,
        write_parquet,
    )
    from mrdamper.metrics import Scores, esr, fit_percent, nrmse, ssse
    from mrdamper.models import (
        Estimator,
        FittedModel,
        SimulationResult,
        available_models,
        get_estimator,
        known_kinds,
        load_model,
    )
    from mrdamper.rig import VirtualRig, reference_damper
    from mrdamper.rig.doe import table_ii
    from mrdamper.study import Protocol, StudyResult, load_protocol, run_study

from mrdamper.version import __version__

#: Public name -> module it comes from. Everything but the exceptions is imported on first use,
#: so ``import mrdamper`` (and the command line's start, which a background compilation may be
#: waiting for) loads neither pandas nor any model module.
_LAZY: dict[str, str] = {
    **dict.fromkeys(
        ["Experiment", "ExperimentSet", "read", "read_directory", "write_csv", "write_parquet"],
        "mrdamper.data",
    ),
    **dict.fromkeys(["Scores", "esr", "fit_percent", "nrmse", "ssse"], "mrdamper.metrics"),
    **dict.fromkeys(
        [
            "Estimator",
            "FittedModel",
            "SimulationResult",
            "available_models",
            "get_estimator",
            "known_kinds",
            "load_model",
        ],
        "mrdamper.models",
    ),
    **dict.fromkeys(["Protocol", "StudyResult", "load_protocol", "run_study"], "mrdamper.study"),
    **dict.fromkeys(["ZoneFit", "ZoneLaws", "fit_zone_laws", "fit_zones"], "mrdamper.analysis"),
    "VirtualRig": "mrdamper.rig",
    "reference_damper": "mrdamper.rig",
    "table_ii": "mrdamper.rig.doe",
    "check_family": "mrdamper.conformance",
    "state_space": "mrdamper.control",
    "to_control": "mrdamper.control",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'mrdamper' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


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
    "Protocol",
    "SchemaError",
    "Scores",
    "SimulationDivergedError",
    "SimulationResult",
    "StudyResult",
    "UnitError",
    "VirtualRig",
    "ZoneFit",
    "ZoneLaws",
    "__version__",
    "available_models",
    "check_family",
    "esr",
    "fit_percent",
    "fit_zone_laws",
    "fit_zones",
    "get_estimator",
    "known_kinds",
    "load_model",
    "load_protocol",
    "nrmse",
    "read",
    "read_directory",
    "reference_damper",
    "run_study",
    "ssse",
    "state_space",
    "table_ii",
    "to_control",
    "write_csv",
    "write_parquet",
]
