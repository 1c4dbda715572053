"""Shipped reference dampers."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.rig import VirtualRig, available_reference_dampers, reference_damper
from mrdamper.rig.reference import REFERENCE_DAMPERS


def test_unknown_name_is_refused() -> None:
    with pytest.raises(DataValidationError, match="name"):
        reference_damper("nope")


@pytest.mark.parametrize("name", REFERENCE_DAMPERS)
def test_reference_damper_loads_or_says_it_is_missing(name: str) -> None:
    if name not in available_reference_dampers():
        with pytest.raises(FileNotFoundError, match=name):
            reference_damper(name)
        pytest.skip(f"parameters/{name}.json is not installed yet")
    d = reference_damper(name)
    assert isinstance(d, FittedModel) and d.kind == "spencer"
    expected = {"quiroz2022": ("i", (0.0, 1.0)), "spencer1997": ("voltage", (0.0, 2.25))}[name]
    assert (d.input, d.input_range) == expected


def test_default_rig_uses_quiroz2022() -> None:
    if "quiroz2022" not in available_reference_dampers():
        pytest.skip("parameters/quiroz2022.json is not installed yet")
    from mrdamper.signals import aprbs, road_profile

    rig = VirtualRig()
    assert rig.model.to_dict() == reference_damper().to_dict()
    x = road_profile(1000.0, 5.0, seed=0, max_frequency=5.0)
    i = aprbs(1000.0, 5.0, low=0.0, high=1.0, min_hold=0.2, seed=1)
    rec = rig.run(x, i, seed=2)
    # a calibrated damper of about +-1.6 kN at 1 A (Quiroz README) on a +-18 mm road profile
    assert 200.0 < np.max(np.abs(rec.F)) < 3000.0
