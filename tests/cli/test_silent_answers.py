"""Inputs that used to give a silent wrong answer: each is now refused in one line, or warned
about in one line, before any work is done (the catalogue of such cases)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mrdamper.data import write_csv
from mrdamper.models.lpv import LPVModel
from mrdamper.models.semiphenomenological import SP3Model
from tests.test_bad_inputs import FS, _folder, _one_line_error, _run, _sine

#: A one-level model: identified at 0.5 A only, its force does not depend on the current.
ONE_LEVEL = SP3Model(S=(800.0, 200.0, 60.0, 0.0, 900.0, 0.0), f0=10.0, input_range=(0.5, 0.5))


def test_quartercar_refuses_a_model_identified_at_one_level(tmp_path, capsys) -> None:
    model = ONE_LEVEL.save(tmp_path / "one.json")
    out = tmp_path / "qc"
    line = _one_line_error(
        *_run(["quartercar", str(model), "--out", str(out), "--duration", "2"], capsys)[::2]
    )
    assert "one i level (0.5 A)" in line
    assert "every controller gives the same numbers" in line
    assert not out.exists()


def test_c_export_of_a_frozen_unstable_model_warns_like_the_other_formats(tmp_path, capsys) -> None:
    unstable = LPVModel(
        alpha=np.array([[-1.05]]),
        beta=np.array([[1.0]]),
        fs=FS,
        input_signal="v",
        rho_range=(0.0, 1.0),
        input_range=(0.0, 1.0),
    )
    path = unstable.save(tmp_path / "u.json")
    warnings.simplefilter("always", RuntimeWarning)  # one process runs three commands here
    lines = {}
    for fmt, out in (
        ("c", tmp_path / "c"),
        ("mat", tmp_path / "u.mat"),
        ("json", tmp_path / "j.json"),
    ):
        code, _out, err = _run(["export", str(path), "--format", fmt, "--out", str(out)], capsys)
        assert code == 0, err
        warns = [ln for ln in err.splitlines() if ln.startswith("warning: ")]
        assert len(warns) == 1, err
        lines[fmt] = warns[0]
    assert lines["c"] == lines["mat"] == lines["json"]
    assert "not frozen-stable" in lines["c"]


@pytest.mark.parametrize(
    ("setting", "expected"),
    [
        ("spl.n_starts=1", "error: --set: unknown model kind 'spl' in 'spl.n_starts=1'"),
        ("lpv.bogus=1", "error: lpv.bogus: lpv does not take the setting 'bogus'"),
        ("lpv.n_m=abc", "error: lpv.n_m: expected an integer >= 1, got 'abc'"),
        ("sp1.n_starts=2", "error: sp1.n_starts: a setting of 'sp1', which is not among"),
    ],
)
def test_select_refuses_bad_settings_before_any_fold(
    setting, expected, tmp_path, capsys, monkeypatch
) -> None:
    from mrdamper.study import selection

    def no_fold(*_a, **_k):
        raise AssertionError("a fold ran")

    monkeypatch.setattr(selection, "selection_folds", no_fold)
    data = _folder(tmp_path / "d")
    line = _one_line_error(
        *_run(["select", str(data), "-m", "lpv", "--set", setting, "--no-progress"], capsys)[::2]
    )
    assert line.startswith(expected), line


def test_select_in_which_every_fit_failed_exits_non_zero(tmp_path, capsys, monkeypatch) -> None:
    from mrdamper.models.semiphenomenological import SP1Estimator

    def broken(self, *_a, **_k):
        raise RuntimeError("singular")

    monkeypatch.setattr(SP1Estimator, "_identify", broken)
    data = _folder(tmp_path / "d")
    code, out, err = _run(["select", str(data), "-m", "sp1", "--no-progress"], capsys)
    assert code == 1
    assert "singular" in out
    assert err.strip().splitlines()[-1].startswith("error: every fit failed")


@pytest.mark.parametrize("kind", ["sp1", "lpv", "p15", "narx", "spencer", "bingham", "lti"])
def test_fit_refuses_a_record_without_motion(kind, tmp_path, capsys) -> None:
    folder = tmp_path / "still"
    folder.mkdir()
    for k, cur in enumerate((0.0, 0.5, 1.0)):
        e = _sine(f"s{k}", cur)
        noise = 1e-9 * np.random.default_rng(k).standard_normal(e.n)
        write_csv(e.replace(v=noise), folder / f"s{k}.csv")
    line = _one_line_error(
        *_run(["fit", kind, str(folder), "--out", str(tmp_path / "m.json")], capsys)[::2]
    )
    assert line.startswith("error: v: training record 's0' has no motion (max |v| = ")
    assert "m/s, below 1e-06 m/s" in line
    assert not (tmp_path / "m.json").exists()


def test_study_in_which_every_fit_failed_exits_non_zero_and_writes_nothing(
    tmp_path, capsys, monkeypatch
) -> None:
    from mrdamper.models.semiphenomenological import SP2Estimator

    def broken(self, *_a, **_k):
        raise RuntimeError("singular")

    monkeypatch.setattr(SP2Estimator, "_identify", broken)
    data = _folder(tmp_path / "d")
    out = tmp_path / "out"
    code, stdout, err = _run(
        [
            "study",
            str(data),
            "--out",
            str(out),
            "--models",
            "sp2",
            "--workers",
            "1",
            "--no-progress",
        ],
        capsys,
    )
    assert code == 1, err
    assert "singular" in stdout
    assert err.strip().splitlines()[-1].startswith("error: every fit failed")
    assert not out.exists()


def test_the_motion_floor_is_far_below_real_motion() -> None:
    from mrdamper.models.base import MIN_PEAK_VELOCITY

    e = _sine("r", 0.5, amp=1e-4, freq=0.5)  # 0.1 mm at 0.5 Hz: 0.3 mm/s peak, still motion
    assert np.max(np.abs(e.v)) > 100 * MIN_PEAK_VELOCITY
