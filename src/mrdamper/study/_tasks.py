"""Worker-side tasks of a study: fit one model on one fold, simulate one model on one record.

Both run in worker processes (or in-process) and never raise for a model's failure: they return a
small frozen value (:class:`FitOutcome`, :class:`SimOutcome`) with a status and the error text, so
the failure becomes a row of the results. Both run with single-threaded BLAS (see
:mod:`mrdamper.study._threads`).
"""

from __future__ import annotations

import dataclasses
import time
import traceback
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from mrdamper.data import Experiment
from mrdamper.errors import (
    DataValidationError,
    IdentificationError,
    OutOfRangeError,
    SimulationDivergedError,
    interrupt_in_chain,
)
from mrdamper.models import FittedModel, RangePolicy
from mrdamper.study._threads import single_threaded_blas
from mrdamper.study.executor import RecordHandle, resolve_record

__all__ = ["FitOutcome", "FitStatus", "SimOutcome", "SimStatus", "fit_task", "simulate_task"]

#: Status of a fit: identified, or failed (the reason is in ``error``).
FitStatus = Literal["ok", "fit-failed"]
#: Status of a free-run simulation of one scored record.
SimStatus = Literal["ok", "diverged", "out-of-range", "sim-failed"]

_NAN = float("nan")


@dataclass(frozen=True)
class FitOutcome:
    """What a fit task returns.

    Attributes
    ----------
    status : {"ok", "fit-failed"}
        Whether the model was identified.
    model : dict or None
        The fitted model's ``to_dict()`` (plain data, cheap to send between processes); None
        unless ok.
    fit_time_s : float
        Wall time of the task [s] (NaN when the worker itself failed).
    error : str
        Why it failed (empty when ok).
    note : str
        Up to three distinct warnings raised while fitting.
    """

    status: FitStatus
    model: Mapping[str, Any] | None
    fit_time_s: float
    error: str = ""
    note: str = ""

    @property
    def ok(self) -> bool:
        """True when the model was identified."""
        return self.status == "ok" and self.model is not None

    @classmethod
    def failed(cls, error: str, fit_time_s: float = _NAN, note: str = "") -> FitOutcome:
        """A failed fit with its reason."""
        return cls("fit-failed", None, fit_time_s, error, note)


@dataclass(frozen=True)
class SimOutcome:
    """What a simulation task returns.

    Attributes
    ----------
    status : {"ok", "diverged", "out-of-range", "sim-failed"}
        Outcome of the free run.
    esr, ssse, nrmse, fit_pct : float
        Scores (ESR, SSSE [N], NRMSE, fit [%]); NaN unless ok.
    sim_time_s : float
        Simulation time [s] (NaN when it did not run).
    error : str
        Why it failed (empty when ok).
    note : str
        Up to three distinct warnings raised while simulating.
    outside_range : bool
        The record's electrical input leaves the range the model was identified on (the
        protocol's range policy then decides: extrapolate, clip or refuse).
    """

    status: SimStatus
    esr: float = _NAN
    ssse: float = _NAN
    nrmse: float = _NAN
    fit_pct: float = _NAN
    sim_time_s: float = _NAN
    error: str = ""
    note: str = ""
    outside_range: bool = False

    @classmethod
    def failed(
        cls, status: SimStatus, error: str, note: str = "", outside_range: bool = False
    ) -> SimOutcome:
        """A simulation that did not give scores, with its status and reason."""
        return cls(status, error=error, note=note, outside_range=outside_range)


def _message(exc: BaseException) -> str:
    text = str(exc).strip().replace("\n", " ")
    return f"{type(exc).__name__}: {text}"[:500]


def _reraise_interrupt(exc: BaseException) -> None:
    """Ctrl-C inside a compiled kernel can surface as ``SystemError`` (its cause is the
    KeyboardInterrupt): that is an interruption of the study, never a failure of the model."""
    if interrupt_in_chain(exc):
        raise KeyboardInterrupt from exc


def _notes(caught: Sequence[warnings.WarningMessage]) -> str:
    seen: list[str] = []
    for w in caught:
        msg = f"{w.category.__name__}: {w.message}".replace("\n", " ")[:200]
        if msg not in seen:
            seen.append(msg)
    return " | ".join(seen[:3])


def fit_task(kind: str, settings: Mapping[str, Any], records: Sequence[RecordHandle]) -> FitOutcome:
    """Identify ``kind`` with ``settings`` on ``records`` (handles, read here).

    Parameters
    ----------
    kind : str
        Registry kind of the model.
    settings : mapping
        Estimator settings.
    records : sequence of record handles
        Training records as the executor shared them (see
        :func:`~mrdamper.study.executor.resolve_record`).

    Returns
    -------
    FitOutcome
    """
    from mrdamper.data import ExperimentSet
    from mrdamper.models import get_estimator

    t0 = time.perf_counter()
    model: Mapping[str, Any] | None = None
    error = ""
    with single_threaded_blas(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            train = ExperimentSet([resolve_record(h) for h in records], name="training")
            model = get_estimator(kind, **dict(settings)).fit(train).to_dict()
        except (
            IdentificationError,
            SimulationDivergedError,
            DataValidationError,
            OutOfRangeError,
        ) as exc:
            error = _message(exc)
        except Exception as exc:  # noqa: BLE001 - any other failure of a model is a result row, not a crash
            _reraise_interrupt(exc)
            tb = traceback.extract_tb(exc.__traceback__)
            where = f" (at {tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
            error = _message(exc) + where
    elapsed = time.perf_counter() - t0
    if model is None:
        return FitOutcome.failed(error, elapsed, _notes(caught))
    return FitOutcome("ok", model, elapsed, "", _notes(caught))


def simulate_task(
    model: Mapping[str, Any], record: RecordHandle, range_policy: RangePolicy
) -> SimOutcome:
    """Free-run simulation of one record by one saved model; return status, scores and timing.

    Parameters
    ----------
    model : mapping
        The model's ``to_dict()``.
    record : record handle
        The scored record as the executor shared it (read here).
    range_policy : str
        Range policy applied to the model (``error``, ``warn``, ``clip``, ``ignore``).

    Returns
    -------
    SimOutcome
    """
    from mrdamper.models import model_from_dict

    outside = False
    with single_threaded_blas(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out: SimOutcome
        try:
            exp = resolve_record(record)
            saved = model_from_dict(dict(model))
            outside = _outside_range(saved, exp)
            fitted = saved.with_range_policy(range_policy)
            res = fitted.simulate(exp)
            try:
                s = res.scores
            except DataValidationError as exc:  # non-finite prediction returned without an error
                out = SimOutcome("diverged", sim_time_s=res.elapsed, error=_message(exc))
            else:
                out = SimOutcome(
                    "ok",
                    esr=s.esr,
                    ssse=s.ssse,
                    nrmse=s.nrmse,
                    fit_pct=s.fit,
                    sim_time_s=res.elapsed,
                )
        except SimulationDivergedError as exc:
            out = SimOutcome.failed("diverged", _message(exc))
        except OutOfRangeError as exc:
            out = SimOutcome.failed("out-of-range", _message(exc))
        except Exception as exc:  # noqa: BLE001 - any other failure of a model is a result row, not a crash
            _reraise_interrupt(exc)
            out = SimOutcome.failed("sim-failed", _message(exc))
    return dataclasses.replace(out, note=_notes(caught), outside_range=outside)


def _outside_range(model: FittedModel, exp: Experiment) -> bool:
    """True when ``exp``'s electrical input leaves the model's identified range."""
    try:
        model.with_range_policy("error").electrical_input(exp)
    except OutOfRangeError:
        return True
    except Exception:  # noqa: BLE001 - a missing channel is reported by the simulation itself
        return False
    return False
