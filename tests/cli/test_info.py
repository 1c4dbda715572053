"""``mrdamper info``: summaries, detected problems, JSON output and one-line errors."""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import numpy as np
import pytest

from mrdamper.cli.main import main
from mrdamper.data import Experiment, write_csv


def _rec(
    tmp_path: Path,
    name: str = "rec",
    n: int = 2000,
    current: float = 0.5,
    clip: float | None = None,
    nan_at: int | None = None,
    units: dict | None = None,
) -> Path:
    t = np.arange(n) / 1000.0
    x = 0.004 * np.sin(2 * np.pi * 2 * t)
    v = np.gradient(x, t)
    F = 900 * np.tanh(v / 0.005)
    if clip is not None:
        F = np.clip(F, -clip, clip)
    e = Experiment(t=t, x=x, v=v, F=F, i=np.full(n, current), name=name)
    p = write_csv(e, tmp_path / f"{name}.csv", units=units)
    if nan_at is not None:
        lines = p.read_text().splitlines()
        cells = lines[nan_at + 1].split(",")
        cells[-1] = ""
        lines[nan_at + 1] = ",".join(cells)
        p.write_text("\n".join(lines) + "\n")
    return p


def _json(capsys: pytest.CaptureFixture[str], *args: str) -> list[dict]:
    main(["info", *args, "--json"])
    return json.loads(capsys.readouterr().out)


def test_summary_of_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = _rec(tmp_path)
    [row] = _json(capsys, str(p))
    assert row["name"] == "rec" and row["samples"] == 2000
    assert row["rate_hz"] == pytest.approx(1000.0)
    assert row["duration_s"] == pytest.approx(1.999)
    assert row["x_mm"] == pytest.approx([-4.0, 4.0], abs=1e-3)
    assert row["F_n"][1] == pytest.approx(900.0, rel=0.01)
    assert row["input"] == "i" and row["levels"] == [0.5]
    assert row["problems"] == []
    main(["info", str(p)])
    out = capsys.readouterr().out
    assert "rec" in out and "x [mm]" in out and "i: 0.5 A" in out


def test_units_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = _rec(tmp_path, units={"F": "kN"})  # header "F [kN]" converts itself
    [row] = _json(capsys, str(p))
    assert row["F_n"][1] == pytest.approx(900.0, rel=0.01)
    t = np.arange(100) / 1000.0
    q = tmp_path / "plain.csv"
    q.write_text(
        "t,x,v,i,F\n"
        + "\n".join(f"{a},{1000 * 0.001 * np.sin(a)},{0.1},{0.5},{np.cos(50 * a)}" for a in t)
    )
    [row] = _json(capsys, str(q), "--units", "x=mm", "--units", "F=kN")
    assert row["F_n"][1] == pytest.approx(1000.0, rel=1e-6)


def test_problems_are_reported(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rows = {
        r["name"]: r
        for r in _json(
            capsys,
            str(_rec(tmp_path, "clipped", clip=700.0)),
            str(_rec(tmp_path, "overcurrent", current=5.0)),
            str(_rec(tmp_path, "gappy", nan_at=500)),
        )
    }
    assert any("held at its maximum 700" in p for p in rows["clipped"]["problems"])
    assert any("held at its minimum -700" in p for p in rows["clipped"]["problems"])
    assert any("outside 0..4 A" in p for p in rows["overcurrent"]["problems"])
    assert any("interpolated 1 non-finite" in p for p in rows["gappy"]["problems"])
    assert not any("held at" in p for p in rows["gappy"]["problems"])


def test_folder_with_pattern(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for c in (0.0, 1.0):
        _rec(tmp_path, f"step_{c:g}A", current=c)
    rows = _json(capsys, str(tmp_path), "--pattern", r"step_(?P<current>[\d.]+)A\.csv")
    assert [r["name"] for r in rows] == ["step_0A", "step_1A"]
    rows = _json(capsys, str(tmp_path))  # no sine-pattern file: every record file is read
    assert len(rows) == 2


@pytest.mark.parametrize(
    ("args", "text"),
    [
        (["info", "does/not/exist.csv"], "does/not/exist.csv: no such file"),
        (["info"], "PATH: give at least one file or folder"),
        (["info", "{p}", "--units", "F=stone"], "unknown unit 'stone'"),
        (["info", "{p}", "--units", "F"], "expected KEY=VALUE"),
        (["info", "{d}", "--pattern", "sine_("], "not a valid regular expression"),
    ],
)
def test_errors_are_one_line_with_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], text: str
) -> None:
    p = _rec(tmp_path)
    args = [a.format(p=p, d=tmp_path) for a in args]
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert text in err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert "Traceback" not in err


def test_debug_shows_the_exception(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        main(["--debug", "info", str(tmp_path / "missing.csv")])


def test_example_wiring(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # Stand-in for the rig's DoE module: checks the call, independent of the rig's state.
    import sys
    import types

    from mrdamper.data import ExperimentSet

    calls: list[dict] = []
    t = np.arange(100) / 1000.0

    def table_ii(**kw: float) -> ExperimentSet:
        calls.append(kw)
        return ExperimentSet(
            [
                Experiment(
                    t=t, x=t, v=t + 1, F=np.sin(40 * t) * 100, i=0.5 + 0 * t, name="exp1_rep01"
                )
            ]
        )

    monkeypatch.setitem(sys.modules, "mrdamper.rig.doe", types.SimpleNamespace(table_ii=table_ii))
    [row] = _json(capsys, "--example")
    assert calls == [{"seed": 0, "scale": 0.1}]
    assert row["name"] == "exp1_rep01" and row["levels"] == [0.5]
    main(["info", "--example"])
    assert "Table II" in capsys.readouterr().out


def test_example(capsys: pytest.CaptureFixture[str]) -> None:
    try:
        importlib.import_module("mrdamper.rig.doe")
    except ImportError as exc:
        pytest.skip(f"mrdamper.rig.doe cannot be imported ({exc})")
    rows = _json(capsys, "--example")
    assert len(rows) == 61  # Table II: 11 + 11 + 11 + 3 + 4 + 7 + 7 + 7 replicates
    assert all(r["samples"] > 0 and r["rate_hz"] > 0 for r in rows)
    # The electrical input stays inside the rig's 0..4 A range and the force varies.
    assert not any(
        "outside 0..4 A" in p or "nearly constant" in p for r in rows for p in r["problems"]
    )


@pytest.mark.realdata
def test_shared_data(
    quiroz_unfiltered_dir: Path, dyke_csv: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = _json(capsys, str(quiroz_unfiltered_dir))
    assert len(rows) == 30
    assert all(r["problems"] == [] for r in rows)
    assert {r["levels"][0] for r in rows} == {0.0, 0.25, 0.5, 0.75, 1.0}
    [guessed] = _json(capsys, str(dyke_csv))  # rounded time column: rate estimated, with a note
    assert (
        guessed["rate_hz"] == pytest.approx(3004.8) and "rate estimated" in guessed["problems"][0]
    )
    [row] = _json(capsys, str(dyke_csv), "--fs", "3004.8")
    assert row["samples"] == 64604 and row["input"] == "voltage" and row["levels"] is None
    assert row["F_n"] == pytest.approx([-1909.944, 1863.196])
    assert len(row["problems"]) == 1 and "time regenerated" in row["problems"][0]
