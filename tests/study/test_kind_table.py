"""A family added with ``register()`` gets a row in the kind table and is seen like any other."""

from __future__ import annotations

import pytest

from mrdamper import kinds
from mrdamper.kinds import cost_rank
from mrdamper.models import get_estimator, known_kinds, model_class, register
from mrdamper.plotting._common import model_color
from tests.study.conftest import ToyEstimator, ToyModel


def test_registered_family_has_a_row() -> None:
    assert "toy" in known_kinds()
    row = kinds.spec("toy")
    assert row is not None and row.module == ToyModel.__module__
    assert row.default is False and "toy" not in kinds.default_kinds()
    assert model_class("toy") is ToyModel
    assert isinstance(get_estimator("toy"), ToyEstimator)
    assert model_color("toy") == row.color
    assert cost_rank("toy") == row.cost_rank


def test_builtin_kind_cannot_be_replaced() -> None:
    class Fake(ToyModel):
        kind = "lpv"

    class FakeEstimator(ToyEstimator):
        kind = "lpv"

    with pytest.raises(ValueError, match="lpv"):
        register(FakeEstimator, Fake)


def test_every_row_names_its_classes() -> None:
    for row in kinds.KINDS:
        cls = model_class(row.kind)
        assert cls.__name__ == row.model and cls.kind == row.kind
        assert type(get_estimator(row.kind)).__name__ == row.estimator
