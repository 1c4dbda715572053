"""Summary statistics and the headline.

Checked against hand computations and the paper's own numbers.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mrdamper.study.tables import headline, improvement_pct, summarize


def test_improvement_reproduces_the_papers_percentages() -> None:
    # paper Section V: ESR LPV 0.036 vs SP-1 0.074 -> "51 %"; SSSE 14.98 vs 23.72 -> "36.8 %"
    assert improvement_pct(0.036, 0.074) == pytest.approx(51.35, abs=0.01)
    assert improvement_pct(14.98, 23.72) == pytest.approx(36.85, abs=0.01)
    assert np.isnan(improvement_pct(1.0, 0.0))


def _frame() -> pd.DataFrame:
    rows = []
    esr = {
        "lpv": [0.01, 0.02, 0.03, 0.1],
        "sp1": [0.05, 0.07, 0.09, 0.2],
        "lti": [0.5, 0.6, 0.7, 0.8],
    }
    for m, vals in esr.items():
        for k, e in enumerate(vals):
            rows.append(
                {
                    "fold": "all",
                    "model": m,
                    "kind": m,
                    "record": f"r{k}",
                    "status": "ok",
                    "esr": e,
                    "ssse": 100 * e,
                    "fit_time_s": 1.0,
                    "sim_time_s": 0.1,
                }
            )
    rows.append(
        {
            "fold": "all",
            "model": "p15",
            "kind": "p15",
            "record": "r0",
            "status": "diverged",
            "esr": np.nan,
            "ssse": np.nan,
            "fit_time_s": 2.0,
            "sim_time_s": np.nan,
        }
    )
    return pd.DataFrame(rows)


def test_summary_statistics_and_failures() -> None:
    s = summarize(_frame()).set_index("model")
    vals = np.array([0.05, 0.07, 0.09, 0.2])
    assert s.loc["sp1", "esr_mean"] == pytest.approx(vals.mean())
    assert s.loc["sp1", "esr_median"] == pytest.approx(np.median(vals))
    assert s.loc["sp1", "esr_q1"] == pytest.approx(np.quantile(vals, 0.25))
    assert s.loc["sp1", "esr_q3"] == pytest.approx(np.quantile(vals, 0.75))
    assert s.loc["lpv", "esr_gain_of_best_pct"] == 0.0
    assert s.loc["sp1", "esr_gain_of_best_pct"] == pytest.approx(100 * (0.1025 - 0.04) / 0.1025)
    assert (
        s.loc["p15", "n_ok"] == 0
        and s.loc["p15", "n_failed"] == 1
        and np.isnan(s.loc["p15", "esr_mean"])
    )


def test_headline_compares_with_best_classical_not_lti() -> None:
    h = headline(summarize(_frame()))
    assert h["available"] and h["best_classical_esr"] == "sp1"
    assert h["esr_improvement_pct"] == pytest.approx(100 * (0.1025 - 0.04) / 0.1025)
    assert "lower" in h["text"]
    assert not headline(summarize(_frame()[lambda d: d["model"] != "lpv"]))["available"]
