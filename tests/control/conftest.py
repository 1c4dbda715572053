"""Models fitted once per session on the shared real data (skipped where the data are absent)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest


@pytest.fixture(scope="session")
def quiroz_records(quiroz_unfiltered_dir: Path) -> list[Any]:
    """The 30 unfiltered constant-current Quiroz sine records."""
    from mrdamper.data.readers import DEFAULT_PATTERN, read_directory

    return list(read_directory(quiroz_unfiltered_dir, DEFAULT_PATTERN))


@pytest.fixture(scope="session")
def quiroz_models(quiroz_records: list[Any]) -> dict[str, Any]:
    """LPV (model rate 200 Hz, defaults otherwise) and SP-1 fitted on all 30 Quiroz sine records."""
    from mrdamper.models.lpv import LPVEstimator
    from mrdamper.models.semiphenomenological import SP1Estimator

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lpv = LPVEstimator(model_fs=200.0, input_signal="u").fit(quiroz_records)
    return {"lpv": lpv, "sp1": SP1Estimator().fit(quiroz_records)}


@pytest.fixture(scope="session")
def dyke_record(dyke_csv: Path) -> Any:
    """The Dyke white-noise record (time base regenerated at 3004.8 Hz)."""
    from mrdamper.data.readers import read_csv

    return read_csv(dyke_csv, fs=3004.8)


@pytest.fixture(scope="session")
def dyke_models(dyke_record: Any) -> dict[str, Any]:
    """LPV (full rate) and SP-1, both with the voltage input through the drive lag eta = 250 1/s,
    fitted on the first 70 %."""
    from mrdamper.models.lpv import LPVEstimator
    from mrdamper.models.semiphenomenological import SP1Estimator

    train = dyke_record.slice(0, int(0.7 * dyke_record.n))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lpv = LPVEstimator(input="voltage", eta=250.0, input_signal="u").fit(train)
    return {"lpv": lpv, "sp1": SP1Estimator(input="voltage", eta=250.0).fit(train)}


def _conformance_records() -> list[Any]:
    """The conformance suite's synthetic records: sines at three current levels."""
    from mrdamper.conformance import training_records

    return training_records()


class LazyFits(dict):  # type: ignore[type-arg]
    """Each kind fitted on first use with the conformance suite's short settings, on the records
    ``training()`` gives (made once, on the first fit; kept as ``records``)."""

    def __init__(self, training: Callable[[], list[Any]] = _conformance_records) -> None:
        super().__init__()
        self._make = training
        self.records: list[Any] = []

    def __missing__(self, kind: str) -> Any:
        from mrdamper.conformance import fit_quietly
        from tests.models.test_conformance import _estimator

        if not self.records:
            self.records = self._make()
        model = fit_quietly(_estimator(kind), self.records)
        self[kind] = model
        return model


@pytest.fixture(scope="session")
def kind_models() -> dict[str, Any]:
    """Every kind fitted lazily on synthetic records (see :class:`LazyFits`)."""
    return LazyFits()


@pytest.fixture(scope="session")
def kind_probe() -> Any:
    """A short record (500 Hz, 1.5 s) with a stepped current inside the training range."""
    from mrdamper.conformance import synthetic_record

    return synthetic_record(0.008, 2.0, (0.3, 0.7, 0.4, 0.6), "probe", 3.0)


def toy_lti() -> Any:
    """A first-order LTI damper model on the velocity (1 kHz; no inverse form)."""
    import numpy as np

    from mrdamper.models.lpv import LTIModel

    return LTIModel(
        alpha=np.array([[-0.9], [0.2]]),
        beta=np.array([[300.0], [-100.0]]),
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )
