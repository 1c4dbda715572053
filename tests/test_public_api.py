"""Pin the curated public API: adding or removing a name must be a deliberate change here."""

from __future__ import annotations

import inspect
import subprocess
import sys

import mrdamper

EXPECTED = {
    "DataValidationError", "Estimator", "Experiment", "ExperimentSet", "FittedModel",
    "IdentificationError", "MrDamperError", "OutOfRangeError", "OutputExistsError", "Protocol",
    "SchemaError", "Scores", "SimulationDivergedError", "SimulationResult", "StudyResult",
    "UnitError", "VirtualRig", "ZoneFit", "ZoneLaws", "__version__", "available_models",
    "check_family", "esr",
    "fit_percent", "fit_zone_laws", "fit_zones", "get_estimator", "known_kinds", "load_model",
    "load_protocol", "nrmse", "read", "read_directory", "reference_damper", "run_study", "ssse",
    "state_space", "table_ii", "to_control", "write_csv", "write_parquet",
}  # fmt: skip


def test_all_is_pinned_and_resolves() -> None:
    assert set(mrdamper.__all__) == EXPECTED
    assert len(mrdamper.__all__) == len(EXPECTED)
    for name in mrdamper.__all__:
        assert getattr(mrdamper, name) is not None


def test_every_public_callable_is_documented() -> None:
    for name in mrdamper.__all__:
        obj = getattr(mrdamper, name)
        if callable(obj):
            assert inspect.getdoc(obj), f"{name} has no docstring"


def test_import_is_light_and_side_effect_free() -> None:
    code = (
        "import sys, mrdamper; "
        "heavy = [m for m in ('numba', 'matplotlib.pyplot', 'dask', 'mrdamper.models.lpv', "
        "'mrdamper.rig') if m in sys.modules]; print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_unknown_attribute_raises() -> None:
    import pytest

    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        mrdamper.nope  # noqa: B018
