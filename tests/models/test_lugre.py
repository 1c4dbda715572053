"""The LuGre model of an MR damper (Jiménez and Álvarez-Icaza 2005): known answer, step, round
trip, one level."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.models import hysteresis_cases as cases

TRUE = {
    "sigma_a": 3.0e5,
    "sigma_0": 1.5e6,
    "sigma_1": 200.0,
    "sigma_2": 900.0,
    "sigma_b": 4000.0,
    "a0": 2.0e-3,
    "f0": 2.0,
}


def test_known_answer_identification_recovers_parameters() -> None:
    cases.check_known_answer("lugre", TRUE, tuple(TRUE), rel=1e-3)


def test_step_equals_predict_with_and_without_drive_lag() -> None:
    cases.check_step_equals_predict("lugre", TRUE)
    cases.check_step_equals_predict("lugre", TRUE, eta=60.0)


def test_json_round_trip(tmp_path: Path) -> None:
    cases.check_round_trip("lugre", TRUE, tmp_path)


def test_single_level_fits_constants() -> None:
    fit = cases.check_single_level("lugre", TRUE, ("sigma_b",))
    assert fit.provenance["fixed"]["sigma_0"] == pytest.approx(fit.sigma_0)


def test_bad_values_name_the_field() -> None:
    cases.check_bad_values("lugre", TRUE, "a0", -1.0)


def test_kernel_matches_a_tight_reference() -> None:
    cases.check_kernel_against_reference("lugre", TRUE)
    cases.check_kernel_against_reference("lugre", TRUE, eta=60.0)
