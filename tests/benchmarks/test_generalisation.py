"""The generalisation benchmark's ``--quick`` variant runs end to end on the shared data and gives
one table with every scenario, test set and model kind."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrdamper.errors import DataValidationError
from tests.conftest import load_benchmark


@pytest.mark.realdata
@pytest.mark.slow
def test_quick_generalisation_table(shared_data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bench = load_benchmark("generalisation")
    # a classical peer and the black-box peer on every scenario; the benchmark runs every kind,
    # here the table's shape is checked (the LPV columns, which add minutes of fits, are measured
    # in docs/results.md)
    models = ["sp1", "narx"]
    tab = bench.main(["--quick", "--models", *models])
    out = capsys.readouterr().out
    assert "| scenario | test |" in out
    scenarios = {s for s, _ in tab.index}
    assert scenarios == {
        "(a) quiroz-freq",
        "(b) quiroz-cross",
        "(c) rig",
        "(d) dyke",
        "(e) labcontrol",
    }
    assert len(tab) == 8  # 2 + 2 + 2 + 1 + 1 test sets
    assert list(tab.columns[:-1]) == models
    for kind in models:
        assert np.all(np.isfinite(tab[kind].to_numpy(float))), tab[kind]
    # the best column names the column holding the row minimum
    for _, row in tab.iterrows():
        vals = row.drop("best").astype(float)
        assert row["best"] == vals.idxmin()


def test_select_column_compares_the_recommendation_with_the_best_kind() -> None:
    bench = load_benchmark("generalisation")
    rows = [
        {"scenario": "s", "test": t, "model": m, "esr": esr, "fit_s": 0.0, "error": ""}
        for t, vals in (("t1", (0.02, 0.04, 0.01)), ("t2", (0.03, 0.02, 0.01)))
        for m, esr in zip(("lpv", "sp1", "lpv-u"), vals, strict=True)
    ]
    tab = bench.table(rows, {"s": "sp1"})
    assert list(tab["select"]) == ["sp1", "sp1"]
    assert list(tab["select_esr"]) == [0.04, 0.02]
    # against the best registered kind (lpv-u is a variant select does not consider)
    assert list(tab["select/best"]) == pytest.approx([2.0, 1.0])
    assert "select" not in bench.table(rows).columns


def test_lpv_set_needs_key_value() -> None:
    bench = load_benchmark("generalisation")
    with pytest.raises(DataValidationError, match="KEY=VALUE"):
        bench.main(["--lpv-set", "n_m"])


@pytest.mark.realdata
def test_lpv_set_reaches_the_lpv_estimator(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bench = load_benchmark("generalisation")
    args = ["--quick", "--models", "lpv", "--scenarios", "quiroz-freq", "--lpv-set", "n_mm=2"]
    tab = bench.main(args)
    out = capsys.readouterr().out
    assert "Failures:" in out and "n_mm" in out  # the misspelt setting was given to the LPV fit
    assert tab["lpv"].isna().all()
