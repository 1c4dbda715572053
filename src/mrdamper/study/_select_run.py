"""The fits of :func:`mrdamper.study.selection.cross_validate`, over worker processes.

One task per model kind and fold: fit the kind on the fold's training records and score it in
free run on the left-out ones, in the worker (a fold's model never leaves it); one task per kind
for the fit on all the records and its stress test. The tasks run on the study's executor
(:func:`mrdamper.study.executor.make_executor`: in this process for one worker, local processes
otherwise), each with single-threaded BLAS, and their results are put together in the plan's
order, so the table is the same, to the byte, whatever the number of workers.

At most one task per worker is queued, so that two rules can act before a fit starts:

* **Successive halving** (``halving``, as scikit-learn's ``HalvingGridSearchCV`` does with
  candidates): the first round is the first in-envelope fold and the first beyond-envelope fold
  (the first two in-envelope folds without beyond-envelope folds) of every kind. A kind whose
  round-one estimate of ``rank_esr`` (the mean of its two ESRs, by the rule of the ranking) is more
  than ``halving`` times the lowest estimate of a kind that can be recommended, or that failed a
  round-one fold, runs no further fit; its status says after how many fits and why. Round two
  (the other folds and the stress test) of a kind may start before round one has ended, on a
  worker that would be idle; its results are dropped if the kind is dropped, so the table does
  not depend on the timing.
* **Time budget** (``time_budget``): once the budget has run out no fit starts; the kinds with
  fits not run are not compared (their status says how many of their fits ran).
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mrdamper import kinds
from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import interrupt_in_chain
from mrdamper.progress import finished, report, section
from mrdamper.study._threads import single_threaded_blas
from mrdamper.study.executor import (
    StudyExecutor,
    compile_kernels,
    make_executor,
    resolve_record,
)

__all__ = ["Plan", "RunOutcome", "default_select_workers", "run_plan"]

#: One fold: label, training records, left-out records, and whether it leaves the envelope.
Fold = tuple[str, ExperimentSet, ExperimentSet, bool]


def default_select_workers() -> int:
    """Default number of worker processes of a selection: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class Plan:
    """What a selection runs.

    Attributes
    ----------
    kinds : sequence of str
        Model kinds, in table order.
    options : mapping
        Kind -> estimator settings.
    folds : sequence of Fold
        ``(label, train, test, beyond)``, the in-envelope folds first.
    records : ExperimentSet
        Every record (the stress test's fit).
    stress : bool
        Fit every kind on every record and stress-test it.
    seed : int
        Seed of the stress test's random motion.
    recommendable : mapping
        Kind -> whether it can be recommended at all (not interpolation-only when validating
        beyond the envelope); only such kinds lead the halving.
    """

    kinds: Sequence[str]
    options: Mapping[str, Mapping[str, Any]]
    folds: Sequence[Fold]
    records: ExperimentSet
    stress: bool
    seed: int
    recommendable: Mapping[str, bool]


@dataclass
class RunOutcome:
    """What :func:`run_plan` gives back.

    Attributes
    ----------
    rows : list of dict
        Score rows (:data:`mrdamper.study.selection.SCORE_COLUMNS`), in plan order.
    fit_times : dict
        Kind -> fit times of its successful in-envelope fold fits [s].
    stress : dict
        Kind -> :class:`~mrdamper.study.stress.StressResult` (kinds whose stress test ran).
    stopped : dict
        Kind -> why it ran no further fit (halving or the time budget).
    notes : list of str
        What the halving dropped and what the budget left out, in words.
    """

    rows: list[dict[str, Any]] = field(default_factory=list)
    fit_times: dict[str, list[float]] = field(default_factory=dict)
    stress: dict[str, Any] = field(default_factory=dict)
    stopped: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def score_row(
    kind: str, fold: str, record: str, esr: float, clipped: bool, error: str, out: bool
) -> dict[str, Any]:
    """One row of the scores table."""
    return {
        "model": kind,
        "fold": fold,
        "record": record,
        "esr": esr,
        "clipped": clipped,
        "error": error,
        "beyond": out,
    }


def fit_kind(
    kind: str, options: Mapping[str, Any], train: ExperimentSet, where: str
) -> tuple[Any, float, str]:
    """``(model or None, fit time [s], error text)``: warnings silenced, failures caught."""
    from mrdamper.models.registry import get_estimator

    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), section(where):
            warnings.simplefilter("ignore")
            model = get_estimator(kind, **options).fit(train)
    except Exception as exc:  # noqa: BLE001 - a failing kind is a row of the table
        return None, time.perf_counter() - t0, f"{type(exc).__name__}: {exc}"
    return model, time.perf_counter() - t0, ""


def _outside(model: Any, e: Experiment) -> bool:
    from mrdamper.errors import OutOfRangeError

    try:
        model.with_range_policy("error").electrical_input(e)
    except OutOfRangeError:
        return True
    except Exception:  # noqa: BLE001 - a missing channel shows up when scoring
        return False
    return False


def _score(model: Any, kind: str, label: str, e: Experiment, out: bool) -> dict[str, Any]:
    clipped = _outside(model, e)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            esr = float(model.with_range_policy("clip").score(e).esr)
    except Exception as exc:  # noqa: BLE001 - reported
        return score_row(
            kind, label, e.name, np.nan, clipped, f"simulate: {type(exc).__name__}: {exc}", out
        )
    return score_row(kind, label, e.name, esr, clipped, "", out)


def _records(handles: Sequence[Any], name: str) -> ExperimentSet:
    return ExperimentSet([resolve_record(h) for h in handles], name=name)


def fold_task(
    kind: str,
    options: Mapping[str, Any],
    fold: tuple[str, bool],
    train: tuple[str, Sequence[Any]],
    test: Sequence[Any],
    where: str,
) -> tuple[list[dict[str, Any]], float | None]:
    """Fit ``kind`` on one fold's training records and score it on the left-out ones (in a
    worker). Returns the score rows and the fit time [s] (None when the fit failed)."""
    label, out = fold
    with single_threaded_blas():
        tests = _records(test, "left out")
        model, elapsed, err = fit_kind(kind, options, _records(train[1], train[0]), where)
        if model is None:
            return [
                score_row(kind, label, e.name, np.nan, False, f"fit: {err}", out) for e in tests
            ], None
        report(f"{where}: scoring the left-out data")
        return [_score(model, kind, label, e, out) for e in tests], elapsed


def stress_task(
    kind: str, options: Mapping[str, Any], records: tuple[str, Sequence[Any]], where: str, seed: int
) -> Any:
    """Fit ``kind`` on every record and stress-test it (in a worker); a
    :class:`~mrdamper.study.stress.StressResult`, failures included."""
    import pandas as pd

    from mrdamper.study.stress import StressResult, stress_test

    with single_threaded_blas():
        exps = _records(records[1], records[0])
        model, _, err = fit_kind(kind, options, exps, where)
        if model is None:
            return StressResult(pd.DataFrame(), False, f"fit on all the records failed: {err}")
        report(f"{where}: stress test")
        try:
            return stress_test(model, exps, seed=seed)
        except Exception as exc:  # noqa: BLE001 - reported
            return StressResult(pd.DataFrame(), False, f"{type(exc).__name__}: {exc}")


def _first_round(folds: Sequence[Fold]) -> list[int]:
    """Plan indices of round one: the first in-envelope and the first beyond-envelope fold, or
    the first two in-envelope folds when none leaves the envelope."""
    inside = [j for j, f in enumerate(folds) if not f[3]]
    beyond = [j for j, f in enumerate(folds) if f[3]]
    return inside[:1] + beyond[:1] if beyond else inside[:2]


def _estimate(rows: Sequence[dict[str, Any]]) -> float:
    """Round-one estimate of ``rank_esr``: mean over folds of the fold's mean ESR (NaN when a fold
    failed), the folds inside and beyond the envelope weighing as in the ranking."""
    by_fold: dict[str, list[float]] = {}
    for r in rows:
        by_fold.setdefault(str(r["fold"]), []).append(np.nan if r["error"] else float(r["esr"]))
    if not by_fold:
        return np.nan
    return float(np.mean([np.mean(v) for v in by_fold.values()]))


class _Runner:
    """The scheduling state of one :func:`run_plan` call."""

    def __init__(
        self,
        plan: Plan,
        ex: StudyExecutor,
        workers: int,
        halving: float | None,
        time_budget: float | None,
    ) -> None:
        self.plan, self.ex, self.workers = plan, ex, workers
        self.halving, self.budget = halving, time_budget
        self.t0 = time.perf_counter()
        n = len(plan.folds)
        self.stress_index = n
        per_kind = n + int(plan.stress)
        self.round_one = _first_round(plan.folds) if halving is not None else list(range(n))
        rest = [j for j in range(per_kind) if j not in self.round_one]
        order = sorted(plan.kinds, key=lambda k: (kinds.cost_rank(k), list(plan.kinds).index(k)))
        self.queue1 = [(k, j) for k in order for j in self.round_one]
        self.queue2 = [(k, j) for k in order for j in rest]
        self.results: dict[tuple[str, int], Any] = {}
        self.pending: dict[Any, tuple[str, int]] = {}
        self.n_tasks = len(plan.kinds) * per_kind
        self.counted = 0
        self.dropped: dict[str, str] = {}
        self.early: set[str] = set()
        self.decided = halving is None
        self.kinds_done: set[str] = set()
        handles: dict[int, Any] = {}

        def share(e: Experiment) -> Any:
            if id(e) not in handles:
                handles[id(e)] = ex.share(e)
            return handles[id(e)]

        self.share = share

    # -------------------------------------------------------------------- submission
    def _submit(self, kind: str, j: int) -> None:
        p = self.plan
        options = dict(p.options[kind])
        k = len(self.results) + len(self.pending) + 1
        if j == self.stress_index:
            where = f"{kind}, all records ({k} of {self.n_tasks})"
            recs = (p.records.name, [self.share(e) for e in p.records])
            fut = self.ex.submit(stress_task, kind, options, recs, where, p.seed)
        else:
            label, train, test, out = p.folds[j]
            where = f"{kind}, fold {label} ({k} of {self.n_tasks})"
            fut = self.ex.submit(
                fold_task,
                kind,
                options,
                (label, out),
                (train.name, [self.share(e) for e in train]),
                [self.share(e) for e in test],
                where,
            )
        self.pending[fut] = (kind, j)

    def _out_of_time(self) -> bool:
        return self.budget is not None and time.perf_counter() - self.t0 >= self.budget

    def _next(self) -> tuple[str, int] | None:
        """The next task to start, or None (nothing left that may start now)."""
        if self.queue1:
            return self.queue1.pop(0)
        for i, (kind, j) in enumerate(self.queue2):
            if kind not in self.early:
                return self.queue2.pop(i)
        return None

    def fill(self) -> None:
        while len(self.pending) < self.workers:
            if self._out_of_time():
                return
            nxt = self._next()
            if nxt is None:
                return
            self._submit(*nxt)

    # -------------------------------------------------------------------- collection
    def collect(self) -> None:
        done, _ = self.ex.wait_first(list(self.pending))
        for fut in sorted(done, key=lambda f: self._order(self.pending[f])):
            key = self.pending.pop(fut)
            self.results[key] = self._result(fut, *key)
            self.counted += 1
            report("cross-validation: fits", self.counted, self.n_tasks)
        self._halve()
        for kind in self.plan.kinds:
            self._announce(kind)

    def _result(self, fut: Any, kind: str, j: int) -> Any:
        """The task's result, or a failure of the kind when the worker itself failed (a worker
        that ended, a record it could not read): a row of the table, not a crash."""
        try:
            return fut.result()
        except Exception as exc:
            if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
                raise KeyboardInterrupt from exc
            why = f"worker error: {type(exc).__name__}: {exc}"
        if j == self.stress_index:
            import pandas as pd

            from mrdamper.study.stress import StressResult

            return StressResult(pd.DataFrame(), False, why)
        label, _, test, out = self.plan.folds[j]
        return [score_row(kind, label, e.name, np.nan, False, why, out) for e in test], None

    def _order(self, key: tuple[str, int]) -> tuple[int, int]:
        return list(self.plan.kinds).index(key[0]), key[1]

    def _round_one_rows(self, kind: str) -> list[dict[str, Any]] | None:
        if any((kind, j) not in self.results for j in self.round_one):
            return None
        return [r for j in self.round_one for r in self.results[(kind, j)][0]]

    def _halve(self) -> None:
        """Drop the kinds far above the leader. Final once every kind's round one is in; until
        then a kind is dropped early (no further fit starts) only when it failed or is already
        far above the lowest estimate so far, which can only fall, so the final rule drops it
        too; the reason is written by the final rule alone."""
        if self.halving is None or self.decided:
            return
        est = {}
        for kind in self.plan.kinds:
            rows = self._round_one_rows(kind)
            if rows is not None:
                est[kind] = _estimate(rows)
        ok = {k: v for k, v in est.items() if np.isfinite(v) and self.plan.recommendable[k]}
        best = min(ok.values()) if ok else np.nan
        for kind, v in est.items():
            if not np.isfinite(v) or (np.isfinite(best) and v > self.halving * best):
                self.early.add(kind)
        if len(est) < len(self.plan.kinds):
            return
        self.decided = True
        n1 = len(self.round_one)
        leader = min(ok, key=lambda k: (ok[k], self._order((k, 0)))) if ok else ""
        for kind in self.plan.kinds:
            v = est[kind]
            if not np.isfinite(v):
                self.dropped[kind] = f"a fold failed in its first {n1} fits (stopped there)"
            elif leader and v > self.halving * ok[leader]:
                self.dropped[kind] = (
                    f"dropped after {n1} fits: estimate {v:.3g}, {v / ok[leader]:.1f} x the "
                    f"leader's ({leader}, {ok[leader]:.3g})"
                )

    def _announce(self, kind: str) -> None:
        if kind in self.kinds_done:
            return
        per_kind = len(self.plan.folds) + int(self.plan.stress)
        have = [j for j in range(per_kind) if (kind, j) in self.results]
        if kind in self.dropped:
            text = f"{kind}: {self.dropped[kind]}"
        elif len(have) == per_kind:
            text = f"{kind}: {_summary(self, kind)}"
        else:
            return
        self.kinds_done.add(kind)
        finished(text, len(self.kinds_done), len(self.plan.kinds))

    def busy(self) -> bool:
        """True while a task whose result is still wanted runs or may start."""
        wanted = any(k not in self.dropped for k, _ in self.pending.values())
        startable = bool(self.queue1) or any(k not in self.early for k, _ in self.queue2)
        return wanted or (startable and not self._out_of_time())

    # -------------------------------------------------------------------- result
    def outcome(self) -> RunOutcome:
        p = self.plan
        out = RunOutcome(fit_times={k: [] for k in p.kinds})
        per_kind = len(p.folds) + int(p.stress)
        for kind in p.kinds:
            missing = [j for j in range(per_kind) if (kind, j) not in self.results]
            keep = [j for j in range(per_kind) if (kind, j) in self.results]
            if kind in self.dropped:
                keep = [j for j in keep if j in self.round_one]
                out.stopped[kind] = self.dropped[kind]
            elif missing:
                out.stopped[kind] = (
                    f"not compared: the time budget ran out ({len(keep)} of {per_kind} fits run)"
                )
            for j in keep:
                if j == self.stress_index:
                    out.stress[kind] = self.results[(kind, j)]
                    continue
                rows, elapsed = self.results[(kind, j)]
                out.rows += rows
                if elapsed is not None and not p.folds[j][3]:
                    out.fit_times[kind].append(elapsed)
        dropped = [k for k in p.kinds if k in self.dropped]
        if dropped:
            out.notes.append(
                f"successive halving: {', '.join(dropped)} ran only the first "
                f"{len(self.round_one)} fits of {per_kind} (far above the leader or failed; "
                "see status)"
            )
        short = [k for k, why in out.stopped.items() if why.startswith("not compared")]
        if short:
            spent = (
                f"time budget of {self.budget:g} s" if self.budget is not None else "time budget"
            )
            out.notes.append(f"the {spent} ran out: not compared: {', '.join(short)}")
        return out


def _summary(run: _Runner, kind: str) -> str:
    rows = [r for j in range(len(run.plan.folds)) for r in run.results[(kind, j)][0]]
    inside = [r["esr"] for r in rows if not r["beyond"] and not r["error"]]
    failed = sum(1 for r in rows if r["error"])
    text = f"{len(run.plan.folds)} folds"
    if inside:
        text += f", mean ESR inside {np.mean(inside):.3g}"
    if failed:
        text += f", {failed} left-out record(s) failed"
    if run.plan.stress:
        text += f", stress test {run.results[(kind, run.stress_index)].reason}"[:120]
    return text + f"; at {time.perf_counter() - run.t0:.0f} s"


def run_plan(
    plan: Plan,
    *,
    workers: int | None = None,
    halving: float | None = None,
    time_budget: float | None = None,
    executor: Callable[[int], StudyExecutor] = make_executor,
) -> RunOutcome:
    """Run every fit of ``plan`` (module docstring) and gather the results in plan order.

    Parameters
    ----------
    plan : Plan
        Kinds, settings and folds.
    workers : int, optional
        Worker processes (default :func:`default_select_workers`); 1 runs in this process.
    halving : float, optional
        Successive-halving factor (> 1); None runs every fit of every kind.
    time_budget : float, optional
        No fit starts after this many seconds [s]; None: no limit.
    executor : callable
        Makes the executor from the number of workers.

    Returns
    -------
    RunOutcome
    """
    n = default_select_workers() if workers is None else workers
    ex = executor(n)
    run = _Runner(plan, ex, n, halving, time_budget)
    report("cross-validation: fits", 0, run.n_tasks)
    try:
        compile_kernels(ex, list(plan.kinds))
        run.fill()
        while run.pending and run.busy():
            run.collect()
            run.fill()
    except BaseException:
        ex.close(cancel=True)
        raise
    ex.close(cancel=bool(run.pending))
    report("cross-validation: fits", run.n_tasks, run.n_tasks)
    return run.outcome()
