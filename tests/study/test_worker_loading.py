"""Records given as files are read by the workers that use them, with the same results.

``study_records(..., load="worker")`` gives sources (headers only in this process) and
``load="parent"`` reads every record first; both must give byte-identical tables with every
executor. The memory effect is measured in ``benchmarks/bench_study_memory.py``, not here.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mrdamper.data import ExperimentSet, RecordSource, SourceSet, write_parquet
from mrdamper.data.writers import write_csv
from mrdamper.errors import DataValidationError
from mrdamper.study import ModelSpec, doe_protocol, run_study, study_records
from mrdamper.study.executor import SerialExecutor, resolve_record
from mrdamper.study.tables import TIMING_COLUMNS

MODELS = [ModelSpec("toy", {"noise": 0.5}), ModelSpec("toyfail")]


@pytest.fixture(scope="module")
def doe_folder(tmp_path_factory: pytest.TempPathFactory, doe: ExperimentSet) -> Path:
    folder = tmp_path_factory.mktemp("records")
    for e in doe:
        write_parquet(e, folder / f"{e.name}.parquet")
    return folder


def _tables(res) -> list[str]:  # type: ignore[no-untyped-def]
    strip = [c for c in res.results.columns if c not in TIMING_COLUMNS]
    fits = res.fits.drop(columns=[c for c in TIMING_COLUMNS if c in res.fits.columns])
    return [
        res.results[strip].to_csv(index=False),
        fits.to_csv(index=False),
        res.roles.to_csv(index=False),
    ]


@pytest.mark.parametrize("workers", [1, 2])
def test_worker_and_parent_loading_give_identical_tables(doe_folder: Path, workers: int) -> None:
    lazy = study_records(doe_folder, load="worker")
    eager = study_records(doe_folder, load="parent")
    assert isinstance(lazy, SourceSet) and isinstance(eager, ExperimentSet)
    assert lazy.names == eager.names
    kw = {"workers": workers, "seed": 2, "progress": False}
    a = run_study(lazy, doe_protocol(), MODELS, **kw)
    b = run_study(eager, doe_protocol(), MODELS, **kw)
    assert _tables(a) == _tables(b)
    assert a.showcase is not None and b.showcase is not None
    assert a.showcase.record.name == b.showcase.record.name
    assert [an.error for an in a.analyses.values()] == [an.error for an in b.analyses.values()]


def test_time_split_of_one_source_matches_the_record(tmp_path: Path, doe: ExperimentSet) -> None:
    e = doe["exp1_rep01"]
    write_csv(e, tmp_path / "one.csv")
    lazy = study_records(tmp_path / "one.csv", load="worker")
    eager = study_records(tmp_path / "one.csv", load="parent")
    kw = {"workers": 1, "progress": False}
    a = run_study(lazy, _default(lazy), [ModelSpec("toy")], **kw)
    b = run_study(eager, _default(eager), [ModelSpec("toy")], **kw)
    assert _tables(a) == _tables(b)
    assert set(a.roles["record"]) == {"one[:70%]", "one[70%:]"}


def _default(records):  # type: ignore[no-untyped-def]
    from mrdamper.study import default_protocol

    return default_protocol(records)[0]


def test_sources_are_passed_to_tasks_and_read_there(doe_folder: Path) -> None:
    src = study_records(doe_folder, load="worker")[0]
    assert isinstance(src, RecordSource)
    assert SerialExecutor().share(src) is src  # no copy of the samples in this process
    e = resolve_record(src)
    assert e.name == src.name and e.n == src.n and e.duration == src.duration


def test_a_file_changed_after_planning_is_refused(tmp_path: Path, doe: ExperimentSet) -> None:
    write_csv(doe["exp1_rep01"], tmp_path / "r.csv")
    src = study_records(tmp_path / "r.csv", load="worker")[0]
    write_csv(doe["exp6_rep01"], tmp_path / "r.csv", force=True)  # another length
    with pytest.raises(DataValidationError, match="when the study was planned"):
        src.load()


def test_unknown_load_mode_is_refused(doe_folder: Path) -> None:
    with pytest.raises(DataValidationError, match="load"):
        study_records(doe_folder, load="later")  # type: ignore[arg-type]


def _cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    from mrdamper.cli.main import main

    try:
        main(args)
        code = 0
    except SystemExit as exc:
        code = int(exc.code or 0)
    return code, capsys.readouterr().err


@pytest.mark.slow
def test_cli_load_option(
    doe_folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    common = ["study", str(doe_folder), "--models", "bingham", "--workers", "1", "--no-progress"]
    outs = {}
    for mode in ("worker", "parent"):
        out = tmp_path / mode
        code, err = _cli([*common, "--out", str(out), "--load", mode], capsys)
        assert code == 0, err
        outs[mode] = (out / "results.csv").read_bytes()
    assert outs["worker"] == outs["parent"]
    code, err = _cli([*common, "--out", str(tmp_path / "x"), "--load", "later"], capsys)
    assert code == 2 and "load" in err and "later" in err
    assert not (tmp_path / "x").exists()
