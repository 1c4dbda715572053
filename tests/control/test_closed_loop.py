"""Any damper in the quarter-car loop: the generic-plant loop against the fused kernel, the rig's
reference damper as controller model and plant, predicted against achieved, the halving check and
the command line."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from numba import njit

from mrdamper.cli.main import main
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.fidelity import checked_run, closed_loop_fidelity, loop_metrics
from mrdamper.control.loop.quarter_car import QuarterCar, iso_road, simulate_quarter_car
from mrdamper.errors import DataValidationError, MrDamperError
from mrdamper.models.lpv import LTIModel
from mrdamper.models.semiphenomenological import SP3Model
from mrdamper.models.sp import kernels as SK
from mrdamper.models.step import Step
from mrdamper.models.step_dispatch import pack
from mrdamper.rig.reference import reference_damper

S = (800.0, 200.0, 60.0, 0.0, 900.0, 0.0)


def _sp3() -> SP3Model:
    return SP3Model(S=S, input_range=(0.0, 1.0))


def _road(duration: float = 2.0):  # type: ignore[no-untyped-def]
    return iso_road("C", duration=duration, fs=1000.0, seed=3)


@pytest.mark.parametrize("ctrl", ["soft", "skyhook"])
def test_model_as_its_own_plant_is_the_fused_kernel(ctrl: str) -> None:
    m, road = _sp3(), _road()
    a = simulate_quarter_car(m, road, ctrl)
    b = simulate_closed_loop(m, road, ctrl)
    for name in ("a_s", "F", "i", "z_s", "z_u"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_a_static_map_s_force_is_recorded_at_every_plant_step() -> None:
    # four plant steps per road sample: the fused kernel (the model as its own plant) and the
    # generic loop (a copy as plant) record the same force at every plant step, and it moves
    # within a sample (the map is evaluated at each step's motion)
    import copy

    m, road = _sp3(), _road(1.0)
    a = simulate_quarter_car(m, road, "soft", substeps=4)
    b = simulate_closed_loop(m, road, "soft", plant=copy.deepcopy(m), substeps=4)
    assert a.F.size == a.t.size
    np.testing.assert_allclose(a.F, b.F, rtol=1e-9, atol=1e-9)
    assert np.ptp(a.F.reshape(-1, 4), axis=1).max() > 1.0  # [N]


@njit(cache=False)
def _wrapped_force(form, s, x, v, e):  # type: ignore[no-untyped-def]
    return SK.step_force(form, s, x, v, e)


@njit(cache=False)
def _wrapped_advance(form, s, x0, v0, e0, x1, v1, e1, dt):  # type: ignore[no-untyped-def]
    return SK.step_advance(form, s, x0, v0, e0, x1, v1, e1, dt)


class _RuntimeFamily:
    """A damper whose step functions are not a built-in family's (as a family added at run time)."""

    kind, input = "wrapped", "i"

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        return dataclasses.replace(
            _sp3().step(dt=dt), kind=self.kind, force=_wrapped_force, advance=_wrapped_advance
        )


@pytest.mark.slow
def test_a_family_added_at_run_time_takes_the_function_path() -> None:
    # its step is not packed: the loop compiled with its functions gives the cached loop's numbers
    road = _road(1.0)
    assert pack(_RuntimeFamily().step()) is None and pack(_sp3().step()) is not None
    a = simulate_closed_loop(_sp3(), road, "skyhook", plant=_sp3())
    b = simulate_closed_loop(_sp3(), road, "skyhook", plant=_RuntimeFamily())
    for name in ("a_s", "F", "i"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


@pytest.mark.slow
def test_reference_damper_as_controller_and_plant_equals_itself() -> None:
    truth = reference_damper("quiroz2022")
    res = closed_loop_fidelity(
        truth, "rig", controllers=["soft", "skyhook"], duration=1.0, max_substeps=4
    )
    t = res.table()
    assert set(t["metric"]) == {
        "rms_acc",
        "a_w",
        "rms_tyre_load",
        "rms_travel",
        "rms_tracking",
        "mean_current",
    }
    np.testing.assert_array_equal(t["predicted"], t["achieved"])
    sky = t[t["controller"] == "skyhook"].set_index("metric")
    assert 0.0 < sky.loc["mean_current", "achieved"] < 1.0  # the step inverse acts
    assert np.isfinite(sky.loc["rms_tracking", "achieved"])


def test_another_plant_gives_another_answer() -> None:
    road = _road()
    pred = loop_metrics(simulate_closed_loop(_sp3(), road, "skyhook"))
    ach = loop_metrics(simulate_closed_loop(_sp3(), road, "skyhook", plant="rig"))
    assert abs(pred["rms_acc"] - ach["rms_acc"]) > 1e-3 * ach["rms_acc"]
    assert pred["mean_current"] != ach["mean_current"]


def test_a_static_map_as_plant_through_the_step_would_equal_the_fused_kernel() -> None:
    # the plant's force at every RK stage with its (empty) state held is the fused kernel's
    # scheme: the rig damper with its own inverse, halved twice, moves the metrics by < 0.5 %
    truth = reference_damper("quiroz2022")
    road = _road(1.0)
    r, s, change = checked_run(
        lambda k: simulate_closed_loop(truth, road, "hard", substeps=k), max_substeps=8
    )
    assert change <= 0.005 and s >= 1 and r.fs == 1000.0 * s


def test_halving_check_refuses_with_the_figure() -> None:
    road = _road(1.0)
    with pytest.raises(MrDamperError, match="not converged.*%"):
        checked_run(
            lambda k: simulate_closed_loop(_sp3(), road, "hard", substeps=k),
            tol=1e-12,
            max_substeps=2,
        )


def test_bad_pairs_are_refused() -> None:
    with pytest.raises(DataValidationError, match="not the same input"):
        simulate_closed_loop(_sp3(), _road(), "soft", plant="rig:spencer1997")
    lti = LTIModel(
        alpha=np.array([[-0.5]]),
        beta=np.array([[800.0]]),
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )
    r = simulate_closed_loop(lti, _road(), "skyhook", plant="rig")  # inverted through its step
    assert np.all(np.isfinite(r.i)) and 0.0 <= r.i.min() and r.i.max() <= 1.0


def test_cli_plant(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = _sp3().save(tmp_path / "sp3.json")
    base = ["quartercar", str(model), "--roads", "C", "--duration", "1.5", "--plant", "rig"]
    main([*base, "--controllers", "soft,skyhook", "--out", str(tmp_path / "o")])
    printed = capsys.readouterr().out
    assert "rms_acc [m/s²]" in printed and "error [%]" in printed
    t = pd.read_csv(tmp_path / "o" / "closed_loop.csv")
    assert list(t.columns) == [
        "controller",
        "road",
        "speed_m_s",
        "metric",
        "predicted",
        "achieved",
        "error_pct",
        "stroke_ratio",
        "outside_stroke",
    ]
    assert len(t) == 2 * 6
    assert (tmp_path / "o" / "closed_loop_runs.csv").is_file()


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["--speed", "-5"], "--speed"),
        (["--plant", "rig:spencer1997"], "not the same input"),
        (["--plant", "nowhere.json"], "--plant"),
    ],
)
def test_cli_plant_refusals(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], field: str
) -> None:
    model = _sp3().save(tmp_path / "sp3.json")
    with pytest.raises(SystemExit) as info:
        main(["quartercar", str(model), "--out", str(tmp_path / "o"), "--plant", "rig", *args])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and field in err


def test_a_refused_run_keeps_its_rows_and_names_the_metric() -> None:
    # one run that does not converge does not take the others with it: its rows are NaN and a
    # note gives the figure and the metric that moved
    res = closed_loop_fidelity(
        _sp3(), "rig", controllers=["hard"], duration=1.0, tol=1e-12, max_substeps=2
    )
    t = res.table()
    assert len(t) == 6 and t["predicted"].isna().all() and t["error_pct"].isna().all()
    refused = [n for n in res.notes if "refused" in n]
    assert len(refused) == 1  # one line naming both runs, predicted and achieved
    assert refused[0].startswith("2 run(s) refused")
    assert "hard ISO C @ 20 m/s predicted, hard ISO C @ 20 m/s achieved" in refused[0]
    assert any(m in refused[0] for m in ("rms_acc", "a_w", "rms_tyre_load", "rms_travel"))
    assert "%" in refused[0] and "\n" not in refused[0]
    assert all("refused" in r for r in res.runs)


def test_a_diverged_run_keeps_its_rows_and_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    # a loop that diverges with the model as the damper is a finding about the model, not the end
    # of the comparison: that run's rows are NaN with a "diverged" note, the other runs are kept
    from mrdamper.control.loop import fidelity
    from mrdamper.errors import SimulationDivergedError

    real = fidelity.simulate_closed_loop

    def flaky(model, road, ctrl, car, *, plant=None, **kw):  # type: ignore[no-untyped-def]
        if plant is None and ctrl.kind == "hard":
            raise SimulationDivergedError("sp3", 7, "state left +-10")
        return real(model, road, ctrl, car, plant=plant, **kw)

    monkeypatch.setattr(fidelity, "simulate_closed_loop", flaky)
    res = closed_loop_fidelity(_sp3(), "rig", controllers=["soft", "hard"], duration=1.0)
    t = res.table()
    hard, soft = t[t["controller"] == "hard"], t[t["controller"] == "soft"]
    passive = ~t["metric"].isin(["rms_tracking", "mean_current"])  # defined for both sides
    assert hard["predicted"].isna().all() and hard.loc[passive, "achieved"].notna().all()
    assert soft.loc[passive, "error_pct"].notna().all()
    why = (
        "sp3: simulation diverged at sample 7: state left +-10, at every plant step down to 1/32 "
        "of the road's: the loop itself diverges, not its integration"
    )
    diverged = [n for n in res.notes if "diverged" in n]
    said = "1 run(s) diverged, their metrics left empty (hard ISO C @ 20 m/s predicted)"
    assert diverged == [f"{said}; the first: {why}"]
    assert [r["refused"] for r in res.runs if "refused" in r] == [f"diverged: {why}"]


def test_a_sampled_loop_oscillation_is_detected_with_its_frequency() -> None:
    # a run whose body acceleration carries an 83 Hz limit cycle (as an LPV model at 1 kHz in
    # passive hard on a smooth road) against the same run without it
    from mrdamper.control.loop.fidelity import HF_SHARE, oscillation

    r = simulate_closed_loop(_sp3(), _road(2.0), "soft")
    clean, _ = oscillation(r)
    assert clean < HF_SHARE
    wobble = 3.0 * np.std(r.a_s) * np.sin(2 * np.pi * 83.0 * r.t)
    share, peak = oscillation(dataclasses.replace(r, a_s=r.a_s + wobble))
    assert share > HF_SHARE and abs(peak - 83.0) <= 1.0


def test_the_oscillation_note_tells_a_sampled_loop_from_the_model_s_own_mode() -> None:
    # a peak near a discrete model's Nyquist frequency asks for a higher rate; below it the note
    # weighs the one-sample delay at the peak (360 f / fs degrees)
    from mrdamper.control.loop.fidelity import oscillation_note

    car = QuarterCar()
    near = oscillation_note(0.5, 480.0, car, 1000.0)
    delayed = oscillation_note(0.5, 37.0, car, 200.0)  # 67 deg
    own = oscillation_note(0.5, 55.0, car, 1000.0)  # 20 deg
    assert near.startswith("sampled-loop oscillation") and "(500 Hz)" in near
    assert "lags by 67 deg" in delayed and "shortens that delay" in delayed
    assert "lags by 20 deg" in own and "a higher rate barely changes it" in own
    assert "`mrdamper rig doe --extension control`" in own  # the command, not the Python API
    assert "doe_extension" not in own
    assert oscillation_note(0.5, 55.0, car).startswith("high-frequency loop oscillation")


def _delayed_damper(c: float) -> LTIModel:
    """``F[k] = c v[k-1]`` at 1 kHz: a linear damper [N s/m] one sample late (no feedthrough)."""
    return LTIModel(
        alpha=np.array([[0.0]]),
        beta=np.array([[c]]),
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )


def test_a_discrete_plant_s_force_is_linear_between_its_samples() -> None:
    # four plant steps per model sample: the recorded force at the steps in between lies on the
    # line from one sample's force to the next (first-order hold), continuous at the samples
    lti = _delayed_damper(1500.0)
    r = simulate_closed_loop(lti, _road(1.0), "soft", plant=lti, substeps=4)
    F = r.F[: (r.F.size // 4) * 4].reshape(-1, 4)
    start, end = F[:-1, 0], F[1:, 0]
    for s in range(1, 4):
        np.testing.assert_allclose(F[:-1, s], start + (end - start) * s / 4, atol=1e-9)
    assert np.ptp(F) > 100.0  # the force moves (the check is not on a constant)


def test_a_fitted_lpv_filter_does_not_ring_in_the_loop() -> None:
    # the frozen 0 A filter of the default LPV model fitted on the rig's Table II (1 kHz, rounded;
    # a pole at -0.997, near the model's Nyquist frequency), driven by the velocity: with its
    # force held over each sample (a zero-order hold, half a sample more delay) this loop diverged
    # after 3.3 s on this road; linear between the samples it stays bounded and smooth
    from mrdamper.control.loop.fidelity import HF_SHARE, oscillation

    lti = LTIModel(
        alpha=np.array([[-0.51], [-0.95], [0.55]]),
        beta=np.array([[3600.0], [2150.0], [-4600.0]]),
        fs=1000.0,
        input_signal="v",
        input_range=(0.0, 1.0),
    )
    road = iso_road("B", speed=10.0, duration=4.0, fs=1000.0, seed=1)
    r = simulate_closed_loop(lti, road, "soft", plant=lti, substeps=4)
    share, _ = oscillation(r)
    assert share < HF_SHARE
    assert np.sqrt(np.mean(r.a_s**2)) < 2.0  # [m/s²]; the held loop left +-10 m


def test_the_envelope_note_names_only_the_dimensions_the_loop_leaves() -> None:
    from mrdamper.control.loop.fidelity import _excursion_text

    exc = {"velocity": 0.71, "stroke": 1.3, "switching": 2.5}
    assert _excursion_text(exc) == "switching-while-moving velocity x2.5, stroke x1.3"
    assert _excursion_text({"velocity": 0.5, "stroke": 1.0, "switching": 0.0}) == ""
    assert _excursion_text({"velocity": 0.9, "frequency": 3.2}) == "frequency content x3.2"
    # within the tolerance of a record's note (5 %) a dimension is not named: no "x1"
    assert _excursion_text({"velocity": 1.04, "switching": 1.049}) == ""
    assert _excursion_text({"velocity": 1.06}) == "velocity x1.1"
    # training records that never switch while moving: said in words, not "xinf"
    text = _excursion_text({"velocity": 2.0, "switching": np.inf})
    assert (
        text == "velocity x2, the input switches while the damper moves, which no training "
        "record does"
    )


def test_the_loop_note_names_frequency_content_beyond_the_training_band() -> None:
    # a model whose training records reach 2 Hz (f_band) and 5 m/s: the loop's motion, with its
    # wheel hop near 12 Hz, leaves the band and nothing else; one band as wide as the loop's
    # stays silent
    env = {"v_max": 5.0, "x_range": [-0.5, 0.5], "e_range": [0.0, 1.0], "v_switch": 5.0}
    low = dataclasses.replace(_sp3(), provenance={"envelope": {**env, "f_band": 2.0}})
    res = closed_loop_fidelity(low, "rig", controllers=["soft", "hard"], duration=2.0)
    notes = [n for n in res.notes if "training envelope" in n]
    # once, the largest excursion over the loops and the remedy: records of the loop's motions
    band = max(r["excursion_frequency"] for r in res.runs if r["side"] == "achieved")
    assert len(notes) == 1 and f"(at most: frequency content x{band:.2g})" in notes[0]
    assert res.runs[1]["excursion_frequency"] > 2.0  # the loop's band is above 4 Hz
    assert notes[0].startswith("2 of 2 loops leave the sp3 model's training envelope")
    assert "mrdamper rig doe --extension control" in notes[0] and "\n" not in notes[0]
    wide = dataclasses.replace(_sp3(), provenance={"envelope": {**env, "f_band": 200.0}})
    res = closed_loop_fidelity(wide, "rig", controllers=["soft"], duration=2.0)
    assert not [n for n in res.notes if "training envelope" in n]


def test_cli_plant_warnings_once_each_on_stderr_in_the_user_s_words(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # every loop leaves a narrow training envelope (a 2 Hz band, no switching while moving):
    # one line per finding over every run, on standard error, naming the command to run
    env = {"v_max": 0.05, "x_range": [-0.01, 0.01], "e_range": [0.0, 1.0], "v_switch": 0.0}
    narrow = dataclasses.replace(_sp3(), provenance={"envelope": {**env, "f_band": 2.0}})
    model = narrow.save(tmp_path / "sp3.json")
    main(
        ["quartercar", str(model), "--roads", "A,C", "--duration", "1", "--plant", "rig"]
        + ["--controllers", "soft,hard,skyhook", "--out", str(tmp_path / "o")]
    )
    out, err = capsys.readouterr()
    assert "warning:" not in out
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines and all(ln.startswith("warning: ") for ln in lines)
    assert len(lines) == len(set(lines)) <= 5, lines
    envelope = [ln for ln in lines if "training envelope" in ln]
    assert len(envelope) == 1 and envelope[0].startswith("warning: 6 of 6 loops leave")
    assert "mrdamper rig doe --extension control" in envelope[0]
    assert "xinf" not in err and "doe_extension" not in err


def test_a_run_that_diverges_is_repeated_at_half_the_step() -> None:
    # a loop that diverges at the road's step (as a stiff damper coupled one step late does) is
    # run again at half the step; the halving check then starts from the first step that ran
    from mrdamper.errors import SimulationDivergedError

    road, tried = _road(1.0), []

    def run(k: int):  # type: ignore[no-untyped-def]
        tried.append(k)
        if k < 4:
            raise SimulationDivergedError("sp3", 9, "a car state left +-10")
        return simulate_closed_loop(_sp3(), road, "soft", substeps=k)

    r, s, change = checked_run(run, max_substeps=16)
    assert (s, tried) == (4, [1, 2, 4, 8]) and r.fs == 4000.0 and change <= 0.005
    with pytest.raises(SimulationDivergedError, match="every plant step down to 1/8"):
        checked_run(lambda k: run(0), max_substeps=16)


def test_a_comparison_keeps_the_runs_that_ran(monkeypatch: pytest.MonkeyPatch) -> None:
    # a run that cannot be made is a row with its reason; the others are kept, and the runs of a
    # damper through its step state their plant step and its check
    from mrdamper.control.loop import quarter_car_study as QS
    from mrdamper.errors import SimulationDivergedError

    real = QS.simulate_closed_loop

    def flaky(model, road, ctrl, car, **kw):  # type: ignore[no-untyped-def]
        if ctrl.kind == "skyhook":
            raise SimulationDivergedError("spencer", 3, "a car state left +-10")
        return real(model, road, ctrl, car, **kw)

    monkeypatch.setattr(QS, "simulate_closed_loop", flaky)
    cmp = QS.compare_controllers(
        reference_damper(), road_classes=("C",), bump=False, controllers=("soft", "skyhook"),
        duration=1.0,
    )  # fmt: skip
    t = cmp.table()
    assert list(t["status"].str[:8]) == ["ok", "Simulati"] and t["rms_acc"].isna().tolist() == [
        False,
        True,
    ]
    assert t["substeps"].iloc[0] >= 1 and t["halving_change_pct"].iloc[0] <= 0.5
    assert "each checked by halving it" in cmp.step_note() and cmp.plot_time().axes
