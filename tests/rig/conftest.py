"""A tiny, fast test damper for the rig tests (the shipped reference damper is tested
separately)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from mrdamper.data import Experiment
from mrdamper.models.base import FittedModel


@dataclass(frozen=True, kw_only=True)
class TanhDamper(FittedModel):
    """Bingham-like smooth damper: ``F = (c0 + c1 e) v + (fy0 + fy1 e) tanh(v / v0)`` [N]."""

    kind: ClassVar[str] = "test_tanh"

    c0: float = 2000.0
    c1: float = 1500.0
    fy0: float = 80.0
    fy1: float = 900.0
    v0: float = 0.01

    def predict(self, experiment: Experiment) -> np.ndarray:
        e = self.electrical_input(experiment)
        v = experiment.v
        return (self.c0 + self.c1 * e) * v + (self.fy0 + self.fy1 * e) * np.tanh(v / self.v0)


@pytest.fixture()
def damper() -> TanhDamper:
    return TanhDamper(input="i", input_range=(0.0, 1.0))


@pytest.fixture(scope="session")
def damper_cls() -> type[TanhDamper]:
    return TanhDamper
