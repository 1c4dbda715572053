"""The comparison study.

Protocols, the runner (models x records), result tables and the HTML report.

Examples
--------
>>> from mrdamper.study import doe_protocol, run_study, write_study  # doctest: +SKIP
>>> from mrdamper.rig.doe import table_ii                # doctest: +SKIP
>>> res = run_study(  # doctest: +SKIP
...     table_ii(seed=0, scale=0.1), doe_protocol(), models=["lpv", "sp1"]
... )
>>> res.summary                                          # doctest: +SKIP
>>> write_study(res, "study-out")                        # doctest: +SKIP
"""

from mrdamper.study.analysis_step import AnalysisOutcome, run_analysis
from mrdamper.study.control_step import ControlRelevance, ControlSettings
from mrdamper.study.default import choose_protocol, default_protocol
from mrdamper.study.executor import make_executor
from mrdamper.study.presets import (
    doe_protocol,
    dyke_protocol,
    load_protocol,
    preset_protocol,
    quiroz_protocol,
)
from mrdamper.study.protocol import (
    DEFAULT_MODELS,
    ModelSpec,
    Protocol,
    Selection,
    Split,
    protocol_from_dict,
)
from mrdamper.study.records import study_records
from mrdamper.study.result import Showcase, StudyResult
from mrdamper.study.runner import run_study
from mrdamper.study.selection import SelectionResult, cross_validate
from mrdamper.study.splits import Fold, make_folds
from mrdamper.study.tables import headline, summarize
from mrdamper.study.writer import write_study

__all__ = [
    "DEFAULT_MODELS",
    "AnalysisOutcome",
    "ControlRelevance",
    "ControlSettings",
    "Fold",
    "ModelSpec",
    "Protocol",
    "Selection",
    "SelectionResult",
    "Showcase",
    "Split",
    "StudyResult",
    "choose_protocol",
    "cross_validate",
    "default_protocol",
    "doe_protocol",
    "dyke_protocol",
    "headline",
    "load_protocol",
    "make_executor",
    "make_folds",
    "preset_protocol",
    "protocol_from_dict",
    "quiroz_protocol",
    "run_analysis",
    "run_study",
    "study_records",
    "summarize",
    "write_study",
]
