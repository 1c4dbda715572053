"""The modified Dahl model (Zhou et al. 2006): known answer, step, round trip, one level."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.models import hysteresis_cases as cases

TRUE = {
    "c0a": 900.0,
    "c0b": 5000.0,
    "k0": 400.0,
    "Fda": 150.0,
    "Fdb": 800.0,
    "sigma": 3000.0,
    "f0": -4.0,
}


def test_known_answer_identification_recovers_parameters() -> None:
    cases.check_known_answer("dahl", TRUE, tuple(TRUE), rel=1e-3)


def test_dahl_variable_stays_in_its_bounds() -> None:
    """|z| <= 1 for any motion: the force never exceeds the viscous, spring and Dahl terms."""
    model = cases.truth("dahl", {**TRUE, "sigma": 1e5})
    e = cases.record(8, duration=1.0)
    F = model.predict(e)
    bound = (900 + 5000 * e.i) * np.abs(e.v) + 400 * np.abs(e.x) + 150 + 800 * e.i + 4.0
    assert np.all(np.abs(F) <= bound + 1e-9)


def test_step_equals_predict_with_and_without_drive_lag() -> None:
    cases.check_step_equals_predict("dahl", TRUE)
    cases.check_step_equals_predict("dahl", TRUE, eta=60.0)


def test_json_round_trip(tmp_path: Path) -> None:
    cases.check_round_trip("dahl", TRUE, tmp_path)


def test_single_level_fits_constants() -> None:
    cases.check_single_level("dahl", TRUE, ("c0b", "Fdb"))


def test_bad_values_name_the_field() -> None:
    cases.check_bad_values("dahl", TRUE, "sigma", -1.0)


def test_kernel_matches_a_tight_reference() -> None:
    cases.check_kernel_against_reference("dahl", TRUE)
    cases.check_kernel_against_reference("dahl", TRUE, eta=60.0)
    cases.check_kernel_against_reference("dahl", {**TRUE, "sigma": 1e5})  # sharp yield
