"""Prediction bands: calibration folds, stored band, intervals, coverage on held-out rig records,
the uncertainty weight, and the command line (``fit --band``, ``simulate --interval``,
``export``)."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import ExperimentSet
from mrdamper.data.writers import write_csv
from mrdamper.errors import DataValidationError, SchemaError
from mrdamper.models import get_estimator, load_model
from mrdamper.rig import VirtualRig, reference_damper
from mrdamper.signals import ramped_sine
from mrdamper.uncertainty import (
    Band,
    band_of,
    bound_share,
    calibration_folds,
    coverage,
    error_spectra,
    fit_weight,
    fit_with_band,
    predict_interval,
    uncertainty_weights,
)
from tests.test_bad_inputs import _one_line_error, _run

FS = 500.0
#: (amplitude [m], frequency [Hz]) of the training and held-out conditions.
TRAIN = ((0.018, 0.5), (0.010, 2.0), (0.005, 3.0))
HELD_OUT = (0.004, 4.0)
CURRENTS = (0.0, 0.5, 1.0)


def _records(conditions: tuple[tuple[float, float], ...], seed: int) -> ExperimentSet:
    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=FS)
    out = []
    for amp, f in conditions:
        for cur in CURRENTS:
            seed += 1
            x = ramped_sine(FS, amplitude=amp, frequency=f, cycles=2)
            out.append(
                rig.run(
                    x, np.full(x.size, cur), seed=seed, name=f"r{amp * 1e3:g}mm_{f:g}Hz_{cur:g}A"
                )
            )
    return ExperimentSet(out)


@pytest.fixture(scope="module")
def train() -> ExperimentSet:
    return _records(TRAIN, 0)


@pytest.fixture(scope="module")
def test_set() -> ExperimentSet:
    return _records((HELD_OUT,), 100)


@pytest.fixture(scope="module")
def lpv(train: ExperimentSet):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_with_band(get_estimator("lpv"), train)


def test_the_two_folds_hold_out_every_sample_once_and_keep_a_conditions_currents_together(
    train: ExperimentSet,
) -> None:
    folds = calibration_folds(train)
    assert len(folds) == 2
    held = [e.name for _, _, test in folds for e in test]
    assert sorted(held) == sorted(train.names)
    for _, fit_part, test in folds:
        assert not set(fit_part.names) & set(test.names)
        for e in test:  # every current of a held-out condition is held out with it
            cond = e.name.rsplit("_", 1)[0]
            assert all(n.rsplit("_", 1)[0] != cond for n in fit_part.names)


def test_one_record_is_cut_in_two_time_blocks(train: ExperimentSet) -> None:
    e = train[0]
    folds = calibration_folds(e)
    assert [f[0] for f in folds] == ["first halves held out", "second halves held out"]
    assert sum(t.n for _, _, ts in folds for t in ts) == e.n


def test_the_band_covers_held_out_records_of_a_new_condition(lpv, test_set) -> None:
    band = band_of(lpv)
    assert band is not None and band.method == "record folds"
    inside = n = 0
    widths = []
    for e in test_set:
        iv = predict_interval(lpv.with_range_policy("clip"), e, 0.9)
        c, w = coverage(e.F, iv)
        inside += c * e.n
        n += e.n
        widths.append(w)
        assert np.all(iv.lower <= iv.F_pred) and np.all(iv.F_pred <= iv.upper)
    assert 0.80 <= inside / n <= 1.0, inside / n
    assert np.mean(widths) < 1.0  # narrower than the force's own RMS: an informative band
    lo50, hi50 = band.interval(np.array([0.0, 100.0]), 0.5)
    lo99, hi99 = band.interval(np.array([0.0, 100.0]), 0.99)
    assert np.all(hi99 - lo99 > hi50 - lo50)


def test_a_saved_model_carries_its_band(lpv, tmp_path: Path) -> None:
    path = lpv.save(tmp_path / "m.json")
    again = load_model(path)
    assert band_of(again) == band_of(lpv)


def test_a_model_without_a_band_says_so(train: ExperimentSet, test_set) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = get_estimator("bingham").fit(train)
    assert band_of(m) is None
    with pytest.raises(DataValidationError, match="no band stored"):
        predict_interval(m, test_set[0], 0.9)


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda b: b.pop("quantiles"), "provenance.band.quantiles"),
        (lambda b: b.__setitem__("a", -1.0), "provenance.band.a"),
        (lambda b: b["quantiles"].__setitem__(3, "x"), "provenance.band.quantiles[3]"),
    ],
)
def test_a_damaged_band_is_one_error_naming_the_field(lpv, tmp_path: Path, edit, field) -> None:
    data = json.loads(lpv.save(tmp_path / "m.json").read_text())
    edit(data["provenance"]["band"])
    (tmp_path / "m.json").write_text(json.dumps(data))
    with pytest.raises(SchemaError, match="^" + re.escape(field)):
        band_of(load_model(tmp_path / "m.json"))


@pytest.mark.parametrize("level", [0.4, 1.0, True, "0.9"])
def test_a_level_outside_the_stored_grid_is_refused(lpv, test_set, level) -> None:
    with pytest.raises(DataValidationError, match="interval: expected a coverage level"):
        predict_interval(lpv, test_set[0], level)


def test_the_weight_bounds_the_records_it_was_built_from_and_is_stable(lpv, test_set) -> None:
    band = band_of(lpv)
    weights = uncertainty_weights(lpv)
    assert len(weights) == len(CURRENTS)  # one per frozen current of the held-out records
    assert bound_share(weights, band.spectra) == 1.0
    for w in weights:
        assert w.k > 0 and w.w_z > 0 and w.w_p > 0
        poles = w.transfer_function().poles()
        assert np.all(poles.real < 0)
    # other records: the held-out condition, predicted by the full model (reported, not required)
    others = error_spectra(lpv.with_range_policy("clip"), test_set)
    assert len(others) == len(test_set)
    share = bound_share(weights, others)
    assert 0.0 <= share <= 1.0


def test_fit_weight_is_the_tightest_first_order_bound_of_its_points() -> None:
    f = np.array([0.5, 1.0, 5.0, 20.0, 50.0])
    rel = np.array([0.02, 0.02, 0.05, 0.3, 0.5])
    w = fit_weight(f, rel)
    assert np.all(w.magnitude(f) >= rel)
    assert w.magnitude(f).max() / rel.max() < 1.5  # tight where the error is largest
    with pytest.raises(DataValidationError, match="rel"):
        fit_weight(f, rel[:2])


def test_band_checks_its_own_fields() -> None:
    with pytest.raises(DataValidationError, match="band.quantiles"):
        Band(a=1.0, b=0.0, quantiles=(1.0, 2.0))


# ----------------------------------------------------------------------------- command line
def _folder(path: Path, records: ExperimentSet) -> Path:
    path.mkdir()
    for e in records:
        write_csv(e, path / f"{e.name}.csv")
    return path


def test_fit_band_simulate_interval_and_export_weight_from_the_command_line(
    train, test_set, tmp_path: Path, capsys
) -> None:
    data = _folder(tmp_path / "train", train)
    model = tmp_path / "lpv.json"
    code, out, err = _run(["fit", "lpv", str(data), "--out", str(model), "--band"], capsys)
    assert code == 0, err
    assert "band calibrated on" in out
    rec = tmp_path / "held.csv"
    write_csv(test_set[1], rec)
    pred = tmp_path / "pred.csv"
    code, out, err = _run(
        ["simulate", str(model), str(rec), "--out", str(pred), "--interval", "0.9"], capsys
    )
    assert code == 0, err
    import pandas as pd

    frame = pd.read_csv(pred)
    assert list(frame.columns) == ["t", "F", "F_pred", "F_lower", "F_upper"]
    assert (frame.F_lower <= frame.F_upper).all()
    assert "inside the 0.9 band" in out
    exported = tmp_path / "lpv_export.json"
    code, out, err = _run(["export", str(model), "--out", str(exported)], capsys)
    assert code == 0, err
    assert "uncertainty weight W(s) at 3 input level(s)" in out
    saved = json.loads(exported.read_text())
    assert saved["W_num"]["shape"] == [3, 2]


def test_simulate_interval_on_a_model_without_a_band_is_one_line(train, tmp_path, capsys) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = get_estimator("bingham").fit(train).save(tmp_path / "b.json")
    rec = tmp_path / "r.csv"
    write_csv(train[0], rec)
    code, _out, err = _run(
        ["simulate", str(path), str(rec), "--out", str(tmp_path / "p.csv"), "--interval", "0.9"],
        capsys,
    )
    line = _one_line_error(code, err)
    assert "--interval" in line and "no band stored" in line
    code, _out, err = _run(
        ["simulate", str(path), str(rec), "--out", str(tmp_path / "p.csv"), "--interval", "1.5"],
        capsys,
    )
    assert "--interval: expected a coverage level" in _one_line_error(code, err)
