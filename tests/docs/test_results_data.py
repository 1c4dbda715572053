"""The results pages agree with their data, and the cheap results still come out of the code.

* Every ``<!-- results:NAME -->`` block of the README and of the pages under ``docs/`` equals what
  ``benchmarks/render_results.py`` renders from ``results/`` (re-rendered in memory).
* Every result file carries its metadata (command, commit, date, load, what it measures).
* The cheap cells of the held-out table are recomputed: SP-1 and Bingham on the Quiroz fold that
  holds out 10 mm / 2 Hz and on Labcontrol, per test record, with the benchmark's own functions
  (relative tolerance :data:`RTOL`: the fits are deterministic; the tolerance leaves room for
  another BLAS's rounding only). The Quiroz fold of every other default kind is recomputed by
  ``tests/models/test_pinned_real_data.py``; here the stored table must agree with those pinned
  values (:data:`PINNED_RTOL`).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pandas as pd
import pytest

from tests.conftest import REPO_ROOT, SHARED_DATA, load_benchmark

#: Relative tolerance of a recomputed test ESR against the stored one.
RTOL = 1e-6
#: Relative tolerance of the stored Quiroz fold means against the pinned values (the fourth
#: significant digit, as the pinned test itself).
PINNED_RTOL = 5e-5
#: Most lines ``docs/results.md`` may have.
MAX_RESULTS_LINES = 400
#: Most lines of the README's results block.
MAX_README_LINES = 15
#: The question blocks ``docs/results.md`` must show.
QUESTIONS = ("held-out", "extrapolation", "closed-loop", "fit-time")


@pytest.fixture(scope="module")
def render() -> ModuleType:
    return load_benchmark("render_results")


@pytest.fixture(scope="module")
def results_mod() -> ModuleType:
    return load_benchmark("_results")


def test_every_page_agrees_with_its_data(render: ModuleType) -> None:
    stale = []
    for page in render.pages():
        text = page.read_text(encoding="utf-8")
        if render.blocks_in(text) and render.render_text(text) != text:
            stale.append(str(page.relative_to(REPO_ROOT)))
    assert not stale, (
        f"results blocks differ from results/ in {stale}: run python benchmarks/render_results.py"
    )


def test_the_results_pages_answer_the_questions(render: ModuleType) -> None:
    page = (REPO_ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    assert len(page.splitlines()) < MAX_RESULTS_LINES
    assert set(QUESTIONS) <= set(render.blocks_in(page))
    readme = (REPO_ROOT / "README.md").read_text(encoding="utf-8")
    assert "readme" in render.blocks_in(readme)
    block = readme.split("<!-- results:readme -->")[1].split("<!-- /results:readme -->")[0]
    assert len(block.strip().splitlines()) <= MAX_README_LINES
    for name in render.FIGURES:
        assert f"figures/results/{name}" in page
        assert (render.FIGURES_DIR / name).is_file(), f"{name}: run benchmarks/render_results.py"


def test_every_result_names_its_origin(results_mod: ModuleType) -> None:
    names = results_mod.result_names()
    assert names
    for name in names:
        doc = results_mod.read_result(name)
        assert doc["name"] == name
        assert doc["rows"], name
        assert doc["command"].split()[0] in ("python", "for", "OPENBLAS_NUM_THREADS=1"), name
        assert doc["commit"] and doc["date"], name
        assert doc["carried_over"] or doc["load_avg"] is not None, name


def test_a_changed_number_shows(render: ModuleType, tmp_path: Path) -> None:
    """The page check can fail: one stored number changed, the rendered page changes."""
    folder = tmp_path / "results"
    shutil.copytree(REPO_ROOT / "results", folder)
    page = (REPO_ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    assert render.render_text(page, folder) == render.render_text(page)
    loop = folder / "closed_loop_tenth.csv"
    lines = loop.read_text(encoding="utf-8").splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    table = pd.read_csv(loop, comment="#")
    first = table.index[(table["metric"] == "a_w") & ~table["outside_stroke"]][0]
    table.loc[first, "error_pct"] = 123.4
    loop.write_text("\n".join(head) + "\n" + table.to_csv(index=False), encoding="utf-8")
    changed = render.render_text(page, folder)
    assert changed != page and "123.4" in changed
    with pytest.raises(KeyError, match="no renderer"):
        render.render_text("<!-- results:nope -->\n<!-- /results:nope -->")


def test_write_result_is_complete_and_atomic(results_mod: ModuleType, tmp_path: Path) -> None:
    path = results_mod.write_result(
        "t-1",
        [{"a": 1.0, "b": float("nan")}, {"a": np.float64(2.5), "c": "x"}],
        command="python benchmarks/x.py",
        measures="a test",
        folder=tmp_path,
    )
    doc = results_mod.read_result("t-1", tmp_path)
    assert doc["columns"] == ["a", "b", "c"]
    assert doc["rows"][0]["b"] is None and doc["rows"][1]["a"] == 2.5
    assert len(doc["load_avg"]) == 3 and not doc["carried_over"]
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left
    with pytest.raises(ValueError, match="name"):
        results_mod.write_result("Bad Name", [], command="c", measures="m", folder=tmp_path)


def _stored(proto: str, model: str, fold: str | None = None) -> dict[str, float]:
    """Stored test ESR per record of ``results/real-data*.json``."""
    rows = [
        r
        for path in sorted((REPO_ROOT / "results").glob("real-data*.json"))
        for r in json.loads(path.read_text(encoding="utf-8"))["rows"]
    ]
    return {
        r["record"]: r["esr"]
        for r in rows
        if r["protocol"] == proto and r["model"] == model and (fold is None or r["fold"] == fold)
    }


def _check(rows: list[dict[str, Any]], stored: dict[str, float]) -> None:
    got = {r["record"]: r["esr"] for r in rows}
    assert set(got) == set(stored)
    for rec, esr in got.items():
        assert esr == pytest.approx(stored[rec], rel=RTOL), rec


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA} (set MRDAMPER_SHARED_DATA)")
    return load_benchmark("accuracy_real_data")


#: SP-1's fits take over 4 s on the loaded 2-core machine (slow); Bingham's are sub-second.
KINDS = [pytest.param("sp1", marks=pytest.mark.slow), "bingham"]


@pytest.mark.parametrize("kind", KINDS)
def test_quiroz_fold_recomputes(bench: ModuleType, kind: str) -> None:
    from mrdamper.data.readers import read_directory

    data = read_directory(SHARED_DATA / "quiroz2022_utfsm" / "sine_unfiltered")
    fold = "10mm_2Hz"
    train, test = next((tr, te) for c, tr, te in data.leave_one_group_out("condition") if c == fold)
    rows = bench.fit_and_score(kind, bench.settings_for(kind, "quiroz"), train, test)
    _check(rows, _stored("quiroz", kind, fold))


@pytest.mark.parametrize("kind", KINDS)
def test_labcontrol_recomputes(bench: ModuleType, kind: str) -> None:
    rows = bench.labcontrol([kind]).to_dict(orient="records")
    _check(rows, _stored("labcontrol", kind))


def test_stored_quiroz_fold_agrees_with_the_pinned_values() -> None:
    from tests.models import test_pinned_real_data as pinned

    for kind, value in pinned.QUIROZ.items():
        stored = _stored("quiroz", kind, pinned.FOLD)
        assert stored, f"{kind}: not in results/real-data*.json"
        mean = float(np.mean(list(stored.values())))
        assert mean == pytest.approx(value, rel=PINNED_RTOL), kind
