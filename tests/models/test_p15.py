"""P-15: known-answer identification, divergence detection, bad input, JSON round trip.

The known answer is the coefficient set that generated the synthetic record by simulation; on
noise-free data (derivative filter off) least squares must return it.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mrdamper import DataValidationError, Experiment, IdentificationError, SimulationDivergedError
from mrdamper.models import get_estimator, load_model
from mrdamper.models.phenomenological import P15Estimator, P15Model

#: A smooth, stable, current-dependent P-15 (m F'' + c F' + g(F) = w1 v with g increasing).
W_TRUE = np.array(
    [
        [1500.0, 2000.0, -500.0],  # w1 [N s/m]
        [-1.0e-2, -4.0e-3, 1.0e-3],  # w2 [s]
        [-1.0e-4, -3.0e-5, 1.0e-5],  # w3 [s^2]
        [-1.0e-7, 2.0e-8, -1.0e-8],  # w4 [1/N^2]
        [-1.0e-13, -5.0e-14, 2.0e-14],  # w5 [1/N^4]
    ]
)
TRUE = P15Model(W=tuple(W_TRUE.ravel()), f0=12.0, input_range=(0.0, 1.0), force_bound=1e5, max_step=2e-5)


def _record(n: int = 8000, fs: float = 4000.0, current: float | None = None, seed: int = 0,
            model: P15Model = TRUE) -> Experiment:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    p = rng.uniform(0, 2 * np.pi, 2)
    v = 0.15 * np.sin(2 * np.pi * 1.5 * t + p[0]) + 0.05 * np.sin(2 * np.pi * 4.1 * t + p[1])
    x = np.cumsum(v) / fs
    i = np.full(n, current) if current is not None else 0.5 + 0.5 * np.sin(2 * np.pi * 0.45 * t)
    e = Experiment(t=t, x=x, v=v, F=np.full(n, model.f0), i=i, name=f"p15_{seed}")
    return e.replace(F=model.predict(e))


def _w_error(fitted: P15Model) -> list[float]:
    """Largest error of each w_j over the input range, relative to its largest magnitude."""
    ii = np.linspace(0.0, 1.0, 5)
    want, got = TRUE.coefficients(ii), fitted.coefficients(ii)
    return [float(np.max(np.abs(got[j] - want[j])) / np.max(np.abs(want[j]))) for j in range(5)]


def test_known_answer_noise_free() -> None:
    data = [_record(seed=1), _record(seed=2)]
    fitted = P15Estimator(cutoff=None).fit(data)
    # Unfiltered central differences carry an O(dt^2) error (it shrinks ~6x at 10 kHz); w4 and
    # w5 trade off against each other over the force span, so they are the least exact.
    err = _w_error(fitted)
    assert err[0] < 2e-5 and err[1] < 2e-4 and err[2] < 5e-4
    assert err[3] < 5e-3 and err[4] < 3e-2
    assert fitted.f0 == pytest.approx(12.0, abs=0.01)
    assert fitted.provenance["training_divergence"] == {}
    # and the identified model reproduces the records in free run
    for e in data:
        assert fitted.score(e).esr < 1e-3


def test_filtered_derivatives_on_noisy_data_stay_close() -> None:
    e = _record(n=12000, seed=3)
    rng = np.random.default_rng(0)
    noisy = e.replace(F=e.F + rng.normal(0.0, 2.0, e.n))
    fitted = P15Estimator(cutoff=60.0).fit(noisy)
    assert fitted.provenance["cutoff_hz"] == {"p15_3": 60.0}
    assert fitted.score(e).esr < 0.01


def test_stable_form_meets_its_sign_constraints() -> None:
    e = _record(seed=4)
    rng = np.random.default_rng(1)
    noisy = e.replace(F=e.F + rng.normal(0.0, 20.0, e.n))
    for form in ("stable", "monotone"):
        fitted = P15Estimator(form=form, cutoff=40.0).fit(noisy)
        w = fitted.coefficients(np.linspace(0.0, 1.0, 101))
        # Bernstein -> monomial conversion leaves rounding of ~1e-7 of the coefficient scale
        assert np.all(w[1] < 0) and np.all(w[2] < 0)
        assert np.all(w[4] <= 1e-6 * np.max(np.abs(W_TRUE[4])))
        if form == "monotone":
            assert np.all(w[3] <= 1e-6 * np.max(np.abs(W_TRUE[3])))
        assert not fitted.provenance["w3_crosses_zero"]


def test_output_error_refinement_improves_a_biased_fit() -> None:
    e = _record(n=6000, seed=4)
    rng = np.random.default_rng(2)
    noisy = e.replace(F=e.F + rng.normal(0.0, 20.0, e.n))
    # a low cut-off biases the filtered derivatives; the output-error refinement corrects it
    plain = P15Estimator(form="stable", cutoff=8.0).fit(noisy)
    refined = P15Estimator(form="stable", cutoff=8.0, refine=True, max_nfev=10).fit(noisy)
    info = refined.provenance["refinement"]
    assert info["rms_after"] < 0.7 * info["rms_before"]
    assert refined.score(e).esr < 0.5 * plain.score(e).esr
    w = refined.coefficients(np.linspace(0.0, 1.0, 51))
    assert np.all(w[1] < 0) and np.all(w[2] < 0)


def test_divergence_is_detected_with_the_sample() -> None:
    W = W_TRUE.copy()
    W[2] = [2.0e-4, 0.0, 0.0]  # w3 > 0: the force ODE has a growing mode
    bad = P15Model(W=tuple(W.ravel()), input_range=(0.0, 1.0), force_bound=5000.0, max_step=2e-5)
    e = _record(n=2000, seed=0)
    with pytest.raises(SimulationDivergedError, match=r"^p15: simulation diverged at sample \d+") as info:
        bad.predict(e)
    assert 0 < info.value.sample < e.n
    assert info.value.model == "p15"


def test_w3_crossing_zero_is_reported() -> None:
    W = W_TRUE.copy()
    W[2] = [-1.0e-4, 2.0e-4, 0.0]  # w3 = 0 at i = 0.5 A
    singular = P15Model(W=tuple(W.ravel()), input_range=(0.0, 1.0), max_step=2e-5)
    t = np.arange(1000) / 1000.0
    e = Experiment(t=t, x=0 * t, v=0.1 * np.sin(6 * t), F=0 * t, i=t)  # ramp 0 -> 1 A
    with pytest.raises(SimulationDivergedError, match="w3") as info:
        singular.predict(e)
    assert info.value.sample == 500


def test_json_round_trip_is_bit_identical(tmp_path: Path) -> None:
    fitted = P15Estimator(cutoff=200.0).fit(_record(seed=5))
    again = load_model(fitted.save(tmp_path / "p15.json"))
    assert again == fitted
    e = _record(seed=6)
    assert np.array_equal(again.predict(e), fitted.predict(e))
    assert type(get_estimator("p15")) is P15Estimator


def test_constant_current_is_not_identifiable() -> None:
    e = _record(current=0.5)
    with pytest.raises(IdentificationError, match="constant.*rank 1 of 3"):
        P15Estimator().fit(e)


def test_two_levels_are_not_enough() -> None:
    data = [_record(current=0.2, seed=1), _record(current=0.8, seed=2)]
    with pytest.raises(IdentificationError, match="rank 2 of 3"):
        P15Estimator().fit(data)


def test_too_few_samples() -> None:
    e = _record().slice(0, 60)
    with pytest.raises(IdentificationError, match="needs at least 160 samples"):
        P15Estimator(cutoff=None).fit(e)


def test_missing_input_channel() -> None:
    e = _record()
    only_voltage = Experiment(t=e.t, x=e.x, v=e.v, F=e.F, voltage=e.i, name="v_only")
    with pytest.raises(DataValidationError, match="^i: record 'v_only' has no 'i' channel"):
        P15Estimator().fit(only_voltage)


@pytest.mark.parametrize(
    ("setting", "value", "field"),
    [("cutoff", -3.0, "cutoff"), ("cutoff", 5000.0, "cutoff"), ("form", "linear", "form"),
     ("filter_order", 0, "filter_order"), ("offset", 1, "offset")],
)
def test_bad_settings_name_the_field(setting: str, value: object, field: str) -> None:
    with pytest.raises(DataValidationError, match=f"^{field}:"):
        P15Estimator(**{setting: value}).fit(_record(seed=1))


def test_predict_uses_measured_force_only_for_initial_state() -> None:
    e = _record(seed=7)
    scrambled = e.replace(F=np.concatenate([e.F[:40], -e.F[40:]]))
    assert np.array_equal(TRUE.predict(e), TRUE.predict(scrambled))


# ----------------------------------------------------------------------------- real data
@pytest.mark.realdata
@pytest.mark.slow
def test_real_data_forms(quiroz_unfiltered_dir: Path) -> None:
    """On the Quiroz sine records (held-out condition 5 mm / 3 Hz) the paper's plain least squares
    gives a model whose free run is worse than the mean force (ESR > 1, documented in
    docs/models.md); the monotone form is stable and useful (ESR < 0.5)."""
    recs = []
    for f in sorted(quiroz_unfiltered_dir.glob("*.csv")):
        d = pd.read_csv(f)
        cond = re.match(r"sine_(.+mm_.+Hz)_", f.stem)
        assert cond is not None
        recs.append(Experiment(t=d["t"], x=d["x"], v=d["v"], i=d["i"], F=d["F"], name=f.stem,
                               metadata={"condition": cond[1]}))
    test = [e for e in recs if e.metadata["condition"] == "5mm_3Hz"]
    train = [e for e in recs if e.metadata["condition"] != "5mm_3Hz"]
    mono = P15Estimator(form="monotone").fit(train)
    assert mono.provenance["training_divergence"] == {}
    assert np.mean([mono.score(e).esr for e in test]) < 0.5
