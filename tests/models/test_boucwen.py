"""The classic Bouc-Wen model: known answer, step, round trip, one level."""

from __future__ import annotations

from pathlib import Path

from tests.models import hysteresis_cases as cases

TRUE = {
    "c0a": 800.0,
    "c0b": 4000.0,
    "k0": 500.0,
    "alpha_a": 3.0e5,
    "alpha_b": 1.5e6,
    "gamma": 1.0e6,
    "beta": 2.0e6,
    "A": 1.0,
    "n": 2.0,
    "f0": 5.0,
}


def test_known_answer_identification_recovers_parameters() -> None:
    fit = cases.check_known_answer(
        "boucwen", TRUE, tuple(k for k in TRUE if k != "A"), rel=2e-2, eta=50.0
    )
    assert fit.A == 1.0 and fit.eta == 50.0


def test_step_equals_predict_with_and_without_drive_lag() -> None:
    cases.check_step_equals_predict("boucwen", TRUE)
    cases.check_step_equals_predict("boucwen", {**TRUE, "n": 1.5}, eta=60.0)


def test_json_round_trip(tmp_path: Path) -> None:
    cases.check_round_trip("boucwen", TRUE, tmp_path)


def test_single_level_fits_constants() -> None:
    cases.check_single_level("boucwen", TRUE, ("c0b", "alpha_b"))


def test_bad_values_name_the_field() -> None:
    cases.check_bad_values("boucwen", TRUE, "n", 0.5)


def test_kernel_matches_a_tight_reference() -> None:
    cases.check_kernel_against_reference("boucwen", TRUE)
    cases.check_kernel_against_reference("boucwen", TRUE, eta=60.0)
    # as stiff as the fit on the Quiroz records (n = 1, gamma = beta, z_max 29 um)
    stiff = {"alpha_a": 3.6e6, "alpha_b": 2.5e7, "gamma": 17392.0, "beta": 17392.0, "n": 1.0}
    cases.check_kernel_against_reference("boucwen", {**TRUE, **stiff})
