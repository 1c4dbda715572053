"""The hyperbolic-tangent model (Kwok et al. 2006): known answer, step, round trip, one level."""

from __future__ import annotations

from pathlib import Path

from tests.models import hysteresis_cases as cases

TRUE = {
    "ca": 900.0,
    "cb": 4000.0,
    "k": 600.0,
    "alpha_a": 150.0,
    "alpha_b": 900.0,
    "beta": 80.0,
    "delta": 0.2,
    "f0": 3.0,
}


def test_known_answer_identification_recovers_parameters() -> None:
    cases.check_known_answer("tanh", TRUE, tuple(TRUE), rel=1e-3)


def test_step_equals_predict_with_and_without_drive_lag() -> None:
    cases.check_step_equals_predict("tanh", TRUE)
    cases.check_step_equals_predict("tanh", TRUE, eta=60.0)


def test_json_round_trip(tmp_path: Path) -> None:
    cases.check_round_trip("tanh", TRUE, tmp_path)


def test_single_level_fits_constants() -> None:
    cases.check_single_level("tanh", TRUE, ("cb", "alpha_b"))


def test_bad_values_name_the_field() -> None:
    cases.check_bad_values("tanh", TRUE, "beta", 0.0)
