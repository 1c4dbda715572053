"""Stress tests of a fitted model: synthetic motions beyond and inside its training envelope.

:func:`stress_test` runs a fitted model in free run (its ``predict``, which equals its per-sample
step) on motions built with :mod:`mrdamper.signals` from the model's training envelope
(``provenance["envelope"]``, :mod:`mrdamper.models.envelope`):

*Beyond the envelope* (``group="beyond"``). The base motion is the sine that spans the training
displacement range with the training's largest velocity (amplitude ``A0`` = half the range,
frequency ``f0 = v_max / (2 pi A0)``), ramped in from rest over one cycle. It is run with the
amplitude times :data:`AMPLITUDE_FACTOR` and with the frequency times :data:`FREQUENCY_FACTOR`,
each at both ends of the electrical input range (the range holding 99 % of the training input
samples, ``e_core_range``, so that a drive's switching spikes are not taken for levels the damper
was run at; models saved without it use the full range). Every run must be

* finite (no divergence error, no NaN),
* bounded: ``max |F| <= BOUND_FACTOR * (velocity ratio) * f_max`` (``f_max`` the largest training
  force),
* dissipative on average: mean ``F v`` over the last :data:`CYCLES_CHECKED` cycles > 0,
* not growing: the force peak of the last cycle at most :data:`GROWTH_FACTOR` times that of the
  second.

*New motions inside the envelope* (``group="inside"``): training records played backwards (the
one with the largest force, and the one with the largest displacement range), and a band-limited
random motion (an ISO 8608 road profile, :func:`mrdamper.signals.road_profile`, scaled to the
training displacement range and slowed down until its velocity stays within the training's) with an
APRBS electrical input over the same range, started from rest. Every run must be finite and
free of bursts: ``max |F| <= BURST_FACTOR * f_max``.

A model that fails any check is not recommended by :func:`mrdamper.study.cross_validate`; the
first failure is its reason.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError

__all__ = [
    "AMPLITUDE_FACTOR",
    "BOUND_FACTOR",
    "BURST_FACTOR",
    "FREQUENCY_FACTOR",
    "STRESS_COLUMNS",
    "StressResult",
    "stress_motions",
    "stress_test",
]

#: Amplitude of the beyond-envelope sine as a multiple of the training half-range [-].
AMPLITUDE_FACTOR = 1.5
#: Frequency of the beyond-envelope sine as a multiple of the base frequency [-].
FREQUENCY_FACTOR = 2.0
#: Beyond the envelope, ``max |F|`` may reach this many times ``f_max`` times the velocity ratio.
BOUND_FACTOR = 3.0
#: Inside the envelope, ``max |F|`` above this many times ``f_max`` is a burst [-].
BURST_FACTOR = 1.5
#: The last cycle's force peak above this many times the second cycle's is growth [-].
GROWTH_FACTOR = 1.5
#: Cycles of each beyond-envelope sine (the first ramps in from rest) and cycles checked [-].
CYCLES = 6
CYCLES_CHECKED = 2
#: Length of the random motion [s] (at least 20 base periods).
RANDOM_SECONDS = 8.0

#: Columns of :attr:`StressResult.table`.
STRESS_COLUMNS: tuple[str, ...] = (
    "motion",
    "group",
    "peak_N",
    "limit_N",
    "mean_power_W",
    "ok",
    "why",
)


@dataclass(frozen=True)
class StressResult:
    """Stress-test outcome of one model.

    Attributes
    ----------
    table : DataFrame
        One row per motion (:data:`STRESS_COLUMNS`): force peak and its limit [N], mean ``F v``
        over the checked cycles [W] (NaN inside the envelope), ``ok`` and the reason it failed.
    passed : bool
        Every motion passed.
    reason : str
        ``"ok"`` or the first failure in one phrase.
    """

    table: pd.DataFrame
    passed: bool
    reason: str


def _envelope(model: Any) -> dict[str, Any]:
    env = getattr(model, "envelope", None)
    if not env or "f_max" not in env:
        raise DataValidationError(
            "model", f"the {model.kind} model carries no training envelope with f_max to test in"
        )
    return dict(env)


def _rate(model: Any) -> float:
    dts = dict(model.provenance or {}).get("record_dt") or [1e-3]
    return float(1.0 / min(float(d) for d in dts))


def _record(
    name: str, fs: float, x: np.ndarray, e: np.ndarray, source: str, meta: dict[str, Any]
) -> Experiment:
    t = np.arange(x.size) / fs
    v = np.gradient(x, 1.0 / fs)
    return Experiment(
        t=t, x=x, v=v, F=np.zeros_like(x), name=name, metadata=meta, **_channel(source, e)
    )


def _channel(source: str, e: np.ndarray) -> dict[str, Any]:
    """The electrical channel keyword of :class:`Experiment` (``i`` or ``voltage``)."""
    return {"i": e, "voltage": None} if source == "i" else {"i": None, "voltage": e}


def _sine(fs: float, amp: float, freq: float, mid: float) -> np.ndarray:
    from mrdamper.signals import sine

    x = sine(fs, CYCLES / freq, amplitude=amp, frequency=freq)
    per = max(round(fs / freq), 1)
    ramp = np.clip(np.arange(x.size) / per, 0.0, 1.0)
    return mid + x * (0.5 - 0.5 * np.cos(np.pi * ramp))


def _random_motion(fs: float, env: dict[str, Any], seed: int) -> np.ndarray:
    from mrdamper.signals import road_profile

    lo, hi = (float(b) for b in env["x_range"])
    span, mid = hi - lo, 0.5 * (hi + lo)
    f_top = float(env.get("f_band") or 0.0) or 5.0
    f_top = min(f_top, 0.45 * fs)
    x = np.zeros(1)
    for _ in range(4):  # lower the band until the velocity stays within the training's
        x = road_profile(
            fs,
            RANDOM_SECONDS,
            seed=seed,
            max_frequency=f_top,
            min_frequency=min(0.2, 0.5 * f_top),
            stroke=span,
            fill=0.9,
        )
        vmax = float(np.max(np.abs(np.gradient(x, 1.0 / fs))))
        if vmax <= 0.9 * float(env["v_max"]) or vmax == 0.0:
            break
        f_top *= 0.9 * float(env["v_max"]) / vmax
    return mid + x


def stress_motions(
    model: Any, training: Iterable[Experiment] = (), *, seed: int = 0
) -> list[Experiment]:
    """The synthetic records of :func:`stress_test` (force channel zero; metadata ``group``).

    Parameters
    ----------
    model : FittedModel
        A fitted model carrying its training envelope.
    training : iterable of Experiment
        Its training records (for the motions played backwards; none: those are left out).
    seed : int
        Seed of the random motion and its electrical input.
    """
    from mrdamper.signals import aprbs

    env = _envelope(model)
    fs = _rate(model)
    source = model.input
    lo, hi = (float(b) for b in env["x_range"])
    a0, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
    f0 = float(env["v_max"]) / (2 * np.pi * a0) if a0 > 0 else 1.0
    e_lo, e_hi = (float(b) for b in env.get("e_core_range", env["e_range"]))
    out: list[Experiment] = []
    for what, amp, freq in (
        (f"amplitude x{AMPLITUDE_FACTOR:g}", AMPLITUDE_FACTOR * a0, f0),
        (f"frequency x{FREQUENCY_FACTOR:g}", a0, FREQUENCY_FACTOR * f0),
    ):
        if freq >= 0.45 * fs:
            continue
        x = _sine(fs, amp, freq, mid)
        levels = (e_lo,) if e_hi == e_lo else (e_lo, e_hi)
        for lev in levels:
            name = f"{what}, {source} {lev:.3g}"
            meta = {"group": "beyond", "frequency": freq}
            out.append(_record(name, fs, x, np.full(x.size, lev), source, meta))
    recs = list(training)
    picks: dict[str, Experiment] = {}
    if recs:
        picks["largest force"] = max(recs, key=lambda r: float(np.max(np.abs(r.F))))
        picks["largest range"] = max(recs, key=lambda r: float(np.ptp(r.x)))
    seen: set[str] = set()
    for label, r in picks.items():
        if r.name in seen:
            continue
        seen.add(r.name)
        e = np.asarray(r.electrical(source))[::-1].copy()
        rev = Experiment(
            t=r.t,
            x=r.x[::-1].copy(),
            v=-r.v[::-1],
            F=np.zeros(r.n),
            name=f"{r.name} backwards ({label})",
            metadata={"group": "inside"},
            **_channel(source, e),
        )
        out.append(rev)
    x = _random_motion(fs, env, seed)
    if e_hi > e_lo:
        e = aprbs(fs, RANDOM_SECONDS, low=e_lo, high=e_hi, min_hold=0.5, seed=seed + 1)[: x.size]
    else:
        e = np.full(x.size, e_lo)
    out.append(_record("band-limited random, from rest", fs, x, e, source, {"group": "inside"}))
    return out


def _check(model: Any, rec: Experiment, env: dict[str, Any], fs: float) -> dict[str, Any]:
    group = rec.metadata["group"]
    f_max = float(env["f_max"])
    row: dict[str, Any] = {"motion": rec.name, "group": group, "mean_power_W": np.nan}
    v_ratio = max(1.0, float(np.max(np.abs(rec.v))) / float(env["v_max"]))
    limit = BOUND_FACTOR * v_ratio * f_max if group == "beyond" else BURST_FACTOR * f_max
    row["limit_N"] = limit
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            F = np.asarray(model.with_range_policy("clip").predict(rec), dtype=float)
    except Exception as exc:  # noqa: BLE001 - a failing run is the finding
        row.update(peak_N=np.nan, ok=False, why=f"{type(exc).__name__}: {str(exc)[:100]}")
        return row
    if not np.all(np.isfinite(F)):
        row.update(peak_N=np.nan, ok=False, why="non-finite force")
        return row
    peak = float(np.max(np.abs(F)))
    row["peak_N"] = peak
    why = ""
    if peak > limit:
        word = "unbounded" if group == "beyond" else "burst"
        why = f"{word}: peak {peak:.4g} N = {peak / f_max:.2f} x the largest training force"
    if group == "beyond" and not why:
        freq = float(rec.metadata["frequency"])
        per = max(round(fs / freq), 1)
        tail = slice(rec.n - CYCLES_CHECKED * per, rec.n)
        power = float(np.mean(F[tail] * rec.v[tail]))
        row["mean_power_W"] = power
        p2 = float(np.max(np.abs(F[per : 2 * per]))) if rec.n >= 2 * per else peak
        p_last = float(np.max(np.abs(F[rec.n - per :])))
        if power <= 0.0:
            why = f"not dissipative: mean F v {power:.3g} W over the last {CYCLES_CHECKED} cycles"
        elif p_last > GROWTH_FACTOR * p2 + 1e-9 * f_max:
            why = f"growing: last cycle's peak {p_last / max(p2, 1e-300):.2f} x the second's"
    row.update(ok=not why, why=why)
    return row


def stress_test(model: Any, training: Iterable[Experiment] = (), *, seed: int = 0) -> StressResult:
    """Run ``model`` on :func:`stress_motions` and check each run (module docstring).

    Parameters
    ----------
    model : FittedModel
        A fitted model carrying its training envelope (``provenance["envelope"]``).
    training : iterable of Experiment
        Its training records (for the motions played backwards).
    seed : int
        Seed of the random motion.

    Returns
    -------
    StressResult

    Raises
    ------
    DataValidationError
        The model carries no training envelope.
    """
    env = _envelope(model)
    fs = _rate(model)
    rows = [_check(model, rec, env, fs) for rec in stress_motions(model, training, seed=seed)]
    table = pd.DataFrame(rows, columns=list(STRESS_COLUMNS))
    bad = table[~table["ok"].astype(bool)]
    if bad.empty:
        return StressResult(table, True, "ok")
    first = bad.iloc[0]
    return StressResult(table, False, f"{first['why']} ({first['motion']})")
