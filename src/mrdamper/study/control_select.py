"""Which model kind for a controller: kinds ranked by their fidelity in the loop.

``select`` ranks kinds by their free-run error on left-out records; a controller needs the model
that predicts its loop. :func:`control_select` fits every kind once, on the records less a
held-out half of the *loop-like* records (those of the control extension,
:mod:`mrdamper.control.loop.doe_extension`: the loop's motions replayed with the loop's current and
with an APRBS current, metadata ``displacement`` beginning with :data:`LOOP_DISPLACEMENT`), and
scores it:

* **open loop, on the held-out loop-like records** (any data): the mean free-run ESR over them
  (``loop_esr``), and how many of them leave the model's training envelope (``loop_beyond``,
  ratio above ``1 +`` :data:`~mrdamper.models.envelope.ENVELOPE_TOLERANCE` in a dimension);
* **closed loop, against the true damper** (virtual-rig records, whose damper is known,
  :func:`~mrdamper.study.control_step.truth_damper`): each controller runs on ISO 8608 roads
  unseen by the extension (:data:`ROADS` at :data:`SPEEDS`) with the model as the damper and
  with the rig's damper (:func:`~mrdamper.control.loop.fidelity.closed_loop_fidelity`); the kind's
  score is the worst |error| [%] of :data:`RANK_METRICS` over the cells within the stroke the
  model was trained on (``closed_loop_worst_pct``; the cells beyond it,
  :func:`~mrdamper.control.loop.stroke_cells.flag_cells`, are counted apart and not scored).

The ranking is by ``closed_loop_worst_pct`` when the truth is known, else by ``loop_esr``; a kind
that cannot be fitted, or whose loop fails, keeps its row with the reason and is ranked last.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.control.loop.fidelity import closed_loop_fidelity
from mrdamper.control.loop.stroke_cells import flag_cells
from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, MrDamperError, interrupt_in_chain
from mrdamper.metrics import esr
from mrdamper.models.envelope import ENVELOPE_TOLERANCE, envelope_of, excursions
from mrdamper.study.control_step import truth_damper

__all__ = [
    "CONTROL_SELECT_COLUMNS",
    "LOOP_DISPLACEMENT",
    "RANK_METRICS",
    "ControlSelection",
    "control_select",
    "split_loop_records",
]

#: How the metadata ``displacement`` of a loop-like record begins (the control extension's
#: replays of a quarter car's damper travel, with the loop's current or an APRBS one).
LOOP_DISPLACEMENT = "quarter car"
#: ISO 8608 classes and speeds [m/s] of the closed-loop check, road length [s] and road seed.
ROADS: tuple[str, ...] = ("B", "C", "D")
SPEEDS: tuple[float, ...] = (10.0, 25.0)
DURATION = 10.0
SEED = 0
#: The loop metrics a kind is scored on (the mean current is reported by ``quartercar --plant``).
RANK_METRICS: tuple[str, ...] = ("a_w", "rms_acc", "rms_tyre_load", "rms_travel", "rms_tracking")
#: Columns of :attr:`ControlSelection.table`.
CONTROL_SELECT_COLUMNS: tuple[str, ...] = (
    "model",
    "rank",
    "closed_loop_worst_pct",
    "worst_at",
    "closed_loop_mean_pct",
    "cells_scored",
    "cells_outside_stroke",
    "loop_esr",
    "loop_beyond",
    "error",
)


@dataclass(frozen=True, eq=False)
class ControlSelection:
    """Kinds ranked by loop fidelity.

    Attributes
    ----------
    table : DataFrame
        :data:`CONTROL_SELECT_COLUMNS`, one row per kind, in rank order.
    truth : str or None
        The true damper of the closed-loop check (None: measured records, ranked on
        ``loop_esr``).
    held_out : list of str
        Names of the held-out loop-like records.
    recommended : str or None
        The first kind without an error.
    notes : list of str
        One-line notes.
    """

    table: pd.DataFrame
    truth: str | None
    held_out: list[str]
    recommended: str | None
    notes: list[str] = field(default_factory=list)


def _loop_like(e: Experiment) -> bool:
    return str(e.metadata.get("displacement", "")).startswith(LOOP_DISPLACEMENT)


def split_loop_records(
    records: Sequence[Experiment],
) -> tuple[list[Experiment], list[Experiment]]:
    """``(training, held_out)``: the loop-like records of every second loop run held out.

    The loop-like records (metadata ``displacement`` beginning with :data:`LOOP_DISPLACEMENT`)
    are grouped by loop run (their ``displacement``, in the order of the records' names); the
    second, fourth, ... runs are held out (both their records: the same motion never trains and
    scores a model). Every other record trains.

    Raises
    ------
    DataValidationError
        Fewer than two loop runs among ``records``.
    """
    loop = sorted(
        (e for e in records if _loop_like(e)),
        key=lambda e: e.name,
    )
    runs = list(dict.fromkeys(str(e.metadata.get("displacement", e.name)) for e in loop))
    if len(runs) < 2:
        raise DataValidationError(
            "data",
            "expected the loop-like records of at least two loop runs (records of the control "
            "extension, `mrdamper rig doe --extension control`, whose displacement is a "
            f"{LOOP_DISPLACEMENT}'s), got {len(runs)}",
        )
    held_runs = set(runs[1::2])
    held = [e for e in loop if str(e.metadata.get("displacement", e.name)) in held_runs]
    held_ids = {id(e) for e in held}
    return [e for e in records if id(e) not in held_ids], held


def _reason(exc: BaseException) -> str:
    if interrupt_in_chain(exc):
        raise KeyboardInterrupt from exc
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _open_loop(model: Any, held: Sequence[Experiment], source: str) -> tuple[float, int]:
    """Mean free-run ESR over ``held`` [-] and how many leave the model's training envelope."""
    errors = [esr(e.F, model.predict(e)) for e in held]
    trained = dict(getattr(model, "provenance", {}) or {}).get("envelope")
    beyond = 0
    if trained:
        for e in held:
            seen = envelope_of([e.x], [e.v], [np.asarray(e.electrical(source))], dt=[e.dt])  # type: ignore[arg-type]
            exc = excursions(trained, seen)
            beyond += (
                any(np.isfinite(v) and v > 1.0 + ENVELOPE_TOLERANCE for v in exc.values())
                or exc.get("switching") == np.inf
            )
    return float(np.mean(errors)), beyond


def _closed_loop(
    model: Any,
    truth: str,
    roads: Sequence[str],
    speeds: Sequence[float],
    duration: float,
    seed: int,
) -> dict[str, Any]:
    """The closed-loop scores of ``model`` against ``truth`` (a row's closed-loop columns)."""
    res = closed_loop_fidelity(
        model, truth, road_classes=roads, speeds=speeds, duration=duration, seed=seed
    )
    table = flag_cells(res.table(), res.runs_frame())
    scored = table[table["metric"].isin(RANK_METRICS) & ~table["outside_stroke"]]
    where = ""
    if scored.empty:  # every cell beyond the stroke: scored on all, and said so
        scored, where = table[table["metric"].isin(RANK_METRICS)], " (beyond the stroke)"
    err = scored["error_pct"].abs()  # NaN: a passive controller's tracking
    refused = [r for r in res.runs if r.get("refused")]
    cells = table.drop_duplicates(["controller", "road", "speed_m_s"])
    out: dict[str, Any] = {
        "cells_scored": int((~cells["outside_stroke"]).sum()),
        "cells_outside_stroke": int(cells["outside_stroke"].sum()),
    }
    if refused:
        out["error"] = f"{len(refused)} loop run(s) failed; the first: {refused[0]['refused']}"
        return out
    if err.notna().any():
        k = err.idxmax()
        r = scored.loc[k]
        out["closed_loop_worst_pct"] = float(err[k])
        out["worst_at"] = (
            f"{r['metric']}, {r['controller']} ISO {r['road']} @ {r['speed_m_s']:g} m/s{where}"
        )
        out["closed_loop_mean_pct"] = float(err.mean())
    return out


def control_select(
    records: Sequence[Experiment],
    kinds: Sequence[str],
    *,
    input: str = "i",
    settings: Mapping[str, Mapping[str, Any]] | None = None,
    plant: str | None = None,
    roads: Sequence[str] = ROADS,
    speeds: Sequence[float] = SPEEDS,
    duration: float = DURATION,
    seed: int = SEED,
) -> ControlSelection:
    """Rank ``kinds`` by their fidelity in the loop (see the module docstring).

    Parameters
    ----------
    records : sequence of Experiment
        The damper's records, loop-like ones among them.
    kinds : sequence of str
        Model kinds to compare.
    input : {"i", "voltage"}
        The electrical input.
    settings : mapping, optional
        Estimator settings per kind.
    plant : str, optional
        The true damper of virtual-rig records when it is not the one they name
        (:func:`~mrdamper.study.control_step.truth_damper`).
    roads, speeds, duration, seed
        ISO 8608 classes, speeds [m/s], road length [s] and road seed of the closed-loop check.

    Returns
    -------
    ControlSelection
    """
    from mrdamper.models.registry import get_estimator

    train, held = split_loop_records(records)
    truth = truth_damper(records, plant)
    settings = settings or {}
    rows = []
    for kind in kinds:
        row: dict[str, Any] = {"model": kind, "error": ""}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = get_estimator(kind, input=input, **dict(settings.get(kind, {}))).fit(train)
                row["loop_esr"], row["loop_beyond"] = _open_loop(model, held, input)
                if truth is not None:
                    row.update(_closed_loop(model, truth, roads, speeds, duration, seed))
        except (MrDamperError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            row["error"] = _reason(exc)
        rows.append(row)
    table = pd.DataFrame(rows).reindex(columns=CONTROL_SELECT_COLUMNS)
    table["error"] = table["error"].fillna("")
    key = "closed_loop_worst_pct" if truth is not None else "loop_esr"
    ok = (table["error"] == "") & table[key].notna()
    table = pd.concat([table[ok].sort_values(key, kind="stable"), table[~ok]], ignore_index=True)
    table["rank"] = [
        i + 1 if good else np.nan
        for i, good in enumerate(table["error"].eq("") & table[key].notna())
    ]
    notes = []
    if truth is None:
        notes.append(
            "the records' damper is not known (measured data): kinds ranked by their open-loop "
            "error on the held-out loop-like records"
        )
    beyond = table[table["loop_beyond"].fillna(0) > 0]
    if len(beyond):
        notes.append(
            "held-out loop-like records outside the training envelope: "
            + ", ".join(
                f"{r.model} {int(r.loop_beyond)} of {len(held)}" for r in beyond.itertuples()
            )
        )
    recommended = str(table.loc[0, "model"]) if ok.any() else None
    return ControlSelection(table, truth, [e.name for e in held], recommended, notes)
