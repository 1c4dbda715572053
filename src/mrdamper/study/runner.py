"""Run a comparison study: every model of a protocol fitted on every fold and scored on its records.

Fits and simulations are tasks on an executor (in-process, local processes or Dask; see
:mod:`mrdamper.study.executor`). A model's simulations start as soon as its fit is done. A model
that fails to fit, diverges or leaves its range stays in the results as rows with a status and the
error. Rows are ordered by fold, model and record whatever the completion order, so the same inputs
and seed give the same table (timing columns aside).
"""

from __future__ import annotations

import dataclasses
import fnmatch
import inspect
import platform
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeVar, cast

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from mrdamper import kinds
from mrdamper.data import Experiment, ExperimentSet, SourceSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, MrDamperError, SchemaError, interrupt_in_chain
from mrdamper.models import Estimator, FittedModel
from mrdamper.models.base import RangePolicy
from mrdamper.progress import finished
from mrdamper.study._tasks import FitOutcome, SimOutcome, fit_task, simulate_task
from mrdamper.study.analysis_step import AnalysisOutcome, run_analysis
from mrdamper.study.control_step import (
    ControlRelevance,
    ControlSettings,
    control_relevance,
    truth_damper,
)
from mrdamper.study.executor import (
    ProcessExecutor,
    SerialExecutor,
    StudyExecutor,
    compile_kernels,
    loops_ahead,
    make_executor,
)
from mrdamper.study.presets import doe_protocol
from mrdamper.study.protocol import ModelSpec, Protocol, _as_spec
from mrdamper.study.provenance import provenance
from mrdamper.study.records import Record, Records, as_list, as_loaded, load_all
from mrdamper.study.result import Showcase, StudyResult
from mrdamper.study.selection import SCORE_COLUMNS, SelectionResult, selection_from_scores
from mrdamper.study.splits import Fold, make_folds, roles_frame
from mrdamper.study.tables import RESULT_COLUMNS

__all__ = [
    "DEFAULT_CONTROL",
    "META_COLUMNS",
    "data_origin",
    "laws_users",
    "progress_bars",
    "run_study",
]

#: Executors whose workers share this machine's kernel cache (the loops are compiled ahead).
_LOCAL = (ProcessExecutor, SerialExecutor)

#: The control-relevance step a study runs unless told otherwise (short roads, one class/speed).
DEFAULT_CONTROL = ControlSettings()

#: Record metadata copied into the results table when present.
META_COLUMNS: tuple[str, ...] = (
    "experiment",
    "replicate",
    "pattern",
    "condition",
    "current",
    "amplitude",
    "frequency",
)

_LAW_SETTINGS = ("laws", "zone_laws")
_O = TypeVar("_O", FitOutcome, SimOutcome)


def _estimator_fields(est: Estimator) -> set[str]:
    if dataclasses.is_dataclass(est):
        return {f.name for f in dataclasses.fields(est)}
    return set(inspect.signature(type(est)).parameters)


def _outer_slopes_wanted(est: Estimator) -> str:
    """The outer slopes of the laws ``est`` takes from the analysis step: those its
    ``outer_slopes`` resolves to, the paper's (``"zones"``) for an estimator without the setting."""
    resolve = getattr(est, "resolved_outer_slopes", None)
    return str(resolve()) if resolve is not None else "zones"


def _settings(
    spec: ModelSpec, protocol: Protocol, seed: int, analysis: AnalysisOutcome
) -> dict[str, Any]:
    """Estimator settings of ``spec``.

    With the protocol's input, the study seed and the fold's laws: the paper's, or those with
    post-yield outer slopes for an estimator whose ``outer_slopes`` resolves to them.
    """
    from mrdamper.models import get_estimator

    out = protocol.settings_for(spec)
    try:
        est = get_estimator(spec.kind, **out)
    except (TypeError, DataValidationError) as exc:  # an unknown setting is refused, naming it
        raise SchemaError(f"models.{spec.label}.settings: {exc}") from None
    fields = _estimator_fields(est)
    if "input" in fields and "input" not in out:
        out["input"] = protocol.input
    if "seed" in fields and "seed" not in out:
        out["seed"] = seed
    laws = analysis.laws_for(_outer_slopes_wanted(est))
    if laws is not None:
        for key in _LAW_SETTINGS:
            if key in fields and key not in out:
                out[key] = laws
    return out


def laws_users(protocol: Protocol) -> dict[str, str]:
    """Label -> outer slopes (``"zones"``: the paper's laws, or ``"post-yield"``) of the zone laws
    each model of ``protocol`` takes from the analysis step, as :func:`_settings` hands them out;
    models that take no zone laws, or that give them themselves, are left out."""
    from mrdamper.models import get_estimator

    out: dict[str, str] = {}
    for spec in protocol.resolved_models():
        own = protocol.settings_for(spec)
        try:
            est = get_estimator(spec.kind, **own)
        except (TypeError, MrDamperError):
            continue  # refused when the study runs, naming the setting
        fields = _estimator_fields(est)
        if any(k in own for k in _LAW_SETTINGS) or not any(k in fields for k in _LAW_SETTINGS):
            continue
        out[spec.label] = _outer_slopes_wanted(est)
    return out


def data_origin(data: Iterable[Record]) -> str:
    """Where the records come from, for the report's wording.

    Parameters
    ----------
    data : iterable of Experiment or RecordSource
        The study's records (their metadata).

    Returns
    -------
    str
        ``"virtual rig (<damper> damper)"`` when every record carries the virtual rig's metadata
        (``source = "virtual rig"``), else ``"measured"`` (files, real test rigs, or records
        whose origin is not recorded).
    """
    recs = list(data)
    if recs and all(e.metadata.get("source") == "virtual rig" for e in recs):
        dampers = sorted({str(e.metadata.get("damper", "unknown")) for e in recs})
        return f"virtual rig ({', '.join(dampers)} damper)"
    return "measured"


def _pick(records: Iterable[Record], pattern: str | None) -> Record | None:
    for e in records:
        if pattern is None or fnmatch.fnmatchcase(e.name, pattern):
            return e
    return None


def _predict_all(
    models: Mapping[str, FittedModel], e: Experiment, policy: RangePolicy
) -> dict[str, NDArray[np.float64] | str]:
    """Label -> predicted force [N] or the error text, for the figures."""
    import warnings

    out: dict[str, NDArray[np.float64] | str] = {}
    for label, m in models.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                F = np.asarray(m.with_range_policy(policy).predict(e), dtype=float)
                out[label] = F if np.all(np.isfinite(F)) else "non-finite prediction"
            except Exception as exc:
                if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
                    raise KeyboardInterrupt from exc
                out[label] = f"{type(exc).__name__}: {exc}"
    return out


def progress_bars(enabled: bool) -> Any:
    """The study's progress bars on standard error: one per stage (fitting, simulating, the
    quarter-car loop), and the writing of a report by the command line; drawn only when it is a
    terminal and ``enabled`` (off a terminal the finished models are announced through
    :func:`mrdamper.progress.finished` instead)."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    console = Console(stderr=True)
    return Progress(
        TextColumn("{task.description:<12}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=console,
        disable=not (enabled and console.is_terminal),
        transient=False,
    )


def run_study(
    data: ExperimentSet | SourceSet | Iterable[Experiment],
    protocol: Protocol | None = None,
    models: Sequence[str | ModelSpec | Mapping[str, Any]] | None = None,
    *,
    workers: int | None = None,
    scheduler: Any = None,
    seed: int = 0,
    progress: bool = True,
    control: ControlSettings | None = DEFAULT_CONTROL,
) -> StudyResult:
    """Fit every model of ``protocol`` on each fold of ``data`` and score it on the fold's records.

    Parameters
    ----------
    data : ExperimentSet, SourceSet or iterable of Experiment
        All records of the study (never modified). Records in memory are shared with the
        workers; sources (:func:`mrdamper.data.record_sources`) are read by the workers that
        use them, so this process holds only the analysis and figure records, one set at a time.
    protocol : Protocol, optional
        Roles of the records and models; default :func:`~mrdamper.study.protocol.doe_protocol`.
    models : sequence, optional
        Overrides the protocol's models: kinds (``"lpv"``), :class:`ModelSpec` or dicts.
    workers : int, optional
        Local worker processes (default ``min(2, cpu)``); ``1`` runs in this process.
    scheduler : str or distributed.Client, optional
        Dask scheduler address or client; when given, tasks run there instead.
    seed : int
        Passed as ``seed`` to every estimator that takes one (unless its settings set it).
    progress : bool
        Show progress bars on standard error when it is a terminal. Each model whose fits and
        simulations are all done is reported as a finished step
        (:func:`mrdamper.progress.finished`) either way.
    control : ControlSettings or None
        The control-relevance step after the fits
        (:func:`~mrdamper.study.control_step.control_relevance`: the first fold's models in the
        quarter-car loop, against the rig's reference damper when the truth is known); None
        skips it.

    Returns
    -------
    StudyResult
        Results, summary, fitted models, analysis and figure data (a value; write it with
        :func:`~mrdamper.study.writer.write_study`).

    Raises
    ------
    SchemaError
        Unknown model kind or setting, or a protocol that leaves a fold without training or
        scoring records. Model failures do not raise: they are rows with a status.
    """
    t_start = time.perf_counter()
    records: Records = data if isinstance(data, SourceSet) else as_experiment_set(data, name="data")
    protocol = protocol or doe_protocol()
    if models is not None:
        protocol = protocol.with_models([_as_spec(m) for m in models])
    specs = protocol.resolved_models()
    if not specs:
        raise SchemaError("models: no model to run (none given and no default model is installed)")
    protocol = protocol.with_models(specs)  # the saved protocol lists the models actually run
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise SchemaError(f"seed: expected an integer, got {seed!r}")
    folds = make_folds(records, protocol)
    analyses: dict[str, AnalysisOutcome] = {}
    for fold in folds:
        if protocol.analysis is None:
            analyses[fold.name] = AnalysisOutcome(
                error="no force-velocity analysis in this protocol"
            )
        else:
            analyses[fold.name] = run_analysis(load_all(fold.analysis), protocol.input)
    settings = {
        (fi, si): _settings(spec, protocol, int(seed), analyses[fold.name])
        for fi, fold in enumerate(folds)
        for si, spec in enumerate(specs)
    }
    fit_out: dict[tuple[int, int], FitOutcome] = {}
    sim_out: dict[tuple[int, int, int], SimOutcome] = {}
    executor = make_executor(workers, scheduler)
    # the quarter-car loops compile once, beside the fits (local workers load them after)
    loops = loops_ahead() if control is not None and isinstance(executor, _LOCAL) else None
    try:
        _execute(executor, folds, specs, settings, protocol, fit_out, sim_out, progress)
        if loops is not None:
            loops.join()
        t_control = time.perf_counter()
        control_res = None
        if control is not None:  # its own bar: the loop runs after the simulations
            with progress_bars(progress) as bar:
                n_loop = sum(fit_out[(0, si)].ok for si in range(len(specs)))
                task = bar.add_task("quarter car", total=n_loop)
                control_res = _control(
                    executor, folds, specs, fit_out, records, control, lambda: bar.advance(task)
                )
        t_control = time.perf_counter() - t_control
        if control_res is not None:
            finished(f"control relevance: the quarter-car loop in {t_control:.0f} s")
    except BaseException:
        if loops is not None and loops.is_alive():
            loops.terminate()
        executor.close(cancel=True)
        raise
    executor.close()
    results, fits = _tables(folds, specs, fit_out, sim_out)
    fitted = _fitted_models(folds, specs, fit_out)
    selection = _selection(folds, specs, fit_out, sim_out, protocol)
    showcase, hysteresis = _showcases(folds, specs, fitted, protocol)
    info = {
        "seed": int(seed),
        "executor": executor.description,
        "wall_time_s": time.perf_counter() - t_start,
        "control_time_s": t_control,
        "n_records": len(records),
        "data_origin": data_origin(records),
        "n_folds": len(folds),
        "sources": sorted({str(e.metadata["source"]) for e in records if e.metadata.get("source")}),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "provenance": provenance(protocol, specs, int(seed)),
    }
    return StudyResult(
        protocol=protocol,
        specs=specs,
        results=results,
        fits=fits,
        roles=roles_frame(folds),
        models=fitted,
        analyses=analyses,
        showcase=showcase,
        hysteresis=hysteresis,
        info=info,
        selection=selection,
        control=control_res,
    )


def _control(
    ex: StudyExecutor,
    folds: list[Fold],
    specs: Sequence[ModelSpec],
    fit_out: Mapping[tuple[int, int], FitOutcome],
    records: Records,
    settings: ControlSettings,
    advance: Callable[[], None] | None = None,
) -> ControlRelevance:
    """The first fold's models in the quarter-car loop, one task per model on the executor (the
    truth is the rig's damper when every record comes from it); ``advance()`` after each
    model."""
    done = {s.label: fit_out[(0, si)] for si, s in enumerate(specs)}
    order = sorted(specs, key=lambda s: kinds.cost_rank(s.kind))  # the longest task starts first
    return control_relevance(
        {s.label: done[s.label].model for s in order if done[s.label].ok},
        [s.label for s in specs],
        {s.label: s.kind for s in specs},
        truth_damper(records, settings.plant),
        folds[0].name,
        settings,
        fit_errors={k: str(v.error) for k, v in done.items()},
        submit=ex.submit,
        advance=advance,
    )


def _execute(
    ex: StudyExecutor,
    folds: list[Fold],
    specs: Sequence[ModelSpec],
    settings: Mapping[tuple[int, int], dict[str, Any]],
    protocol: Protocol,
    fit_out: dict[tuple[int, int], FitOutcome],
    sim_out: dict[tuple[int, int, int], SimOutcome],
    show: bool,
) -> None:
    handles: dict[int, Any] = {}

    def handle(e: Record) -> Any:
        if id(e) not in handles:
            handles[id(e)] = ex.share(e)
        return handles[id(e)]

    ex.prepare([e for fold in folds for part in (fold.train, fold.score) for e in part])
    n_sims = sum(len(f.score) for f in folds) * len(specs)
    fits: dict[Any, tuple[int, int]] = {}  # future -> (fold, model)
    sims: dict[Any, tuple[int, int, int]] = {}  # future -> (fold, model, scored record)
    trains = [[handle(e) for e in fold.train] for fold in folds]
    order = sorted(
        ((fi, si) for fi in range(len(folds)) for si in range(len(specs))),
        key=lambda k: (kinds.cost_rank(specs[k[1]].kind), k),
    )
    compile_kernels(ex, [spec.kind for spec in specs])
    for fi, si in order:
        fits[ex.submit(fit_task, specs[si].kind, settings[(fi, si)], trains[fi])] = (fi, si)
    left = {si: len(folds) + sum(len(f.score) for f in folds) for si in range(len(specs))}
    models_done = 0

    def step(si: int, n: int = 1) -> None:
        nonlocal models_done
        left[si] -= n
        if left[si] == 0:
            models_done += 1
            finished(
                _model_line(specs[si].label, si, folds, fit_out, sim_out), models_done, len(specs)
            )

    with progress_bars(show) as bar:
        t_fit = bar.add_task("fitting", total=len(folds) * len(specs))
        t_sim = bar.add_task("simulating", total=n_sims)
        while fits or sims:
            done, _ = ex.wait_first([*fits, *sims])
            for fut in done:
                if fut in fits:
                    fi, si = fits.pop(fut)
                    fr = _outcome(fut, FitOutcome)
                    fit_out[(fi, si)] = fr
                    bar.advance(t_fit)
                    if fr.ok:
                        for ri, e in enumerate(as_list(folds[fi].score)):
                            sims[
                                ex.submit(simulate_task, fr.model, handle(e), protocol.range_policy)
                            ] = (fi, si, ri)
                    else:
                        bar.advance(t_sim, len(folds[fi].score))
                        step(si, len(folds[fi].score))
                    step(si)
                else:
                    key = sims.pop(fut)
                    sim_out[key] = _outcome(fut, SimOutcome)
                    bar.advance(t_sim)
                    step(key[1])


def _model_line(
    label: str,
    si: int,
    folds: list[Fold],
    fit_out: Mapping[tuple[int, int], FitOutcome],
    sim_out: Mapping[tuple[int, int, int], SimOutcome],
) -> str:
    """One line on a model whose fits and simulations are all done."""
    fitted = sum(fit_out[(fi, si)].ok for fi in range(len(folds)))
    esr = [o.esr for (_, s, _), o in sim_out.items() if s == si and o.status == "ok"]
    failed = sum(1 for (_, s, _), o in sim_out.items() if s == si and o.status != "ok")
    text = f"{label}: fitted on {fitted} of {len(folds)} fold(s)"
    if esr:
        text += f", mean ESR {float(np.mean(esr)):.3g} over {len(esr)} record(s)"
    return text + (f", {failed} simulation(s) failed" if failed else "")


def _outcome(fut: Any, kind: type[_O]) -> _O:
    """The task's outcome, or a failed one when the worker itself raised."""
    try:
        res = fut.result()
    except Exception as exc:
        if interrupt_in_chain(exc):  # Ctrl-C inside a compiled kernel
            raise KeyboardInterrupt from exc
        why = f"worker error: {type(exc).__name__}: {exc}"
        if kind is FitOutcome:
            return cast(_O, FitOutcome.failed(why))
        return cast(_O, SimOutcome.failed("sim-failed", why))
    if not isinstance(res, kind):
        raise TypeError(f"task returned {type(res).__name__}, expected {kind.__name__}")
    return res


def _tables(
    folds: list[Fold],
    specs: Sequence[ModelSpec],
    fit_out: Mapping[tuple[int, int], FitOutcome],
    sim_out: Mapping[tuple[int, int, int], SimOutcome],
) -> tuple[pd.DataFrame, pd.DataFrame]:
    nan = float("nan")
    rows: list[dict[str, Any]] = []
    fit_rows: list[dict[str, Any]] = []
    meta_present = [k for k in META_COLUMNS if any(k in e.metadata for f in folds for e in f.score)]
    for fi, fold in enumerate(folds):
        for si, spec in enumerate(specs):
            fr = fit_out[(fi, si)]
            fit_rows.append(
                {
                    "fold": fold.name,
                    "model": spec.label,
                    "kind": spec.kind,
                    "status": fr.status,
                    "fit_time_s": fr.fit_time_s,
                    "n_train": len(fold.train),
                    "train_samples": int(sum(e.n for e in fold.train)),
                    "note": fr.note,
                    "error": fr.error,
                }
            )
            for ri, e in enumerate(as_list(fold.score)):
                row: dict[str, Any] = {
                    "fold": fold.name,
                    "model": spec.label,
                    "kind": spec.kind,
                    "record": e.name,
                    "fit_time_s": fr.fit_time_s,
                }
                if not fr.ok:
                    row.update(
                        status=fr.status,
                        esr=nan,
                        ssse=nan,
                        nrmse=nan,
                        fit_pct=nan,
                        sim_time_s=nan,
                        note=fr.note,
                        error=fr.error,
                    )
                else:
                    sr = sim_out[(fi, si, ri)]
                    row.update(
                        status=sr.status,
                        esr=sr.esr,
                        ssse=sr.ssse,
                        nrmse=sr.nrmse,
                        fit_pct=sr.fit_pct,
                        sim_time_s=sr.sim_time_s,
                        note=sr.note,
                        error=sr.error,
                    )
                for k in meta_present:
                    row[k] = e.metadata.get(k)
                rows.append(row)
    results = pd.DataFrame(rows, columns=[*RESULT_COLUMNS, *meta_present])
    return results, pd.DataFrame(fit_rows)


def _selection(
    folds: list[Fold],
    specs: Sequence[ModelSpec],
    fit_out: Mapping[tuple[int, int], FitOutcome],
    sim_out: Mapping[tuple[int, int, int], SimOutcome],
    protocol: Protocol,
) -> SelectionResult:
    """The model-selection table of ``mrdamper select`` from this study's held-out scores.

    Only scored records that neither trained the models nor the analysis of their fold count
    (a protocol may score training records; those scores are not held out). A fold fails for a
    model when its fit failed or one of its held-out simulations did not give a score.
    """
    rows: list[dict[str, Any]] = []
    fit_times: dict[str, list[float]] = {s.label: [] for s in specs}
    for fi, fold in enumerate(folds):
        trained = set(fold.train.names) | set(fold.analysis.names)
        for si, spec in enumerate(specs):
            fr = fit_out[(fi, si)]
            if fr.ok:
                fit_times[spec.label].append(fr.fit_time_s)
            for ri, e in enumerate(as_list(fold.score)):
                if e.name in trained:
                    continue
                row: dict[str, Any] = {"model": spec.label, "fold": fold.name, "record": e.name}
                if not fr.ok:
                    row.update(esr=float("nan"), clipped=False, error=f"fit: {fr.error}")
                else:
                    sr = sim_out[(fi, si, ri)]
                    ok = sr.status == "ok"
                    row.update(
                        esr=sr.esr if ok else float("nan"),
                        clipped=sr.outside_range,
                        error="" if ok else f"{sr.status}: {sr.error}",
                    )
                rows.append(row)
    scores = pd.DataFrame(rows, columns=list(SCORE_COLUMNS))
    return selection_from_scores(
        scores, [s.label for s in specs], fit_times, protocol.split.kind, len(folds)
    )


def _fitted_models(
    folds: list[Fold], specs: Sequence[ModelSpec], fit_out: Mapping[tuple[int, int], FitOutcome]
) -> dict[tuple[str, str], FittedModel]:
    from mrdamper.models import model_from_dict

    out: dict[tuple[str, str], FittedModel] = {}
    for fi, fold in enumerate(folds):
        for si, spec in enumerate(specs):
            res = fit_out[(fi, si)]
            if res.ok and res.model is not None:
                out[(fold.name, spec.label)] = model_from_dict(dict(res.model))
    return out


def _informative(folds: list[Fold], source: ElectricalSource) -> tuple[Fold, Record] | None:
    """The scored record that shows the most of a current-scheduled model (default showcase).

    Preference: a record whose electrical input varies (more than 10 % of the span over all
    scored records), then the highest mean electrical level, then the widest velocity spread;
    ties keep the first in fold and record order. Record sources are read one at a time.
    """
    cands = [(f, e) for f in folds for e in f.score]
    if not cands:
        return None
    stats = [_record_stats(as_loaded(e), source) for _, e in cands]
    span = max(max(hi for _, hi, _, _ in stats) - min(lo for lo, _, _, _ in stats), 1e-12)

    def key(k: int) -> tuple[bool, int, float]:
        lo, hi, mean_abs, v_std = stats[k]
        return (hi - lo > 0.1 * span, round(20 * mean_abs / span), v_std)

    best = max(range(len(cands)), key=lambda k: (key(k), -k))
    return cands[best]


def _record_stats(e: Experiment, source: ElectricalSource) -> tuple[float, float, float, float]:
    """``(min input, max input, mean |input|, std of v)`` of one record."""
    el = np.asarray(e.electrical(source), dtype=np.float64)
    return float(np.min(el)), float(np.max(el)), float(np.mean(np.abs(el))), float(np.std(e.v))


def _showcases(
    folds: list[Fold],
    specs: Sequence[ModelSpec],
    fitted: Mapping[tuple[str, str], FittedModel],
    protocol: Protocol,
) -> tuple[Showcase | None, Showcase | None]:
    """Predictions of every model on the figure records (Figs. 4, 6, 9, 10, 11).

    The showcase is the protocol's ``showcase`` glob (first match in fold order) or, when unset,
    the most informative scored record (:func:`_informative`); the hysteresis record is the
    protocol's ``hysteresis_record`` glob, else the showcase.
    """
    kinds = {s.label: s.kind for s in specs}

    def make(fold: Fold, rec: Record) -> Showcase:
        ms = {
            s.label: fitted[(fold.name, s.label)] for s in specs if (fold.name, s.label) in fitted
        }
        e = as_loaded(rec)
        return Showcase(
            fold=fold.name,
            record=e,
            predictions=_predict_all(ms, e, protocol.range_policy),
            kinds=kinds,
        )

    show = hyst = None
    if protocol.showcase is None:
        hit = _informative(folds, protocol.input)
        if hit is not None:
            show = make(*hit)
    for pattern, is_hyst in ((protocol.showcase, False), (protocol.hysteresis_record, True)):
        if pattern is None:
            continue
        for fold in folds:
            e = _pick(fold.score, pattern)
            if e is None:
                continue
            if is_hyst:
                hyst = make(fold, e)
            else:
                show = make(fold, e)
            break
    if hyst is None:
        hyst = show
    return show, hyst
