"""The LPV model's parallel stiffness ``k_x`` (``F = y + F0 + k_x x``): identified with the other
unknowns, carried by every tool that runs the model (prediction, step, inverse, state space,
export), fixed or switched off by a setting."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment, load_model
from mrdamper.control import inverse_current
from mrdamper.control.export.matrices import lpv_export_data
from mrdamper.control.export.statespace import simulate_state_space
from mrdamper.models.lpv import LPVEstimator, LPVModel
from mrdamper.models.lpv import kernels as K
from mrdamper.models.step import run_step
from tests.models.test_lpv import ALPHA, BETA, FS

K_X = 850.0  # [N/m]
OFFSET = -40.0  # [N]


def _record(level: float, seed: int, varying: bool = False) -> Experiment:
    """A record of the known LPV structure (``u = v``) plus ``F0 + K_X x``; the displacement
    has a slow drift so that it is not a filtered copy of the velocity."""
    rng = np.random.default_rng(seed)
    n = 2000
    t = np.arange(n) / FS
    v = 0.1 * np.sin(2 * np.pi * 1.3 * t) + 0.03 * rng.standard_normal(n)
    x = np.cumsum(v) / FS + 0.004 * np.sin(2 * np.pi * 0.21 * t + seed)
    i = np.full(n, level)
    if varying:
        i = np.clip(0.5 + 0.5 * np.sin(2 * np.pi * 0.37 * t), 0.0, 1.0)
    y, bad = K.simulate_record(v, i, ALPHA, BETA, 1e12)
    assert bad == -1
    return Experiment(t=t, x=x, v=v, F=y + OFFSET + K_X * x, i=i, name=f"s{seed}")


def _train() -> list[Experiment]:
    recs = [_record(lev, k) for k, lev in enumerate((0.0, 0.5, 1.0))]
    return [*recs, _record(0.0, 9, varying=True)]


@pytest.fixture(scope="module")
def fitted() -> LPVModel:
    return LPVEstimator(n_m=2, n_rho=2, input_signal="v", stiffness="identify").fit(_train())


def test_the_stiffness_is_identified_with_the_other_unknowns(fitted: LPVModel) -> None:
    assert fitted.stiffness == pytest.approx(K_X, rel=1e-4)
    assert fitted.offset == pytest.approx(OFFSET, abs=0.05)
    np.testing.assert_allclose(fitted.alpha, ALPHA, rtol=1e-4, atol=1e-5)
    assert fitted.score(_record(0.3, 42)).esr < 1e-8
    # the paper's structure (no stiffness, the default) cannot explain the force in phase with x
    paper = LPVEstimator(n_m=2, n_rho=2, input_signal="v").fit(_train())
    assert paper.stiffness == 0.0
    assert paper.score(_record(0.3, 42)).esr > 100 * fitted.score(_record(0.3, 42)).esr
    # a fixed value is kept as given
    fixed = LPVEstimator(n_m=2, n_rho=2, input_signal="v", stiffness=K_X).fit(_train())
    assert fixed.stiffness == K_X
    # without the refinement the least-squares start (k_x = 0) stays, and says so
    ls = LPVEstimator(n_m=2, n_rho=2, input_signal="v", refine=False, stiffness="identify").fit(
        _train()
    )
    assert ls.stiffness == 0.0 and "stiffness_note" in ls.provenance


def test_the_step_the_prediction_and_a_saved_copy_agree(fitted: LPVModel, tmp_path) -> None:
    e = _record(0.6, 7, varying=True)
    F = fitted.predict(e)
    F_step, status, _ = run_step(fitted.step(), e.x, e.v, e.i, 1.0 / FS)
    assert status == 0
    np.testing.assert_allclose(F_step, F, rtol=1e-10, atol=1e-8)
    again = load_model(fitted.save(tmp_path / "k.json"))
    assert again.stiffness == fitted.stiffness
    np.testing.assert_array_equal(again.predict(e), F)
    # a file written before the stiffness existed loads as the paper's structure
    old = dataclasses.replace(fitted, stiffness=0.0)
    np.testing.assert_allclose(old.predict(e), F - fitted.stiffness * e.x, atol=1e-9)


def test_the_inverse_takes_the_stiffness_force_out_of_the_target(fitted: LPVModel) -> None:
    e = _record(0.5, 11, varying=True)
    F = fitted.predict(e)
    res = inverse_current(fitted, e, F, method="exact")
    inside = ~res.saturated
    assert inside.mean() > 0.9
    np.testing.assert_allclose(res.F_achieved[inside], F[inside], atol=1e-6 * np.abs(F).max())
    assert np.mean(np.abs(res.i - e.i) < 1e-3) > 0.9  # the current that made the force


def test_state_space_and_export_carry_the_stiffness(fitted: LPVModel) -> None:
    e = _record(0.5, 12)
    u, rho = fitted.model_signals(e)
    with pytest.raises(DataValidationError, match="x"):
        simulate_state_space(fitted, u, rho)
    F = simulate_state_space(fitted, u, rho, x=e.x)
    np.testing.assert_allclose(F, fitted.predict(e), rtol=1e-9, atol=1e-7)
    assert lpv_export_data(fitted)["k_x"] == fitted.stiffness


@pytest.mark.parametrize("bad", ["choose", float("nan"), float("inf"), "1e3", None])
def test_a_bad_stiffness_setting_is_refused_in_one_line(bad: object) -> None:
    with pytest.raises(DataValidationError, match="stiffness") as info:
        LPVEstimator(stiffness=bad).fit(_train())  # type: ignore[arg-type]
    assert "\n" not in str(info.value)


def _stroke_test(level: float, seed: int) -> Experiment:
    """A slow sine over most of the rig's stroke (the extension's stroke test): there the
    reference damper's accumulator force ``k1 x`` (693 N/m) is a visible share of the force."""
    from mrdamper.rig import VirtualRig, reference_damper
    from mrdamper.signals import ramped_sine

    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=1000.0)
    x = ramped_sine(rig.fs, amplitude=0.018, frequency=0.5, cycles=2)
    meta = {"current": level}
    return rig.run(x, np.full(x.size, level), seed=seed, name=f"stroke{seed}", metadata=meta)


def test_auto_identifies_no_stiffness_without_given_records(rig_data) -> None:
    train, _ = rig_data
    m = LPVEstimator(stroke=1e-4, blend=0.5).fit(train[:6])
    assert LPVEstimator().stiffness == "auto" and m.stiffness == 0.0
    assert "stiffness_stages" not in m.provenance


def test_auto_lets_given_records_decide_the_stiffness(rig_data) -> None:
    train, _ = rig_data
    strokes = [_stroke_test(level, 40 + k) for k, level in enumerate((0.0, 1.0))]
    given = [_stroke_test(level, 50 + k) for k, level in enumerate((0.0, 1.0))]
    m = LPVEstimator(stroke=1e-4).fit([*train[:6], *strokes], choice_records=given)
    rows = m.provenance["hysteretic_choice"]
    with_k = [r for r in rows if r.get("stiffness") == "identify"]
    assert len(with_k) == 1 and with_k[0]["blend"] == m.blend  # the best candidate, once more
    best = min(r["held_out_esr"] for r in rows if "stiffness" not in r)
    # the given records keep it where it predicts them better, and here it does: the stroke
    # test's travel carries the reference damper's 693 N/m
    assert with_k[0]["held_out_esr"] < best
    assert 300.0 < m.stiffness < 1100.0 and "stiffness_stages" in m.provenance
    assert m.provenance["settings"]["stiffness"] == "auto"
    assert "identified" in m.provenance["hysteretic_note"]
    fixed = LPVEstimator(stroke=1e-4, stiffness=0.0).fit(
        [*train[:6], *strokes], choice_records=given
    )
    assert fixed.stiffness == 0.0
    assert not any("stiffness" in r for r in fixed.provenance["hysteretic_choice"])


@pytest.mark.slow
def test_table_ii_and_the_extension_give_the_damper_its_gas_spring() -> None:
    """End to end on the virtual rig: Table II and the control extension (with its stroke test)
    as training records, a second extension as the given records; the default keeps the
    stiffness and finds the reference damper's accumulator (693 N/m) to within a fifth."""
    from mrdamper.control.loop.doe_extension import control_extension
    from mrdamper.rig import reference_damper
    from mrdamper.rig.doe import table_ii

    truth = reference_damper("quiroz2022")
    train = [*table_ii(seed=0, scale=0.07, damper=truth)]
    train += [*control_extension(seed=1, scale=0.1, damper=truth)]
    given = control_extension(seed=2, scale=0.1, damper=truth)
    m = LPVEstimator(stroke=1e-4).fit(train, choice_records=given)
    assert m.stiffness == pytest.approx(693.0, rel=0.2)
    assert m.provenance["hysteretic_note"].endswith("identified")
