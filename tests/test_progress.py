"""Progress reports (:mod:`mrdamper.progress`): the reporter itself, the stages every model kind
reports while it fits (counts within their totals, never going back), fits that give the same
model with and without a listener, one report per file read, the cross-validation's stages, and
the command line's live line (only on a terminal)."""

from __future__ import annotations

import io
import json
import re
import sys
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from mrdamper import Experiment, get_estimator, progress, write_csv
from tests.conftest import package_kinds
from tests.models.test_single_level import _sine  # three short sines through the rig damper

KINDS = package_kinds()
FAST = {"spencer": {"n_starts": 2, "screen_nfev": 5, "max_nfev": 20}}
TEMPLATE = ["preparing the training data", "identifying", "done"]
#: Stages of each family's own steps (exact names; the SP maps' first start is "start 1 of N").
FAMILY = {
    "lpv": ["hysteretic input: candidate", "zone laws", "output-error refinement: iteration"],
    "lti": ["hysteretic input: candidate", "least squares", "output-error refinement: iteration"],
    "p15": ["equation-error start", "multiple shooting: evaluation"],
    "sp1": ["best start on the fit samples: evaluation"],
    "sp2": ["best start on the fit samples: evaluation"],
    "sp3": ["best start on the fit samples: evaluation"],
    "sp4": ["best start on the fit samples: evaluation"],
    "spencer": ["start 1 of 2: least squares: evaluation", "best start: least squares: evaluation"],
    "bingham": ["least squares: record"],
    "narx": ["term selection: record", "output-error refinement: evaluation"],
    "tanh": ["step-size check"],
    "boucwen": ["step-size check"],
    "dahl": ["step-size check"],
    "lugre": ["step-size check"],
}

Event = tuple[str, "int | None", "int | None"]


@pytest.fixture(scope="module")
def records() -> list[Experiment]:
    """Three short sines at three current levels [A] (a few seconds of data in all)."""
    return [_sine(0.01, 1.0, 0.2, "a"), _sine(0.005, 3.0, 0.5, "bb"), _sine(0.002, 5.0, 0.8, "ccc")]


def _check_counts(events: list[Event]) -> None:
    """Counts are within their totals and never go back within a stage."""
    last: dict[str, int] = {}
    totals: dict[str, int | None] = {}
    for stage, done, total in events:
        if done is None:
            assert total is None, (stage, done, total)
            continue
        assert done >= 0, (stage, done)
        if total is not None:
            assert done <= total, (stage, done, total)
        assert done >= last.get(stage, 0), f"{stage}: {done} after {last[stage]}"
        assert totals.setdefault(stage, total) == total, (stage, total)
        last[stage] = done


def _fit(kind: str, records: list[Experiment], listen: bool) -> tuple[dict, list[Event]]:
    events: list[Event] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = get_estimator(kind, **FAST.get(kind, {}))
        if listen:
            with progress.listening(lambda s, d, t: events.append((s, d, t))):
                model = est.fit(records)
        else:
            model = est.fit(records)
    return model.to_dict(), events


# ----------------------------------------------------------------------------- the reporter
def test_report_without_listener_does_nothing() -> None:
    progress.report("nobody listens", 1, 2)  # no error, no effect
    f = lambda x: x + 1  # noqa: E731
    assert progress.counted(f, "calls", 3) is f  # nothing to count: the function itself


def test_listening_sections_and_counted() -> None:
    events: list[Event] = []
    with progress.listening(lambda s, d, t: events.append((s, d, t))):
        progress.report("a")
        with progress.section("outer"), progress.section("inner"):
            progress.report("b", 1, 2)
        f = progress.counted(lambda x: 2 * x, "calls", 5)
        assert [f(1), f(2)] == [2, 4]
    progress.report("after")  # the listener is gone
    assert events == [
        ("a", None, None),
        ("outer: inner: b", 1, 2),
        ("calls", 1, 5),
        ("calls", 2, 5),
    ]


def test_listener_is_restored_after_an_error() -> None:
    events: list[Event] = []
    with progress.listening(lambda s, d, t: events.append((s, d, t))):
        with pytest.raises(ValueError), progress.listening(lambda s, d, t: None):
            raise ValueError
        progress.report("back")
    assert events == [("back", None, None)]


# ----------------------------------------------------------------------------- fits
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.slow
def test_fit_reports_stages_and_gives_the_same_model(kind: str, records: list[Experiment]) -> None:
    quiet, none = _fit(kind, records, listen=False)
    assert none == []
    heard, events = _fit(kind, records, listen=True)
    # progress never changes a result: same parameters and provenance, to the bit
    assert json.dumps(heard, sort_keys=True) == json.dumps(quiet, sort_keys=True)
    stages = [s for s, _, _ in events]
    for stage in TEMPLATE + FAMILY[kind]:
        assert stage in stages, f"{kind}: no {stage!r} in {sorted(set(stages))}"
    assert stages.index("preparing the training data") < stages.index("identifying")
    assert events[-1] == ("done", None, None)
    _check_counts(events)
    # the four standard hysteresis models count their evaluations without a total (a
    # finite-difference Jacobian calls the residuals a number of times not known ahead)
    no_total = kind in ("tanh", "boucwen", "dahl", "lugre")
    counted = [(d, t) for _, d, t in events if d is not None and (t is not None or no_total)]
    assert counted, f"{kind}: no stage counts its steps"
    if kind.startswith("sp"):
        assert any(re.fullmatch(r"start 1 of \d+: least squares: evaluation", s) for s in stages)
    if kind in ("lpv", "lti"):  # the candidate fits report inside their own section
        n = {s: t for s, _, t in events}["hysteretic input: candidate"]
        assert n is not None and n > 1
        assert ("hysteretic input: candidate", n, n) in events
        assert f"hysteretic candidate {n} of {n}: done" in stages
    if kind == "bingham":
        assert ("least squares: record", 3, 3) in events


@pytest.mark.slow
def test_lpv_least_squares_solver_counts_evaluations(records: list[Experiment]) -> None:
    events: list[Event] = []
    est = get_estimator("lpv", oe_solver="least_squares", stroke=0.01, blend=0.5, max_nfev=5)
    with warnings.catch_warnings(), progress.listening(lambda s, d, t: events.append((s, d, t))):
        warnings.simplefilter("ignore")
        est.fit(records)
    evals = [(d, t) for s, d, t in events if s == "output-error refinement: evaluation"]
    assert evals and evals[0] == (1, 6)  # scipy's "lm" may evaluate the start once more
    _check_counts(events)


# ----------------------------------------------------------------------------- reading, selection
def test_read_records_reports_each_file(tmp_path: Path, records: list[Experiment]) -> None:
    from mrdamper.data.readers import read_records

    for e in records:
        write_csv(e, tmp_path / f"{e.name}.csv")
    events: list[Event] = []
    with progress.listening(lambda s, d, t: events.append((s, d, t))):
        got = read_records(tmp_path)
    assert len(got) == 3
    assert events == [("reading records", k, 3) for k in range(3)]


def test_cross_validate_reports_folds_and_kinds(records: list[Experiment]) -> None:
    from mrdamper.study.selection import cross_validate

    events: list[Event] = []
    done: list[Event] = []
    with (
        warnings.catch_warnings(),
        progress.listening(
            lambda s, d, t: events.append((s, d, t)),
            finished=lambda s, d, t: done.append((s, d, t)),
        ),
    ):
        warnings.simplefilter("ignore")
        res = cross_validate(
            records,
            models=["bingham", "sp1"],
            folds="record",
            settings={"bingham": {"degree": 1}},
            beyond=False,  # the in-envelope folds only: their count is checked below
            stress=False,
            workers=1,  # in this process: each fit's own stages are heard
            halving=None,
        )
    n = 2 * res.n_folds
    fits = [(d, t) for s, d, t in events if s == "cross-validation: fits"]
    assert fits == [(k, n) for k in range(n + 1)] + [(n, n)]
    stages = [s for s, _, _ in events]
    assert any(re.fullmatch(r"bingham, fold .+ \(\d of \d+\): identifying", s) for s in stages)
    assert any(re.fullmatch(r"bingham, fold .+ \(\d of \d+\): done", s) for s in stages)
    assert any(re.fullmatch(r"bingham, fold .+: scoring the left-out data", s) for s in stages)
    # sp1 cannot be fitted at two current levels: its stages up to the failure are reported
    assert any(re.fullmatch(r"sp1, fold .+ \(\d of \d+\): identifying", s) for s in stages)
    _check_counts(events)
    # one finished step per kind, counted, each saying what came of it
    assert [(d, t) for _, d, t in done] == [(1, 2), (2, 2)]
    lines = dict(s.split(": ", 1) for s, _, _ in done)
    assert set(lines) == {"bingham", "sp1"}
    assert re.fullmatch(r"3 folds, mean ESR inside [0-9.e-]+; at \d+ s", lines["bingham"])
    assert re.fullmatch(r"3 folds, 3 left-out record\(s\) failed; at \d+ s", lines["sp1"])


def test_time_left() -> None:
    from mrdamper.cli._status import time_left

    assert time_left(10.0, 0, 4) == "" and time_left(10.0, 2, None) == ""
    assert time_left(10.0, 4, 4) == ""
    assert time_left(10.0, 1, 4) == "about 30 s left"
    assert time_left(100.0, 1, 3) == "about 3 min left"


# ----------------------------------------------------------------------------- command line
def _data_dir(tmp_path: Path, records: list[Experiment]) -> Path:
    d = tmp_path / "data"
    d.mkdir()
    for e in records:
        write_csv(e, d / f"{e.name}.csv")
    return d


_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


@pytest.fixture()
def terminal(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[], str]]:
    """The live line drawn on a forced terminal console; yields a function giving its text."""
    from rich.console import Console

    from mrdamper.cli import _status

    monkeypatch.setenv("TERM", "xterm-256color")
    buf = io.StringIO()
    monkeypatch.setattr(
        _status,
        "_terminal_console",
        lambda: Console(file=buf, force_terminal=True, force_interactive=True, width=200),
    )
    yield lambda: _ANSI.sub("", buf.getvalue()).replace("\r", "\n")


def test_fit_cli_prints_plain_lines_off_a_terminal(
    tmp_path: Path, records: list[Experiment], capsys: pytest.CaptureFixture[str]
) -> None:
    from mrdamper.cli.main import main

    data = _data_dir(tmp_path, records)
    main(["fit", "bingham", str(data), "--out", str(tmp_path / "m.json")])
    out, err = capsys.readouterr()
    assert out == f"bingham: identified on 3 record(s); wrote {tmp_path / 'm.json'}\n"
    n = sum(e.n for e in records)
    assert "\r" not in err and "\x1b" not in err
    assert re.fullmatch(
        rf"fitting bingham on 3 record\(s\), {n} samples: done in \d+\.\d s\n", err
    ), err
    main(
        ["fit", "bingham", str(data), "--out", str(tmp_path / "m.json"), "--force", "--no-progress"]
    )
    assert capsys.readouterr().err == ""


def test_select_cli_prints_a_line_per_kind_off_a_terminal(
    tmp_path: Path, records: list[Experiment], capsys: pytest.CaptureFixture[str]
) -> None:
    from mrdamper.cli.main import main

    data = _data_dir(tmp_path, records)
    main(["select", str(data), "-m", "bingham", "-m", "tanh", "--inside-only", "--workers", "2"])
    err = capsys.readouterr().err
    assert "\r" not in err and "\x1b" not in err
    lines = [x for x in err.splitlines() if not x.startswith("note: ")]  # select's notes
    found = [re.fullmatch(r"cross-validating: (\w+): .+ \(([12]) of 2\)", x) for x in lines[:2]]
    assert sorted(m[1] for m in found if m) == ["bingham", "tanh"], err
    assert [m[2] for m in found if m] == ["1", "2"]
    assert re.fullmatch(r"cross-validating: done in \d+\.\d s", lines[2]) and len(lines) == 3


def test_finished_steps_on_a_terminal(terminal: Callable[[], str]) -> None:
    from mrdamper.cli._status import working

    with working("busy"):
        progress.report("stage", 1, 4)
        progress.finished("first part", 1, 4)
    shown = terminal()
    assert re.search(r"^busy: first part \(1 of 4\)$", shown, re.MULTILINE), shown
    assert re.search(r"busy: stage 1/4 .*about \d+ s left", shown), shown
    assert re.search(r"^busy: done in \d+\.\d s$", shown, re.MULTILINE), shown


@pytest.mark.slow
def test_fit_cli_shows_stages_and_time_on_a_terminal(
    tmp_path: Path,
    records: list[Experiment],
    capsys: pytest.CaptureFixture[str],
    terminal: Callable[[], str],
) -> None:
    from mrdamper.cli.main import main

    data = _data_dir(tmp_path, records)
    main(["fit", "sp1", str(data), "--out", str(tmp_path / "m.json"), "--n-starts", "2"])
    assert capsys.readouterr().out.startswith("sp1: identified on 3 record(s)")
    shown = terminal()
    assert "fitting sp1: reading records 0/3" in shown
    n = sum(e.n for e in records)
    message = f"fitting sp1 on 3 record(s), {n} samples"
    assert f"{message}: identifying" in shown
    assert re.search(
        rf"{re.escape(message)}: start 1 of 2: least squares: evaluation \d+/200", shown
    )
    assert re.search(rf"^{re.escape(message)}: done in \d+\.\d s$", shown, re.MULTILINE), shown


def test_no_progress_and_score_on_a_terminal(
    tmp_path: Path,
    records: list[Experiment],
    capsys: pytest.CaptureFixture[str],
    terminal: Callable[[], str],
) -> None:
    from mrdamper.cli.main import main

    data = _data_dir(tmp_path, records)
    model = tmp_path / "m.json"
    main(["fit", "bingham", str(data), "--out", str(model), "--no-progress"])
    assert terminal() == ""
    capsys.readouterr()
    main(["score", str(model), str(data), "--json"])
    assert json.loads(capsys.readouterr().out)["mean"]["n_scored"] == 3
    shown = terminal()
    assert "scoring bingham: simulating records 2/3" in shown
    assert re.search(r"^scoring bingham: done in \d+\.\d s$", shown, re.MULTILINE), shown


def test_terminal_detection(monkeypatch: pytest.MonkeyPatch) -> None:
    from mrdamper.cli import _status

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert _status._terminal_console() is None
    with _status.working("plain") as status:
        progress.report("a stage: never printed off a terminal", 1, 2)
        status.message = "plain lines"
    assert re.fullmatch(r"plain lines: done in \d+\.\d s\n", sys.stderr.getvalue())
    monkeypatch.setattr(sys, "stderr", Tty())
    assert _status._terminal_console() is not None
    with _status.working("busy"):
        pass
    assert re.search(r"busy: done in \d+\.\d s", _ANSI.sub("", sys.stderr.getvalue()))
