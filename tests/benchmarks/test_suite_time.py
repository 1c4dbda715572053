"""``benchmarks/suite_time.py`` reads pytest's summary line and keeps one row per scope."""

from __future__ import annotations

import json

import pytest

from tests.conftest import load_benchmark


@pytest.fixture(scope="module")
def suite():  # type: ignore[no-untyped-def]
    return load_benchmark("suite_time")


def test_the_summary_line_gives_counts_and_seconds(suite) -> None:  # type: ignore[no-untyped-def]
    log = "....\n=== 1635 passed, 1 skipped, 3 warnings in 631.12s (0:10:31) ===\n"
    counts, secs = suite.parse_summary(log)
    assert counts == {"passed": 1635, "skipped": 1, "warnings": 3}
    assert secs == 631.12
    counts, _ = suite.parse_summary("2 failed, 10 passed in 3.5s\n")
    assert counts["failed"] == 2


def test_a_log_without_a_summary_is_refused(suite) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match="no pytest summary line"):
        suite.parse_summary("collected 0 items\n")


def test_a_scope_replaces_only_its_own_row(suite, tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(suite, "RESULTS", tmp_path)
    log = tmp_path / "log.txt"
    for scope, text in (("full", "10 passed in 600.0s"), ("not slow", "8 passed in 60.0s")):
        log.write_text(text)
        assert suite.main(["--scope", scope, "--log", str(log), "--commit", "abc"]) == 0
    log.write_text("1 failed, 9 passed in 590.0s")
    assert suite.main(["--scope", "full", "--log", str(log), "--wall", "620"]) == 1
    rows = json.loads((tmp_path / "test-suite.json").read_text())["rows"]
    assert [r["scope"] for r in rows] == ["full", "not slow"]
    assert rows[0]["tests"] == 10 and rows[0]["failed"] == 1 and rows[0]["wall_s"] == 620.0
    assert rows[1]["tests"] == 8 and rows[1]["commit"] == "abc"
