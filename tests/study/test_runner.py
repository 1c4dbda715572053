"""The study runner and its outputs, on test-double models (fast, deterministic)."""

from __future__ import annotations

import io
import re
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest

from mrdamper.errors import OutputError, OutputExistsError, SchemaError
from mrdamper.models import load_model
from mrdamper.study import ModelSpec, doe_protocol, run_study, write_study
from mrdamper.study.tables import TIMING_COLUMNS

MODELS = ["toy", "toyfail", "toydiverge"]


@pytest.fixture(scope="module")
def result(doe):
    return run_study(doe, doe_protocol(), MODELS, workers=1, progress=False)


@pytest.fixture(scope="module")
def written(result, tmp_path_factory):
    """The study folder of ``result`` (figures and report), written once for the tests that only
    read it."""
    return write_study(result, tmp_path_factory.mktemp("study") / "out")


def test_failed_models_stay_as_rows_with_their_error(result, doe) -> None:
    r = result.results
    n_scored = len(doe) - 6
    assert len(r) == 3 * n_scored
    assert (r.loc[r["model"] == "toy", "status"] == "ok").all()
    fail = r[r["model"] == "toyfail"]
    assert (fail["status"] == "fit-failed").all() and fail["esr"].isna().all()
    assert (
        fail["error"]
        .str.contains("IdentificationError: toyfail: regression matrix is singular")
        .all()
    )
    div = r[r["model"] == "toydiverge"]
    assert (div["status"] == "diverged").all()
    assert div["error"].str.contains("diverged at sample 7").all()
    s = result.summary.set_index("model")
    assert s.loc["toyfail", "n_failed"] == n_scored and s.loc["toy", "n_ok"] == n_scored
    # the toy model is the true structure of the synthetic data: near-perfect scores
    assert s.loc["toy", "esr_mean"] < 1e-3


def test_scores_are_the_metrics_of_the_saved_model(result, doe) -> None:
    from mrdamper.metrics import score_arrays

    model = result.models[("all", "toy")]
    row = result.results.query("model == 'toy' and record == 'exp2_rep03'").iloc[0]
    s = score_arrays(doe["exp2_rep03"].F, model.predict(doe["exp2_rep03"]))
    assert row["esr"] == s.esr and row["ssse"] == s.ssse


def test_same_seed_gives_same_results_across_executors(doe) -> None:
    models = [ModelSpec("toy", {"noise": 0.5})]  # the seed changes the fitted parameters
    a = run_study(doe, doe_protocol(), models, workers=1, seed=3, progress=False).results
    b = run_study(doe, doe_protocol(), models, workers=2, seed=3, progress=False).results
    c = run_study(doe, doe_protocol(), models, workers=1, seed=4, progress=False).results
    strip = [col for col in a.columns if col not in TIMING_COLUMNS]
    pd.testing.assert_frame_equal(a[strip], b[strip])
    assert a[strip].to_csv(index=False) == b[strip].to_csv(index=False)
    assert not np.array_equal(a["esr"].to_numpy(), c["esr"].to_numpy())


def test_dask_local_cluster_gives_the_same_results(doe) -> None:
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cl,
        distributed.Client(cl) as client,
    ):
        d = run_study(doe, doe_protocol(), MODELS, scheduler=client, progress=False)
    s = run_study(doe, doe_protocol(), MODELS, workers=1, progress=False)
    strip = [col for col in s.results.columns if col not in TIMING_COLUMNS]
    pd.testing.assert_frame_equal(d.results[strip], s.results[strip])
    assert d.info["executor"].startswith("Dask scheduler")


def test_unknown_model_or_setting_is_refused_before_running(doe) -> None:
    with pytest.raises(SchemaError, match="unknown kind 'nope'"):
        run_study(doe, doe_protocol(), ["nope"], workers=1, progress=False)
    with pytest.raises(
        SchemaError, match=r"models.toy.settings: .*does not take the setting 'order'"
    ):
        run_study(doe, doe_protocol(), [ModelSpec("toy", {"order": 3})], workers=1, progress=False)


@pytest.mark.slow
def test_write_outputs_and_report(result, written) -> None:
    out = written
    names = {p.name for p in out.iterdir()}
    assert {
        "results.csv",
        "summary.csv",
        "fits.csv",
        "roles.csv",
        "protocol.json",
        "study.json",
        "report.html",
        "models",
        "figures",
    } <= names
    res = pd.read_csv(out / "results.csv")
    kept = [c for c in result.results.columns if c not in TIMING_COLUMNS]
    assert len(res) == len(result.results) and list(res.columns) == kept
    assert list(pd.read_csv(out / "timings.csv").columns) == [
        "fold",
        "model",
        "record",
        *TIMING_COLUMNS,
    ]
    summ = pd.read_csv(out / "summary.csv")
    assert list(summ["model"]) == MODELS
    import json

    assert [m["kind"] for m in json.loads((out / "protocol.json").read_text())["models"]] == MODELS
    m = load_model(out / "models" / "all" / "toy.json")
    e = result.showcase.record
    assert np.array_equal(m.predict(e), result.models[("all", "toy")].predict(e))
    assert not (out / "models" / "all" / "toyfail.json").exists()
    html = (out / "report.html").read_text()
    drawn = sorted(p.stem for p in (out / "figures").glob("*.png"))
    assert sorted(p.stem for p in (out / "figures").glob("*.svg")) == drawn
    assert len(drawn) >= 7  # F-v map, zones, laws, 2 box plots, force-time, F-v models
    assert html.count('<img src="data:image/png;base64,') == len(drawn)
    for name in drawn:
        assert f'id="{name}"' in html
    # figures not drawn (no LTI, no LPV model here) say why
    assert "Not drawn: no LTI model in this study" in html
    assert "Not drawn: no LPV model in this study" in html
    assert "Train/score overlap:</b> none" in html
    assert not re.search(r"<(script|link)\b", html)  # self-contained, nothing fetched


def test_write_refuses_non_empty_folder_and_force_replaces(result, tmp_path) -> None:
    out = tmp_path / "o"
    write_study(result, out, figures=False)
    with pytest.raises(OutputExistsError, match="not empty; pass --force"):
        write_study(result, out, figures=False)
    write_study(result, out, force=True, figures=False)
    assert (out / "report.html").exists()
    (out / "results.csv").write_text("edited")  # an edited file is the user's: never replaced
    with pytest.raises(OutputError, match=r"changed since \(results.csv\)"):
        write_study(result, out, force=True, figures=False)
    assert (out / "results.csv").read_text() == "edited"
    mine = tmp_path / "mine"  # a folder mrdamper did not write is never replaced
    mine.mkdir()
    (mine / "keep.txt").write_text("x")
    with pytest.raises(OutputError, match="mrdamper did not write"):
        write_study(result, mine, force=True, figures=False)
    assert (mine / "keep.txt").read_text() == "x"
    empty = tmp_path / "empty"
    empty.mkdir()
    write_study(result, empty, figures=False)
    assert (empty / "results.csv").exists()


def test_interrupted_write_leaves_nothing_that_looks_complete(
    result, tmp_path, monkeypatch
) -> None:
    from mrdamper.study import report

    def boom(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "render_report", boom)
    with pytest.raises(KeyboardInterrupt):
        write_study(result, tmp_path / "out", figures=False)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_report_renders_in_a_headless_browser(written, tmp_path) -> None:
    browser = next(
        (
            shutil.which(b)
            for b in ("chromium", "chromium-browser", "google-chrome")
            if shutil.which(b)
        ),
        None,
    )
    if browser is None:
        pytest.skip("no headless browser (chromium) installed to render report.html")
    out = written
    shot = tmp_path / "shot.png"
    subprocess.run(
        [
            browser,
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            f"--screenshot={shot}",
            "--window-size=1200,2000",
            (out / "report.html").as_uri(),
        ],
        check=True,
        timeout=120,
        capture_output=True,
    )
    import matplotlib.image as mpimg

    img = mpimg.imread(io.BytesIO(shot.read_bytes()), format="png")
    assert img.size > 0 and float(np.std(img)) > 0.01  # not a blank page


def test_interrupt_during_the_run_stops_workers_and_cleans_up(doe, monkeypatch) -> None:
    import mrdamper.study.executor as ex

    made = []
    real = ex.ProcessExecutor.__init__

    def spy(self, workers):
        real(self, workers)
        made.append(self)

    def interrupted(self, pending):
        raise KeyboardInterrupt

    monkeypatch.setattr(ex.ProcessExecutor, "__init__", spy)
    monkeypatch.setattr(ex.ProcessExecutor, "wait_first", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_study(doe, doe_protocol(), MODELS, workers=2, progress=False)
    (executor,) = made
    assert not executor._dir.exists()
