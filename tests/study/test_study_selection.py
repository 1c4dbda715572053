"""The study report carries the model-selection table of ``mrdamper select``, computed from the
study's own held-out scores with the rule of ``cross_validate``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mrdamper.study import ModelSpec, Protocol, Selection, doe_protocol, run_study
from mrdamper.study.report import render_report
from mrdamper.study.selection import SCORE_COLUMNS, selection_from_scores

MODELS = [ModelSpec("toy"), ModelSpec("toy", {"noise": 0.5}, label="noisy"), ModelSpec("toyfail")]


@pytest.fixture(scope="module")
def result(doe):  # type: ignore[no-untyped-def]
    return run_study(doe, doe_protocol(), MODELS, workers=1, progress=False)


def test_table_is_the_held_out_scores_by_the_select_rule(result) -> None:  # type: ignore[no-untyped-def]
    sel = result.selection
    assert sel is not None and sel.split == "fixed" and sel.n_folds == 1
    r = result.results
    for label in ("toy", "noisy"):
        esr = r.loc[r["model"] == label, "esr"]
        assert sel.table.loc[label, "mean_esr"] == pytest.approx(float(esr.mean()), rel=1e-12)
        assert sel.table.loc[label, "worst_esr"] == pytest.approx(float(esr.max()), rel=1e-12)
    assert np.isnan(sel.table.loc["toyfail", "mean_esr"])
    assert sel.table.loc["toyfail", "folds_failed"] == 1
    # the true structure without noise wins, and the reason says why
    best = min(("toy", "noisy"), key=lambda k: sel.table.loc[k, "mean_esr"])
    assert sel.recommended == best
    assert "lowest mean free-run ESR" in sel.reason and "toyfail" in sel.reason


def test_scores_of_training_records_are_not_held_out(doe) -> None:  # type: ignore[no-untyped-def]
    proto = Protocol(
        train=Selection(match={"experiment": 1}), score=Selection(), exclude_trained=False
    )
    res = run_study(doe, proto, [ModelSpec("toy")], workers=1, progress=False)
    assert res.selection is not None
    trained = set(res.roles.loc[res.roles["role"] == "train", "record"])
    assert trained and trained <= set(res.results["record"])  # scored, but not held out
    assert set(res.selection.scores["record"]).isdisjoint(trained)
    held = res.results[~res.results["record"].isin(trained)]
    mean = float(held["esr"].mean())
    assert res.selection.table.loc["toy", "mean_esr"] == pytest.approx(mean, rel=1e-12)


def test_report_shows_the_table_and_recommendation(result) -> None:  # type: ignore[no-untyped-def]
    html = render_report(result, result.summary, {})
    assert "Which model for this damper?" in html
    assert f"Recommended: {result.selection.recommended}." in html
    assert "held-out scores" in html and "not by fitting again" in html


def test_selection_from_scores_refuses_a_table_without_its_columns() -> None:
    from mrdamper.errors import DataValidationError

    with pytest.raises(DataValidationError, match="scores"):
        selection_from_scores(pd.DataFrame({"model": []}), ["a"], {}, "record", 2)
    empty = pd.DataFrame(columns=list(SCORE_COLUMNS))
    sel = selection_from_scores(empty, ["a"], {}, "record", 2)
    assert sel.recommended is None and "no model kind" in sel.reason
