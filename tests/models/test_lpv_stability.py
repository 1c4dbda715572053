"""LPV estimator: frozen stability enforced over the identified range, per-record weights,
``laws_by="auto"`` on mixed metadata, and the up-sampling warning."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from mrdamper import DataValidationError, IdentificationError
from mrdamper.data.readers import read_directory
from mrdamper.models.lpv import LPVEstimator
from mrdamper.models.lpv import fit as _lpv_fit

from .test_lpv import ALPHA, FS, _record, _train


def test_largest_frozen_pole_matches_roots() -> None:
    grid = np.linspace(0.0, 1.0, 11)
    pmax, rho_at, pole = _lpv_fit.largest_frozen_pole(ALPHA, grid)
    ref = np.abs(_lpv_fit.frozen_poles(ALPHA, grid))
    assert pmax == pytest.approx(ref.max(), rel=1e-12)
    assert rho_at == grid[np.unravel_index(ref.argmax(), ref.shape)[0]]
    assert abs(pole) == pytest.approx(pmax)


def test_record_weights_zero_drops_a_record() -> None:
    recs = _train()
    noisy = _record(0.5, 42, name="noisy")
    noisy = noisy.replace(F=noisy.F + np.random.default_rng(0).normal(0.0, 200.0, noisy.n))
    est = LPVEstimator(n_m=2, n_rho=2, input_signal="v", offset=False, refine=False)
    without = est.fit(recs)
    weighted = est.fit([*recs, noisy], record_weights=[1, 1, 1, 1, 0])
    np.testing.assert_allclose(weighted.alpha, without.alpha, rtol=1e-9, atol=1e-12)
    assert weighted.provenance["record_weights"] == [1.0, 1.0, 1.0, 1.0, 0.0]
    unweighted = est.fit([*recs, noisy])
    assert not np.allclose(unweighted.alpha, without.alpha, rtol=1e-6)


@pytest.mark.parametrize(
    "bad", [[1.0, 1.0], [1.0, -1.0, 1.0, 1.0], [np.nan, 1, 1, 1], [0, 0, 0, 0]]
)
def test_record_weights_are_validated(bad) -> None:
    with pytest.raises(DataValidationError, match="record_weights"):
        LPVEstimator(n_m=2, n_rho=2, input_signal="v", refine=False).fit(
            _train(), record_weights=bad
        )


def test_laws_by_auto_refuses_mixed_current_metadata() -> None:
    recs = _train()
    recs[1] = recs[1].replace(metadata={})
    with pytest.raises(DataValidationError, match="laws_by.*1 of 4 records lack it"):
        LPVEstimator(n_m=2, n_rho=2, refine=False).fit(recs)


def test_laws_by_auto_without_any_current_metadata_notes_bins() -> None:
    recs = [r.replace(metadata={}) for r in _train()]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = LPVEstimator(n_m=2, n_rho=2, refine=False, stability="warn").fit(recs)
    assert "rho bins" in m.provenance["laws_note"]


def test_model_rate_above_record_rate_warns() -> None:
    with pytest.warns(RuntimeWarning, match="above the record rate"):
        LPVEstimator(n_m=2, n_rho=2, input_signal="v", refine=False, model_fs=2 * FS).fit(_train())


def test_stability_setting_is_validated() -> None:
    with pytest.raises(DataValidationError, match="stability"):
        LPVEstimator(stability="maybe").fit(_train())  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def quiroz_fold(quiroz_unfiltered_dir: Path):
    """Quiroz training fold without 2 mm / 5 Hz: its unconstrained refinement is frozen-unstable."""
    data = read_directory(quiroz_unfiltered_dir)
    return data.where(lambda e: e.metadata["condition"] != "2mm_5Hz")


@pytest.mark.realdata
@pytest.mark.slow
def test_enforced_stability_on_a_fold_where_the_unconstrained_fit_is_unstable(quiroz_fold) -> None:
    with pytest.warns(RuntimeWarning, match="not frozen-stable"):
        free = LPVEstimator(model_fs=200.0, stability="warn", input_signal="u").fit(quiroz_fold)
    assert free.max_pole_modulus(n_grid=101) >= 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no instability warning by default
        m = LPVEstimator(model_fs=200.0).fit(quiroz_fold)
    assert m.max_pole_modulus(n_grid=101) < _lpv_fit.STABILITY_LIMIT
    assert m.provenance["frozen_stable"] is True


@pytest.mark.realdata
def test_unstable_least_squares_model_is_refused_naming_the_pole(quiroz_fold) -> None:
    with pytest.raises(IdentificationError, match=r"frozen pole z = .*\|z\| = 1\.\d+\) at rho = "):
        LPVEstimator(model_fs=200.0, refine=False).fit(quiroz_fold)
