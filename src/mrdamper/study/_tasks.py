"""Worker-side tasks of a study: fit one model on one fold, simulate one model on one record.

Both run in worker processes (or in-process) and never raise for a model's failure: they return a
plain dict with a ``status`` and the error text, so the failure becomes a row of the results.
Both run with single-threaded BLAS (see :mod:`mrdamper.study._threads`).
"""

from __future__ import annotations

import time
import traceback
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

from mrdamper.errors import (
    DataValidationError,
    IdentificationError,
    OutOfRangeError,
    SimulationDivergedError,
    interrupt_in_chain,
)
from mrdamper.study._threads import single_threaded_blas
from mrdamper.study.executor import resolve_record

__all__ = ["fit_task", "simulate_task"]


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


def fit_task(kind: str, settings: Mapping[str, Any], records: Sequence[Any]) -> dict[str, Any]:
    """Identify ``kind`` with ``settings`` on ``records`` (handles); return status and model dict.

    Returns
    -------
    dict
        ``status`` (``"ok"`` or ``"fit-failed"``), ``model`` (the model's ``to_dict()`` or None),
        ``fit_time_s`` [s], ``error`` and ``note`` (warnings raised while fitting).
    """
    from mrdamper.data import ExperimentSet
    from mrdamper.models import get_estimator

    t0 = time.perf_counter()
    out: dict[str, Any]
    with single_threaded_blas(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            train = ExperimentSet([resolve_record(h) for h in records], name="training")
            model = get_estimator(kind, **dict(settings)).fit(train)
            out = {"status": "ok", "model": model.to_dict(), "error": ""}
        except (
            IdentificationError,
            SimulationDivergedError,
            DataValidationError,
            OutOfRangeError,
        ) as exc:
            out = {"status": "fit-failed", "model": None, "error": _message(exc)}
        except Exception as exc:  # noqa: BLE001 - any other failure of a model is a result row, not a crash
            _reraise_interrupt(exc)
            tb = traceback.extract_tb(exc.__traceback__)
            where = f" (at {tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
            out = {"status": "fit-failed", "model": None, "error": _message(exc) + where}
    out["fit_time_s"] = time.perf_counter() - t0
    out["note"] = _notes(caught)
    return out


def simulate_task(model: Mapping[str, Any], record: Any, range_policy: str) -> dict[str, Any]:
    """Free-run simulation of one record by one saved model; return status, scores and timing.

    Returns
    -------
    dict
        ``status`` in ``ok``, ``diverged``, ``out-of-range``, ``sim-failed``; ``esr``, ``ssse``
        [N], ``nrmse``, ``fit_pct`` [%] (NaN unless ok), ``sim_time_s`` [s], ``note``, ``error``.
    """
    from mrdamper.models import model_from_dict

    nan = float("nan")
    out: dict[str, Any] = {
        "esr": nan,
        "ssse": nan,
        "nrmse": nan,
        "fit_pct": nan,
        "sim_time_s": nan,
        "error": "",
    }
    with single_threaded_blas(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            exp = resolve_record(record)
            fitted = model_from_dict(dict(model)).with_range_policy(range_policy)  # type: ignore[arg-type]
            res = fitted.simulate(exp)
            out["sim_time_s"] = res.elapsed
            try:
                s = res.scores
            except DataValidationError as exc:  # non-finite prediction returned without an error
                out.update(status="diverged", error=_message(exc))
            else:
                out.update(status="ok", esr=s.esr, ssse=s.ssse, nrmse=s.nrmse, fit_pct=s.fit)
        except SimulationDivergedError as exc:
            out.update(status="diverged", error=_message(exc))
        except OutOfRangeError as exc:
            out.update(status="out-of-range", error=_message(exc))
        except Exception as exc:  # noqa: BLE001 - any other failure of a model is a result row, not a crash
            _reraise_interrupt(exc)
            out.update(status="sim-failed", error=_message(exc))
    out["note"] = _notes(caught)
    return out
