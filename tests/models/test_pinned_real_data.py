"""Pinned real-data numbers of every default model kind: a change of the model code that moves a
test ESR in its fourth significant digit fails here.

Settings are those of ``benchmarks/accuracy_real_data.py`` (imported from it, so the two cannot
drift): estimator defaults plus the data set's electrical input; on Quiroz the LPV / LTI model rate
is 200 Hz; on Dyke the drive lag is fixed at ``eta = 250 1/s`` (every model with that setting; the
value the benchmark chose on the training part before the estimators identified the lag
themselves, which pins the model code without the lag search's cost), the model rate is the
record rate 3004.8 Hz, and every model is scored with ``range_policy="clip"``.

* Quiroz (``sine_unfiltered``), leave-one-condition-out, the fold that holds out 10 mm / 2 Hz (the
  cheapest fold: it removes the most samples from training): mean test ESR over its five records.
* Dyke (``ranran_50.csv``), first 70 % trains, last 30 % tests: test ESR.

How the values were produced: the code as it stood before the estimator skeleton was unified
(commit e032958), ``OPENBLAS_NUM_THREADS=1``, running exactly the fits below (``repr`` of the
mean ESR, rounded here to 6 significant digits). They agree with the per-fold Quiroz table and the
Dyke table of ``docs/results.md`` ("Every model side by side") to the 3 digits printed there.
The LPV and LTI values were measured again when their default input became the hysteretic one
(``input_signal="hysteretic"``, ``docs/models.md``): the same fits gave the same digits on the
branch that introduced it and after it was merged onto the unified skeleton. The Dyke values of
SP-1..SP-4 were measured again when the benchmark gave them the same drive lag as the LPV model.
The Quiroz NARX value was measured again when NARX started clipping its regressors to the
training envelope by default (``extrapolation="clip"``): 0.0108954 -> 0.0103553. The LPV and LTI
values were measured again when their zone laws took post-yield outer slopes by default
(``outer_slopes="auto"``, ``docs/models.md``).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from mrdamper.data import ExperimentSet
from mrdamper.models import get_estimator
from tests.conftest import load_benchmark

FOLD = "10mm_2Hz"
#: Dyke drive-lag rate [1/s] of the pinned values (the benchmark's former choice on the training
#: part; the default ``eta="auto"`` now identifies the lag, ``tests/models/test_lag.py``).
DYKE_ETA = 250.0
#: Kinds with a drive-lag setting.
LAGGED = {"lpv", "lti", "p15", "sp1", "sp2", "sp3", "sp4"}
#: Relative tolerance: the fourth significant digit.
RTOL = 5e-5

#: Mean test ESR of the Quiroz fold holding out 10 mm / 2 Hz (docs/results.md: 0.00724, 0.230,
#: 0.00650, 0.0281, 0.0504, 0.0370, 0.0357, 0.00879, 0.0761, 0.0109).
QUIROZ: dict[str, float] = {
    # LPV and LTI with post-yield outer slopes (0.00927236 and 0.205197 with the three-zone
    # regression's), at their default model rate, 500 Hz (0.0103503 and 0.206264 at the 200 Hz
    # fixed a priori before; 0.00832719 for LPV with the training choice of stroke and blend)
    "lpv": 0.00723649,
    "lti": 0.229512,
    "p15": 0.00527541,  # 0.00649598 before the shooting stage continued past its first budget
    "sp1": 0.0281058,
    "sp2": 0.0503522,
    "sp3": 0.0370066,
    "sp4": 0.0357106,
    "spencer": 0.00879430,
    "bingham": 0.0760880,
    # 0.0108954 before NARX clipped its regressors to the training envelope; 0.0103553 before its
    # free run started from rest (it took the record's first measured forces)
    "narx": 0.0103577,
}
#: Test ESR of Dyke 70/30 (docs/results.md: 0.0228, 0.0831, 0.0448, 0.0532, 0.0695, 0.0588, 0.0542,
#: 0.0316, 0.154, 0.0480).
DYKE: dict[str, float] = {
    # LPV and LTI with post-yield outer slopes (0.0218731 and 0.0733214 with the regression's)
    "lpv": 0.0228445,
    "lti": 0.0830504,
    "p15": 0.0447804,
    "sp1": 0.0532314,
    "sp2": 0.0694617,
    "sp3": 0.0587776,
    "sp4": 0.0542275,
    "spencer": 0.0316366,
    "bingham": 0.153524,
    "narx": 0.0480078,  # 0.0469363 before the free run started from rest (measured forces)
}
#: Kinds whose pinned fit takes longer than about 3 s on the shared machine (accuracy checks: out
#: of the ``-m "not slow"`` dev loop, run by CI with everything else; the quick kinds stay in it as
#: a guard on the real-data numbers).
SLOW = {"spencer", "p15", "sp1", "narx", "lpv", "lti"}


def _params(table: dict[str, float]) -> list[Any]:
    return [
        pytest.param(k, marks=[pytest.mark.slow] if k in SLOW else [], id=k) for k in sorted(table)
    ]


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_benchmark("accuracy_real_data")


@pytest.fixture(scope="module")
def quiroz_fold(quiroz_unfiltered_dir: Path) -> tuple[ExperimentSet, ExperimentSet]:
    from mrdamper.data.readers import read_directory

    data = read_directory(quiroz_unfiltered_dir)
    for cond, train, test in data.leave_one_group_out("condition"):
        if cond == FOLD:
            return train, test
    raise AssertionError(f"fold {FOLD} not found")


@pytest.fixture(scope="module")
def dyke_parts(dyke_csv: Path, bench: ModuleType) -> tuple[Any, Any]:
    return bench._dyke_parts()


def test_every_default_kind_is_pinned() -> None:
    from mrdamper.kinds import KINDS

    # the study's default kinds (the kind table's defaults); the others have known-answer tests
    assert sorted(QUIROZ) == sorted(row.kind for row in KINDS if row.default) == sorted(DYKE)


@pytest.mark.realdata
@pytest.mark.parametrize("kind", _params(QUIROZ))
def test_quiroz_fold_esr_pinned(
    kind: str, bench: ModuleType, quiroz_fold: tuple[ExperimentSet, ExperimentSet]
) -> None:
    train, test = quiroz_fold
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = get_estimator(kind, **bench.settings_for(kind, "quiroz")).fit(train)
        esr = float(np.mean([model.score(e).esr for e in test]))
    assert esr == pytest.approx(QUIROZ[kind], rel=RTOL), f"{kind}: mean test ESR {esr!r}"


@pytest.mark.realdata
@pytest.mark.parametrize("kind", _params(DYKE))
def test_dyke_esr_pinned(kind: str, bench: ModuleType, dyke_parts: tuple[Any, Any]) -> None:
    train, test = dyke_parts
    settings = bench.settings_for(kind, "dyke")
    if kind in LAGGED:  # the fixed lag these values were measured with (the default identifies it)
        settings["eta"] = DYKE_ETA
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = get_estimator(kind, **settings).fit(train).with_range_policy("clip")
        esr = float(model.score(test).esr)
    assert esr == pytest.approx(DYKE[kind], rel=RTOL), f"{kind}: test ESR {esr!r}"
