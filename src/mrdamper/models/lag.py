"""The drive lag identified on the training records: one step shared by every family with ``eta``.

When the electrical input is a command to a drive (``input="voltage"``), the coil current follows
the command through the drive's dynamics, modelled as a first-order lag
``d rho/dt = -eta (rho - voltage)``. The families with an ``eta`` setting (LPV, LTI, P-15,
SP-1..SP-4, tanh, Bouc-Wen, Dahl, LuGre) take ``eta="auto"`` by default, and
:meth:`mrdamper.models.Estimator.fit` then calls :func:`fit_with_lag`:

* input ``"i"`` (the current is measured), or a voltage held within every record (a lag of a
  constant is the constant; each record spans at most
  :data:`~mrdamper.models.envelope.SWITCH_FRACTION` of the training range, so sensor noise on a
  held voltage is not a command that moves): no lag (``eta=None``), the fit is the plain fit;
* otherwise every training record is cut in time, the first :data:`INNER_FRACTION` fits and the
  rest validates; the family is fitted on the fit parts with candidates of :data:`ETA_GRID` and
  scored in free run on the validation parts (mean ESR, eq. 24, with ``range_policy="clip"``): the
  search starts at 200 1/s and its two neighbours, walks along the grid while the validation
  error falls, then tries the geometric midpoints on either side of the best grid point (5-8
  fits on the inner split); the candidate with the lowest validation ESR is fitted on the whole
  training records. A family that can start a fit from given parameters (the one-state
  hysteresis families: ``lag_screening``) fits the first candidate from its own starts and every
  further one from the optimum of the nearest rate already fitted, with one start (neighbouring
  rates differ by little more than the timing of the input), and the final fit on the whole
  training records from the chosen candidate's optimum (a fit on part of the same training
  records: no left-out data is seen). On a synthetic Bouc-Wen record and on the Dyke record
  (four families) it chose the rate that fitting every candidate from scratch chooses, for about
  a quarter of the evaluations (``tests/models/test_lag.py``; ``docs/performance.md``, "The
  drive-lag search of the hysteresis families").

``eta="identify"`` identifies the lag the same way whenever the electrical input switches within
a record, **measured current included**: the damper's force follows the coil current through the
build-up of the field (magnetic circuit, eddy currents, the fluid's response), and the virtual
rig's reference dampers have such a lag (``eta = 100 1/s``). A model meant for a switching
controller needs it (``docs/results.md``, "Every gain of the sweep"); it is not the default for a
measured current, whose tables were measured without it. For a measured current *no lag* is one
more candidate, scored on the same split: a lag is kept only where it predicts the validation
parts better than none. A family that leaves settings open (the LPV hysteretic input's stroke
and blend) chooses them without the lag first, and the lag's candidates are then fitted with
those settings held (:func:`settings_chosen_without_lag`).

The choice, every candidate's validation ESR and the time it took are in the model's provenance
(``drive_lag``). The Spencer family identifies its own filter rate with its other parameters
(output error), so it does not use this step. A fixed number (or None) skips it.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError
from mrdamper.models.envelope import SWITCH_FRACTION
from mrdamper.models.levels import held_within_records
from mrdamper.progress import report

__all__ = [
    "AUTO",
    "ETA_GRID",
    "IDENTIFY",
    "INNER_FRACTION",
    "LAG_SETTINGS",
    "check_lag",
    "fit_with_lag",
    "lag_applies",
    "lag_setting",
    "resolved",
    "settings_chosen_without_lag",
]

#: The setting that asks for the drive lag to be identified when the input is a voltage command.
AUTO = "auto"
#: The setting that asks for the lag to be identified whenever the electrical input switches
#: within a record, current or voltage.
IDENTIFY = "identify"
#: The settings of ``eta`` that identify the lag on the training records.
LAG_SETTINGS: tuple[str, ...] = (AUTO, IDENTIFY)
#: Candidate drive-lag rates [1/s] (factor 2 apart, time constants 0.6-40 ms).
ETA_GRID: tuple[float, ...] = (25.0, 50.0, 100.0, 200.0, 400.0, 800.0, 1600.0)
#: Index in :data:`ETA_GRID` where the search starts.
START = 3
#: Share of each training record (in time) that fits the candidates; the rest validates [-].
INNER_FRACTION = 0.8


def check_lag(value: Any) -> None:
    """Refuse an ``eta`` setting other than ``"auto"``, ``"identify"``, None or a positive finite
    rate [1/s].

    Parameters
    ----------
    value : object
        The setting given.
    """
    if value is None or (isinstance(value, str) and value in LAG_SETTINGS):
        return
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not (ok and math.isfinite(float(value)) and float(value) > 0):
        raise DataValidationError(
            "eta",
            f"expected 'auto', 'identify', None or a positive drive-lag rate [1/s], got {value!r}",
        )


def lag_setting(text: str) -> str | float:
    """An ``eta`` setting read from text (a command-line value): ``"auto"``, ``"identify"`` or a
    rate [1/s], checked as :func:`check_lag` does.

    Parameters
    ----------
    text : str
        The value as written.
    """
    value: str | float = text if text in LAG_SETTINGS else _rate(text)
    check_lag(value)
    return value


def _rate(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise DataValidationError(
            "eta", f"expected 'auto', 'identify' or a drive-lag rate [1/s], got {text!r}"
        ) from None


def resolved(eta: float | str | None) -> float | None:
    """The drive-lag rate a family's identification step uses [1/s] (None: no lag).

    :meth:`~mrdamper.models.Estimator.fit` resolves ``"auto"`` before the family's step runs, so
    the step never sees it.

    Parameters
    ----------
    eta : float, "auto" or None
        The setting.
    """
    if isinstance(eta, str):
        raise TypeError(f"eta: {eta!r} reached the identification step unresolved")
    return None if eta is None else float(eta)


def lag_applies(
    records: Iterable[Experiment], source: ElectricalSource, setting: str = AUTO
) -> bool:
    """True when the lag is to be identified: the electrical input switches within at least one
    record and it is a voltage command (``setting="auto"``) or any input (``"identify"``).

    A record whose input spans at most :data:`~mrdamper.models.envelope.SWITCH_FRACTION` of the
    training range holds it (noise on a held input is not a switch), as in
    :func:`~mrdamper.models.levels.held_within_records`.

    Parameters
    ----------
    records : iterable of Experiment
        Training records.
    source : {"i", "voltage"}
        Electrical input channel of the estimator.
    setting : {"auto", "identify"}
        The estimator's ``eta``.
    """
    if source != "voltage" and setting != IDENTIFY:
        return False
    extremes = []
    for e in records:
        u = np.asarray(e.electrical(source), dtype=float)
        extremes.append((float(np.min(u)), float(np.max(u))))
    return bool(extremes) and not held_within_records(extremes, SWITCH_FRACTION)


def settings_chosen_without_lag(est: Any) -> bool:
    """True when a family's open settings (the LPV hysteretic input's stroke and blend) are
    chosen with no lag, before the lag is identified with them held: a measured current, for
    which no lag is itself a candidate of :func:`fit_with_lag`.

    For a voltage command every candidate setting is fitted with its own lag search (the drive
    always has a lag, and the settings that go with it differ).

    Parameters
    ----------
    est : mrdamper.models.Estimator
        A family with an ``eta`` setting.
    """
    return getattr(est, "input", "i") != "voltage" and getattr(est, "eta", None) in LAG_SETTINGS


def _split(records: ExperimentSet) -> tuple[list[Experiment], list[Experiment]]:
    fit, val = [], []
    for e in records:
        cut = round(INNER_FRACTION * e.n)
        fit.append(e.slice(0, cut, name=f"{e.name}:lag-fit"))
        val.append(e.slice(cut, None, name=f"{e.name}:lag-val"))
    return fit, val


def _setting(rate: float) -> float | None:
    """The ``eta`` setting of a candidate rate [1/s]: None (no lag) for an infinite rate."""
    return None if math.isinf(rate) else float(rate)


def _validation_esr(
    est: Any,
    eta: float | None,
    parts: tuple[list[Experiment], list[Experiment]],
    options: Mapping[str, Any],
    weights: Sequence[float] | None,
) -> tuple[float, Any]:
    """Mean validation ESR of the family fitted with ``eta`` (None: no lag) on the fit parts
    (inf on failure), and the fitted model (None on failure)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = dataclasses.replace(est, eta=eta).fit(parts[0], **options)
            model = model.with_range_policy("clip")
            esr = [model.score(e).esr for e in parts[1]]
    except (ValueError, RuntimeError, ArithmeticError):
        return math.inf, None
    value = float(np.average(esr, weights=weights))
    return (value, model) if math.isfinite(value) else (math.inf, None)


def _nearest(fitted: Mapping[float, Any], eta: float) -> Any:
    """The fitted candidate whose finite rate is nearest ``eta`` in log scale (None if none)."""
    finite = [c for c in fitted if math.isfinite(c)]
    if not finite or math.isinf(eta):
        return None
    return fitted[min(finite, key=lambda c: abs(math.log(c / eta)))]


def fit_with_lag(
    est: Any, data: Experiment | Iterable[Experiment], options: Mapping[str, Any]
) -> Any:
    """Fit ``est`` (whose ``eta`` is ``"auto"``) with its drive lag identified (module docstring).

    Parameters
    ----------
    est : mrdamper.models.Estimator
        A family with an ``eta`` setting, set to ``"auto"`` or ``"identify"``.
    data : Experiment or iterable of Experiment
        Training records.
    options : mapping
        Per-fit options of the family (passed to every fit; ``record_weights`` also weights the
        validation ESR).

    Returns
    -------
    mrdamper.models.FittedModel
        The model fitted on every training record with the chosen lag.
    """
    records = as_experiment_set(data, name="training")
    source: ElectricalSource = getattr(est, "input", "i")
    if not lag_applies(records, source, est.eta):
        return dataclasses.replace(est, eta=None).fit(records, **options)
    t0 = time.perf_counter()
    parts = _split(records)
    weights = options.get("record_weights")
    # candidate rates [1/s]; an infinite rate is no lag, a candidate for a measured current
    # (the case whose open settings were chosen without the lag)
    scores: dict[float, float] = {}
    no_lag = settings_chosen_without_lag(est)

    # a family that can start a candidate's fit from a neighbour's (``lag_screening``) fits the
    # first finite rate from its own starts and every further one from the nearest fitted rate
    screening = getattr(est, "lag_screening", None)
    fitted: dict[float, Any] = {}

    def trial(eta: float) -> None:
        report("identifying the lag: candidate", len(scores) + 1, len(ETA_GRID) + 2 + no_lag)
        neighbour = _nearest(fitted, eta)
        candidate = est if screening is None or neighbour is None else screening(neighbour)
        scores[eta], model = _validation_esr(candidate, _setting(eta), parts, options, weights)
        if model is not None:
            fitted[eta] = model

    if no_lag:
        trial(math.inf)
    k = START
    for eta in (ETA_GRID[k], ETA_GRID[k - 1], ETA_GRID[k + 1]):
        trial(eta)
    # walk down the grid while the validation error falls (it is one-dimensional and, on the
    # records measured, unimodal in log eta), then try the geometric midpoints around the best
    step = -1 if scores[ETA_GRID[k - 1]] < scores[ETA_GRID[k + 1]] else 1
    while scores[ETA_GRID[k + step]] < scores[ETA_GRID[k]]:
        k += step
        if not 0 <= k + step < len(ETA_GRID):
            break
        trial(ETA_GRID[k + step])
    best = ETA_GRID[k]
    for j in (k - 1, k + 1):
        if 0 <= j < len(ETA_GRID):
            trial(float(round(math.sqrt(best * ETA_GRID[j]), 1)))
    chosen = min(scores, key=lambda c: scores[c])
    if not math.isfinite(scores[chosen]):
        raise DataValidationError(
            "eta", f"{est.kind}: no drive-lag candidate could be fitted on the inner split"
        )
    selection_s = time.perf_counter() - t0
    final = est if screening is None or chosen not in fitted else screening(fitted[chosen])
    model = dataclasses.replace(final, eta=_setting(chosen)).fit(records, **options)
    prov = dict(model.provenance)
    prov["drive_lag"] = {
        "eta": _setting(chosen),
        "how": (
            f"chosen on an inner split of the training records (first {INNER_FRACTION:.0%} of "
            "each fits, the rest validates; mean free-run ESR"
            + ("; no lag (None) is a candidate for a measured current)" if no_lag else ")")
        ),
        "candidates": [_setting(c) for c in scores],
        "validation_esr": [float(v) for v in scores.values()],
    }
    prov["lag_selection_s"] = selection_s
    prov["elapsed_s"] = float(prov.get("elapsed_s", 0.0)) + selection_s
    return dataclasses.replace(model, provenance=prov)
