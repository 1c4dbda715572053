"""The controllers as strategy objects: the registry, each law against the compiled kernel, and a
controller added with one module and one registry line."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from mrdamper.control import CONTROLLERS, Controller, iso_road, simulate_quarter_car
from mrdamper.control.loop import _quarter_car_kernels as QK
from mrdamper.control.loop.controllers import LAWS, ControllerLaw, law_of, register
from mrdamper.control.loop.controllers.law import CTRL_PASSIVE
from mrdamper.controller_names import BUILTIN_CONTROLLERS
from mrdamper.errors import DataValidationError
from mrdamper.models.semiphenomenological import SP3Model
from mrdamper.rig.doe_control import CONTROLLERS as RIG_CONTROLLERS

SP3 = SP3Model(S=(800.0, 200.0, 60.0, 0.0, 900.0, 0.0), f0=10.0, input_range=(0.0, 2.0))


def test_the_default_comparison_is_the_registry() -> None:
    assert CONTROLLERS == tuple(LAWS) == ("soft", "hard", "skyhook", "groundhook", "hybrid")
    # the names read without loading the loops (command line, rig DoE) are the registry's
    assert BUILTIN_CONTROLLERS == tuple(LAWS)
    assert RIG_CONTROLLERS == tuple(LAWS)
    assert [n for n, law in LAWS.items() if law.passive] == ["soft", "hard"]
    assert {LAWS["soft"].constant_input(0.1, 0.9), LAWS["hard"].constant_input(0.1, 0.9)} == {
        0.1,
        0.9,
    }


@pytest.mark.parametrize("name", [n for n in CONTROLLERS if not LAWS[n].passive])
def test_each_law_is_the_kernels_law(name: str) -> None:
    law = LAWS[name]
    rng = np.random.default_rng(7)
    for vs, vu, c_sky, c_gnd, alpha in zip(
        rng.normal(0, 0.5, 400),
        rng.normal(0, 0.5, 400),
        rng.uniform(0, 8000, 400),
        rng.uniform(0, 8000, 400),
        rng.uniform(0, 1, 400),
        strict=True,
    ):
        want = law.desired(vs, vu, c_sky, c_gnd, alpha)
        got = QK._desired(law.code, vs, vu, c_sky, c_gnd, alpha)
        assert got == want, (name, vs, vu)


def test_an_unknown_controller_is_refused_in_one_line() -> None:
    with pytest.raises(DataValidationError, match="expected one of .*'hybrid'.*got 'skyhok'"):
        Controller("skyhok")
    with pytest.raises(DataValidationError, match="is registered"):
        register(LAWS["soft"])


@dataclass(frozen=True)
class _Firm(ControllerLaw):
    def constant_input(self, lo: float, hi: float) -> float:
        return 0.5 * (lo + hi)


@pytest.fixture
def firm() -> Iterator[ControllerLaw]:
    law = register(_Firm("firm", CTRL_PASSIVE, "passive, mid-range input"))
    yield law
    del LAWS["firm"]


def test_a_registered_controller_runs_in_the_quarter_car(firm: ControllerLaw) -> None:
    assert law_of("firm") is firm
    road = iso_road("C", duration=2.0)
    runs = {n: simulate_quarter_car(SP3, road, n) for n in ("soft", "firm", "hard")}
    assert np.all(runs["firm"].i == 1.0)  # the middle of SP3's [0, 2] A
    assert runs["soft"].i[0] == 0.0 and runs["hard"].i[0] == 2.0
    aw = {n: r.metrics()["rms_acc_wk"] for n, r in runs.items()}
    assert aw["firm"] != aw["soft"] and aw["firm"] != aw["hard"]
