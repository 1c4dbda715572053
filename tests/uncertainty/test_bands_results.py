"""The coverage table of ``docs/results.md`` ("Prediction bands") is the stored benchmark data."""

from __future__ import annotations

import pytest

from tests.conftest import REPO_ROOT, load_benchmark

RESULTS = sorted((REPO_ROOT / "results").glob("bands*.csv"))


@pytest.mark.skipif(not RESULTS, reason="no results/bands*.csv stored")
def test_every_result_file_says_how_it_was_made() -> None:
    for path in RESULTS:
        head = [ln for ln in path.read_text().splitlines() if ln.startswith("#")]
        for key in (
            "# command: python benchmarks/bench_bands.py",
            "# commit: ",
            "# date: ",
            "# load average",
        ):
            assert any(ln.startswith(key) for ln in head), (path.name, key)


@pytest.mark.skipif(not RESULTS, reason="no results/bands*.csv stored")
def test_the_results_page_shows_the_table_of_the_stored_results() -> None:
    bench = load_benchmark("bench_bands")
    rows = bench.read_results(RESULTS)
    assert len(rows) > 0
    assert rows["coverage"].dropna().between(0.0, 1.0).all()
    page = (REPO_ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    assert bench.table(rows) in page
