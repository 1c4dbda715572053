"""Bounded-cost identification on long campaigns: evenly spread training windows.

Nonlinear output-error fits (Spencer, P-15, the refinement steps of LPV and NARX) cost several
free runs of the whole training set per iteration and, for some, a Jacobian as tall as the data.
Above :data:`WINDOW_THRESHOLD` samples in all, those steps run on a fixed budget of
:data:`WINDOW_BUDGET` samples: windows of :data:`WINDOW_SECONDS` spread evenly over every record
(deterministic, no random draw; each window keeps its own start like a separate record). The
identified model is then checked on the full data (free-run cost or ESR of every record), and the
check is reported in the model's provenance. Below the threshold nothing changes: the fit sees
every sample, exactly as before.

The threshold (400 000 samples: 6.7 minutes at 1 kHz) is three times the largest shared
real-data training set (the 30 Quiroz records hold 133 000 samples, the Dyke record 64 600) and
above the full Table II demo (its largest training set is 90 000 samples), so their results do
not depend on this module. The costliest fits use a smaller budget (Spencer 120 000 samples,
P-15 200 000), passed by their estimators.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from mrdamper.data import Experiment, ExperimentSet

__all__ = [
    "SEGMENT_SAMPLES",
    "WINDOW_BUDGET",
    "WINDOW_BUDGET_LPV",
    "WINDOW_BUDGET_P15",
    "WINDOW_BUDGET_SPENCER",
    "WINDOW_SECONDS",
    "WINDOW_SECONDS_LPV",
    "WINDOW_THRESHOLD",
    "LazyRecords",
    "RecordList",
    "chunked_qr",
    "distinct_levels",
    "extrema",
    "fold_qr",
    "full_data_esr",
    "input_range",
    "input_range_of",
    "lpv_gram_records",
    "lpv_qr_factor",
    "lpv_qr_records",
    "narx_windows",
    "plan_windows",
    "split_long",
    "strided",
    "window_arrays",
    "window_records",
    "window_set",
]

#: Longest training record identified in one piece [samples] (about 70 minutes at 1 kHz); a
#: longer one is identified as consecutive segments (:func:`split_long`).
SEGMENT_SAMPLES = 1 << 22
#: Total training samples above which the expensive steps run on windows [samples].
WINDOW_THRESHOLD = 400_000
#: Samples the windows hold in all [samples].
WINDOW_BUDGET = 300_000
#: Budgets of the costliest fits (Spencer, P-15) [samples].
WINDOW_BUDGET_SPENCER = 120_000
WINDOW_BUDGET_P15 = 200_000
#: Budget and window length of the LPV / LTI output-error refinement [samples], [s].
WINDOW_BUDGET_LPV = 900_000
WINDOW_SECONDS_LPV = 60.0
#: Length of one window [s] (at least 2000 samples whatever the rate).
WINDOW_SECONDS = 20.0


def split_long(
    exps: ExperimentSet, max_samples: int | None = None
) -> tuple[ExperimentSet, tuple[int, ...]]:
    """Cut every record longer than ``max_samples`` (default :data:`SEGMENT_SAMPLES`) into
    consecutive segments of equal length (views: no copy).

    Every identification step works record by record, and its work arrays (scheduling and input
    signals, states, free-run outputs, sensitivities) are as long as the record: a 10 h record
    held in one file would need several times its own size. As segments, the work arrays are
    bounded by ``max_samples`` whatever the record length. A segment is a record of its own to
    the fit: its free run starts at rest and the first samples of its regression have no past
    (``n_m`` samples of ``max_samples``).

    Parameters
    ----------
    exps : ExperimentSet
        Training records.
    max_samples : int, optional
        Longest piece [samples].

    Returns
    -------
    segments : ExperimentSet
        ``exps`` itself when no record is longer; otherwise the records with the long ones
        replaced by their segments, named ``"<name> [k/K]"``.
    owners : tuple of int
        For every segment, the index of its record in ``exps``.
    """
    cap = SEGMENT_SAMPLES if max_samples is None else int(max_samples)
    if all(e.n <= cap for e in exps):
        return exps, tuple(range(len(exps)))
    out: list[Experiment] = []
    owners: list[int] = []
    for k, e in enumerate(exps):
        parts = -(-e.n // cap)
        if parts == 1:
            out.append(e)
            owners.append(k)
            continue
        bounds = np.linspace(0, e.n, parts + 1).round().astype(np.int64)
        for j in range(parts):
            seg = e.slice(int(bounds[j]), int(bounds[j + 1]), name=f"{e.name} [{j + 1}/{parts}]")
            out.append(seg)
            owners.append(k)
    return ExperimentSet(out, name=exps.name), tuple(owners)


def plan_windows(
    lengths: Sequence[int],
    fs: float,
    *,
    threshold: int | None = None,
    budget: int | None = None,
    seconds: float | None = None,
) -> list[tuple[int, int, int]] | None:
    """Windows ``(record, start, stop)`` spread evenly over records of ``lengths`` samples.

    Parameters
    ----------
    lengths : sequence of int
        Samples per record.
    fs : float
        Sampling rate [Hz] (sets the window length in samples).
    threshold, budget : int, optional
        Total samples above which windows are used; samples the windows hold in all (default
        :data:`WINDOW_THRESHOLD`, :data:`WINDOW_BUDGET`).
    seconds : float, optional
        Window length [s] (default :data:`WINDOW_SECONDS`).

    Returns
    -------
    list of (int, int, int) or None
        None when the records hold at most ``threshold`` samples (use everything). Otherwise
        each record gets windows in proportion to its length (at least one), their starts
        evenly spaced over the record.
    """
    threshold = WINDOW_THRESHOLD if threshold is None else threshold
    budget = WINDOW_BUDGET if budget is None else budget
    seconds = WINDOW_SECONDS if seconds is None else seconds
    total = int(sum(lengths))
    if total <= threshold:
        return None
    win = max(round(seconds * fs), 2000)
    n_win = max(1, budget // win)
    out: list[tuple[int, int, int]] = []
    for r, n in enumerate(lengths):
        n = int(n)
        k = max(1, round(n_win * n / total))
        w = min(win, n)
        k = min(k, max(1, n // w))
        starts = (
            np.linspace(0, n - w, k).round().astype(np.int64) if k > 1 else np.array([(n - w) // 2])
        )
        out.extend((r, int(s), int(s) + w) for s in starts)
    return out


def window_set(exps: ExperimentSet, **kwargs: Any) -> tuple[ExperimentSet, dict[str, Any] | None]:
    """The training windows of ``exps`` as records (``exps`` itself below the threshold).

    Returns the set to fit on and a provenance entry (None when every sample is used).
    """
    fs = min(e.fs for e in exps)
    plan = plan_windows([e.n for e in exps], fs, **kwargs)
    if plan is None:
        return exps, None
    wins = [exps[r].slice(a, b, name=f"{exps[r].name}[{a}:{b}]") for r, a, b in plan]
    return ExperimentSet(wins, name="windows"), _info(plan, sum(e.n for e in exps))


def window_arrays(
    arrays: Sequence[Sequence[np.ndarray]], fs: float, **kwargs: Any
) -> tuple[list[list[np.ndarray]] | None, list[int], dict[str, Any] | None]:
    """Window per-record arrays: ``arrays[c][r]`` is channel ``c`` of record ``r``.

    Returns the windowed channels (None below the threshold), the parent record of each window
    and the provenance entry. Windows are views (no copy) of the given arrays.
    """
    lengths = [a.shape[-1] for a in arrays[0]]
    plan = plan_windows(lengths, fs, **kwargs)
    if plan is None:
        return None, list(range(len(lengths))), None
    chans = [[ch[r][..., a:b] for r, a, b in plan] for ch in arrays]
    return chans, [r for r, _, _ in plan], _info(plan, sum(lengths))


def window_records(rec: Any, fs: float, **kwargs: Any) -> tuple[Any, dict[str, Any] | None]:
    """Windows of an LPV ``Records`` (fields ``F, u, rho``, optionally ``x``, per record, and
    ``weights``); ``rec``
    itself below the threshold. Each window keeps its parent record's weight.

    Defaults: :data:`WINDOW_BUDGET_LPV` samples in windows of :data:`WINDOW_SECONDS_LPV` (on a 1 h
    rig record, 300 000 samples in 20 s windows gave a 17 % higher test ESR than every sample;
    900 000 in 60 s windows 0.6 %, at a quarter of the time)."""
    kwargs.setdefault("budget", WINDOW_BUDGET_LPV)
    kwargs.setdefault("seconds", WINDOW_SECONDS_LPV)
    x = getattr(rec, "x", None)
    channels = [rec.F, rec.u, rec.rho] + ([x] if x is not None else [])
    chans, parent, info = window_arrays(channels, fs, **kwargs)
    if chans is None:
        return rec, None
    F, u, rho = chans[:3]
    return dataclasses.replace(
        rec,
        F=F,
        u=u,
        rho=rho,
        **({"x": chans[3]} if x is not None else {}),
        weights=np.asarray(rec.weights)[parent],
    ), info


def _info(plan: list[tuple[int, int, int]], total: int) -> dict[str, Any]:
    used = sum(b - a for _, a, b in plan)
    return {
        "windows": len(plan),
        "window_samples": int(plan[0][2] - plan[0][1]),
        "samples_used": int(used),
        "samples_total": int(total),
        "threshold": int(WINDOW_THRESHOLD),
        "note": (
            "the output-error step ran on evenly spread windows; full_data_check is on every sample"
        ),
    }


def extrema(a: np.ndarray) -> np.ndarray:
    """``[min, max]`` of ``a`` (what a range computation needs of a long record)."""
    return np.array([np.min(a), np.max(a)])


def input_range(exps: Sequence[Experiment], source: Any) -> tuple[float, float]:
    """Range of the electrical input ``source`` over every record."""
    ext = np.array([extrema(e.electrical(source)) for e in exps])
    return float(ext[:, 0].min()), float(ext[:, 1].max())


def strided(
    channels: Sequence[Sequence[np.ndarray]], threshold: int | None = None
) -> list[list[np.ndarray]]:
    """Every k-th sample of each record (views, no copy) so at most about ``threshold`` samples
    remain in all (default :data:`WINDOW_THRESHOLD`); the arrays themselves below it.

    For static fits (the F-v zone regression of the LPV laws), where sample order does not matter
    and an even thinning keeps every record and level represented.
    """
    threshold = WINDOW_THRESHOLD if threshold is None else threshold
    total = sum(a.size for a in channels[0])
    if total <= threshold:
        return [list(ch) for ch in channels]
    k = -(-total // threshold)
    return [[a[::k] for a in ch] for ch in channels]


def input_range_of(arrays: Sequence[np.ndarray]) -> tuple[float, float]:
    """``(min, max)`` over per-record arrays (no concatenation)."""
    ext = np.array([extrema(a) for a in arrays])
    return float(ext[:, 0].min()), float(ext[:, 1].max())


def full_data_esr(model: Any, exps: Sequence[Experiment]) -> dict[str, float]:
    """Free-run ESR of ``model`` on every record (one record at a time): mean, worst, samples."""
    from mrdamper.metrics import score_arrays

    esr = [float(score_arrays(e.F, model.predict(e)).esr) for e in exps]
    return {
        "mean_esr": float(np.mean(esr)),
        "max_esr": float(np.max(esr)),
        "samples": int(sum(e.n for e in exps)),
    }


#: Rows of one block of the chunked least squares [rows].
QR_BLOCK = 32768


class LazyRecords(Sequence[np.ndarray]):
    """Per-record arrays built on demand (``build(exps[r])``), so only one is held at a time."""

    def __init__(self, build: Callable[[Any], np.ndarray], exps: Sequence[Any]) -> None:
        self._build = build
        self._exps = exps

    def __len__(self) -> int:
        return len(self._exps)

    def __getitem__(self, r: Any) -> Any:
        if isinstance(r, slice):
            return [self[k] for k in range(*r.indices(len(self)))]
        return self._build(self._exps[r])


def chunked_qr(
    records: Sequence[np.ndarray],
    weights: Sequence[float],
    base: np.ndarray,
    terms: np.ndarray,
    p: int,
    fill: Callable[..., None],
) -> tuple[np.ndarray, np.ndarray]:
    """Triangular factor of the weighted NARX regression ``[X y]``, accumulated by blocks.

    ``fill(S, base, terms, k0, k1, out)`` writes the regressors of samples ``k0:k1`` of record
    ``S``. Returns ``(R_X, z)`` with ``R_X`` upper triangular (``M x M``) and ``z = Q^T y``: the
    least-squares problem ``min |R_X c - z|`` has the solution, and ``R_X`` the singular values,
    of ``min |X c - y|``. Memory: one block of :data:`QR_BLOCK` rows.
    """
    M = terms.shape[0]
    R = np.zeros((0, M + 1))
    blk = np.empty((QR_BLOCK, M + 1))
    for S, w in zip(records, weights, strict=True):
        sw = float(np.sqrt(w))
        for k0 in range(p, S.shape[1], QR_BLOCK):
            k1 = min(k0 + QR_BLOCK, S.shape[1])
            B = blk[: k1 - k0]
            fill(S, base, terms, k0, k1, B[:, :M])
            B[:, M] = S[0, k0:k1]
            B *= sw
            R = np.asarray(np.linalg.qr(np.vstack((R, B)), mode="r"))
    R = np.vstack((R, np.zeros((max(0, M + 1 - R.shape[0]), M + 1))))
    return np.ascontiguousarray(R[:M, :M]), R[:M, M].copy()


def narx_windows(
    records: Sequence[np.ndarray], weights: Sequence[float], fs: float, p: int
) -> tuple[Sequence[np.ndarray], list[float], dict[str, Any] | None]:
    """Windows (copies) of NARX signal arrays ``S`` (5 x N) for the output-error refinement;
    the records themselves below the threshold. Each window keeps its parent's weight."""
    lengths = [_n_columns(records, r) for r in range(len(records))]
    plan = plan_windows(lengths, fs)
    if plan is None:
        return records, list(weights), None
    wins: list[np.ndarray] = []
    w: list[float] = []
    for r in sorted({r for r, _, _ in plan}):
        S = records[r]
        for rr, a, b in plan:
            b = min(b, S.shape[1])
            if rr == r and b - a > p + 1:
                wins.append(np.ascontiguousarray(S[:, a:b]))
                w.append(float(weights[r]))
        del S
    return wins, w, _info(plan, sum(lengths))


def _n_columns(records: Sequence[np.ndarray], r: int) -> int:
    if isinstance(records, LazyRecords):
        e = records._exps[r]
        return int(e.n)  # at the record rate; windows are clipped to the model-rate length
    return int(records[r].shape[1])


def lpv_qr_factor(
    y: np.ndarray,
    u: np.ndarray,
    rho: np.ndarray,
    starts: np.ndarray,
    weights: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
    build: Callable[..., tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """Triangular factor ``(R, z)`` of the weighted LPV regression ``[X t]``, block by block.

    ``build`` is the kernel that materialises the rows of whole records
    (:func:`~mrdamper.models.lpv.kernels.build_regressors`); it is called on blocks of
    :data:`QR_BLOCK` rows (each with the ``n_m`` samples before it, so the lags are exact), and the
    blocks are folded into the QR factor. ``min |R c - z|`` has the solution and ``R`` the
    singular values of ``min |X c - t|``; memory is one block instead of the whole ``X``.
    """
    R: np.ndarray | None = None
    for r in range(starts.size - 1):
        a, b = int(starts[r]), int(starts[r + 1])
        w = np.asarray(weights[r : r + 1], dtype=np.float64)
        for k0 in range(a + n_m, b, QR_BLOCK):
            k1 = min(k0 + QR_BLOCK, b)
            sl = slice(k0 - n_m, k1)
            Xb, tb = build(
                y[sl],
                u[sl],
                rho[sl],
                np.array([0, k1 - k0 + n_m], dtype=np.int64),
                w,
                n_m,
                n_p,
                with_const,
            )
            B = np.column_stack((Xb, tb))
            R = B if R is None else np.vstack((R, B))
            R = np.asarray(np.linalg.qr(R, mode="r"))
    if R is None:
        raise ValueError("no regression rows")
    P = R.shape[1] - 1
    R = np.vstack((R, np.zeros((max(0, P + 1 - R.shape[0]), P + 1))))
    return np.ascontiguousarray(R[:P, :P]), R[:P, P].copy()


def fold_qr(blocks: Iterable[np.ndarray]) -> np.ndarray:
    """Triangular factor ``R`` of the row blocks ``[X_b y_b]`` stacked (``Q R = [X y]``).

    Returns the square ``(P+1) x (P+1)`` factor: ``R[:P, :P]`` and ``R[:P, P]`` give the
    least-squares solution and singular values of ``X c = y``; ``R[P, P]**2`` is the residual sum of
    squares. Memory: one block at a time.
    """
    R: np.ndarray | None = None
    for B in blocks:
        R = np.asarray(np.linalg.qr(B if R is None else np.vstack((R, B)), mode="r"))
    if R is None:
        raise ValueError("no regression rows")
    P1 = R.shape[1]
    return np.vstack((R, np.zeros((max(0, P1 - R.shape[0]), P1))))[:P1]


class RecordList(list[Any]):
    """Per-record arrays that the LPV least squares takes record by record (no concatenation)."""


def lpv_gram_records(
    ys: Sequence[np.ndarray],
    us: Sequence[np.ndarray],
    rhos: Sequence[np.ndarray],
    weights: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
    gram_pass: Callable[..., Any],
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """``gram_pass`` summed over records given as separate arrays (same sums as one call on the
    concatenation, up to the order of the floating-point additions)."""
    G: np.ndarray | None = None
    g: np.ndarray | None = None
    yy, n_eq = 0.0, 0
    for r in range(len(us)):
        st = np.array([0, us[r].size], dtype=np.int64)
        Gr, gr, yyr, nr = gram_pass(
            ys[r],
            us[r],
            rhos[r],
            st,
            np.asarray(weights[r : r + 1], dtype=np.float64),
            n_m,
            n_p,
            with_const,
        )
        G = Gr if G is None else G + Gr
        g = gr if g is None else g + gr
        yy += float(yyr)
        n_eq += int(nr)
    assert G is not None and g is not None
    return G, g, yy, n_eq


def lpv_qr_records(
    ys: Sequence[np.ndarray],
    us: Sequence[np.ndarray],
    rhos: Sequence[np.ndarray],
    weights: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
    build: Callable[..., tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`lpv_qr_factor` over records given as separate arrays."""

    def blocks() -> Iterator[np.ndarray]:
        for r in range(len(us)):
            st = np.array([0, us[r].size], dtype=np.int64)
            R, z = lpv_qr_factor(
                ys[r],
                us[r],
                rhos[r],
                st,
                np.asarray(weights[r : r + 1]),
                n_m,
                n_p,
                with_const,
                build,
            )
            yield np.column_stack((R, z))

    Rf = fold_qr(blocks())
    return np.ascontiguousarray(Rf[:-1, :-1]), Rf[:-1, -1].copy()


def distinct_levels(rhos: Sequence[np.ndarray], tol: float) -> int:
    """Number of levels of the scheduling variable separated by more than ``tol``, record by record.

    One representative per cluster of each record, then the same count over the representatives.
    """
    reps = []
    for r in rhos:
        s = np.sort(r)
        reps.append(s[np.r_[True, np.diff(s) > tol]])
    s = np.sort(np.concatenate(reps))
    return int(1 + np.count_nonzero(np.diff(s) > tol))
