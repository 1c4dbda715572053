"""The documented closed-loop recipe, rerun at tenth length, against the figures the docs quote.

* ``results/closed_loop_tenth.csv`` (written by ``benchmarks/closed_loop_cli.py``, which runs the
  recipe of ``docs/control.md``) is the source of the fidelity table quoted there: the table in
  the page is rendered from the file;
* one slice of the recipe (the tenth-length DoE with its control extension, the default LPV fit,
  ``quartercar --plant rig`` on ISO D at 25 m/s, road seed 0) is rerun here and its rows agree
  with the stored ones to the file's six significant digits, the stroke flags included;
* ``select --for control`` on those records ranks the kinds in the order of their closed-loop
  errors against the true damper, computed here independently: each kind fitted on every record
  (``mrdamper fit KIND``) and run in the loop with the rig's damper.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import REPO_ROOT, load_benchmark

pytestmark = pytest.mark.slow

RESULT = REPO_ROOT / "results" / "closed_loop_tenth.csv"
DOC = REPO_ROOT / "docs" / "control.md"
KINDS = ("sp1", "sp2", "lpv")
#: The closed-loop check of the ranking test (short: the ranking only needs the order).
LOOP = {"roads": "B", "speeds": "10", "duration": "4"}
#: The commands run this checkout's package.
ENV = dict(os.environ, PYTHONPATH=str(REPO_ROOT / "src"), MPLBACKEND="Agg")


@pytest.fixture(scope="module")
def bench():  # type: ignore[no-untyped-def]
    return load_benchmark("closed_loop_cli")


@pytest.fixture(scope="module")
def recipe(tmp_path_factory: pytest.TempPathFactory, bench) -> tuple[Path, pd.DataFrame]:  # type: ignore[no-untyped-def]
    folder = tmp_path_factory.mktemp("recipe")
    table = bench.run_recipe(folder, 0.1, speeds=(25,), seeds=(0,), roads="D")
    return folder, table


def test_the_quoted_table_is_rendered_from_the_stored_result(bench) -> None:  # type: ignore[no-untyped-def]
    stored = bench.read_table(RESULT)
    assert set(stored["seed"]) == {0, 1, 2} and set(stored["speed_m_s"]) == {10, 25}
    assert set(stored["road"]) == {"B", "C", "D"}
    head = [ln for ln in RESULT.read_text().splitlines() if ln.startswith("# command:")]
    assert head and "benchmarks/closed_loop_cli.py --scale 0.1" in head[0]
    doc = " ".join(DOC.read_text(encoding="utf-8").split())  # a sentence may wrap
    assert bench.summary_markdown(stored) in DOC.read_text(encoding="utf-8")
    assert bench.coverage_sentence(stored) in doc
    assert bench.overall_sentence(stored) in doc
    table2 = bench.read_table(RESULT.with_name("closed_loop_tenth_table2.csv"))
    assert bench.overall_sentence(table2) in doc  # the same recipe on Table II alone
    readme = " ".join((REPO_ROOT / "README.md").read_text(encoding="utf-8").split())
    assert bench.headline_sentence(stored) in readme
    assert bench.coverage_sentence(stored) in readme


def test_the_recipe_reproduces_the_stored_rows(recipe, bench) -> None:  # type: ignore[no-untyped-def]
    _, table = recipe
    stored = bench.read_table(RESULT)
    stored = stored[(stored["speed_m_s"] == 25) & (stored["seed"] == 0) & (stored["road"] == "D")]
    key = ["controller", "metric"]
    both = table.merge(stored, on=key, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == len(stored) == 30
    for col in ("predicted", "achieved", "error_pct", "stroke_ratio"):
        np.testing.assert_allclose(
            both[col], both[f"{col}_stored"], rtol=1e-5, atol=1e-9, equal_nan=True, err_msg=col
        )
    assert (both["outside_stroke"] == both["outside_stroke_stored"]).all()


def _closed_loop_worst(model_file: Path) -> float:
    """Worst |error| [%] over the ranking's metrics and cells, with the rig's damper as plant."""
    from mrdamper.control.loop.fidelity import closed_loop_fidelity
    from mrdamper.models.registry import load_model

    res = closed_loop_fidelity(
        load_model(model_file),
        "rig",
        road_classes=[LOOP["roads"]],
        speeds=[float(LOOP["speeds"])],
        duration=float(LOOP["duration"]),
    )
    t = res.table()
    t = t[t["metric"] != "mean_current"]
    return float(t["error_pct"].abs().max())


def test_select_for_control_ranks_kinds_by_their_closed_loop_error(recipe) -> None:  # type: ignore[no-untyped-def]
    folder, _ = recipe
    doe = folder / "doe-ctrl"
    csv = folder / "control_rank.csv"
    args = [sys.executable, "-m", "mrdamper", "select", str(doe), "--for", "control"]
    args += [a for k in KINDS for a in ("-m", k)]
    args += ["--loop-roads", LOOP["roads"], "--loop-speeds", LOOP["speeds"]]
    args += ["--loop-duration", LOOP["duration"], "--csv", str(csv), "--no-progress"]
    proc = subprocess.run(args, capture_output=True, text=True, check=False, env=ENV)
    assert proc.returncode == 0, proc.stderr
    ranked = pd.read_csv(csv)
    assert ranked["error"].isna().all(), ranked["error"]  # no kind failed (empty cells)
    # every cell of this check lies within the stroke: the select's score covers all of them
    assert (ranked["cells_outside_stroke"] == 0).all()
    measured = {}
    for kind in KINDS:
        model = folder / "lpv.json" if kind == "lpv" else folder / f"{kind}.json"
        if kind != "lpv":
            fit = [sys.executable, "-m", "mrdamper", "fit", kind, str(doe), "--out", str(model)]
            subprocess.run(fit, capture_output=True, text=True, check=True, env=ENV)
        measured[kind] = _closed_loop_worst(model)
    order = sorted(KINDS, key=measured.__getitem__)
    assert list(ranked["model"]) == order, (ranked[["model", "closed_loop_worst_pct"]], measured)
    assert "recommended for control: " + order[0] in proc.stdout
