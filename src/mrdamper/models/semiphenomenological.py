"""The SP-1 ... SP-4 family under its earlier import path; it lives in :mod:`mrdamper.models.sp`."""

from __future__ import annotations

from mrdamper.models.sp.model import (
    SP1Estimator,
    SP1Model,
    SP2Estimator,
    SP2Model,
    SP3Estimator,
    SP3Model,
    SP4Estimator,
    SP4Model,
    SPModel,
)

__all__ = [
    "SP1Estimator",
    "SP1Model",
    "SP2Estimator",
    "SP2Model",
    "SP3Estimator",
    "SP3Model",
    "SP4Estimator",
    "SP4Model",
    "SPModel",
]
