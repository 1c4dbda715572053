"""Known-answer and property tests of the paper's indices (eqs 23-24)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mrdamper import DataValidationError, esr, fit_percent, nrmse, ssse
from mrdamper.metrics import score_arrays


def test_known_values() -> None:
    F = np.array([1.0, -1.0, 1.0, -1.0])  # mean 0, variance 1
    Fh = np.array([0.5, -1.0, 1.0, -1.0])  # one error of 0.5
    assert ssse(F, Fh) == pytest.approx(np.sqrt(0.25 / 4))
    assert esr(F, Fh) == pytest.approx(0.0625)
    assert nrmse(F, Fh) == pytest.approx(0.25)
    assert fit_percent(F, Fh) == pytest.approx(75.0)


def test_perfect_and_mean_predictor() -> None:
    rng = np.random.default_rng(0)
    F = rng.normal(size=200)
    assert esr(F, F) == 0.0
    assert esr(F, np.full_like(F, F.mean())) == pytest.approx(1.0)


def test_errors() -> None:
    with pytest.raises(DataValidationError, match="shape"):
        esr(np.ones(3), np.ones(4))
    with pytest.raises(DataValidationError, match="constant"):
        esr(np.ones(3), np.zeros(3))
    with pytest.raises(DataValidationError, match="non-finite"):
        ssse(np.arange(3.0), np.array([0, np.nan, 1]))


finite = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)


@given(arrays(float, 50, elements=finite), arrays(float, 50, elements=finite), st.floats(0.1, 100))
def test_scale_invariance_of_esr_and_scaling_of_ssse(
    F: np.ndarray, Fh: np.ndarray, k: float
) -> None:
    if np.var(F) < 1e-6:
        return
    assert esr(k * F, k * Fh) == pytest.approx(esr(F, Fh), rel=1e-6, abs=1e-12)
    assert ssse(k * F, k * Fh) == pytest.approx(k * ssse(F, Fh), rel=1e-6, abs=1e-9)
    s = score_arrays(F, Fh)
    assert s.nrmse == pytest.approx(np.sqrt(s.esr))
