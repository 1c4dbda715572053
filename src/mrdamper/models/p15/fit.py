"""Identification of P-15: the equation-error fit on filtered derivatives (the paper's literal
fit, also the start of the output-error fit) and the output-error fit, stable by construction.

Private machinery of :class:`~mrdamper.models.p15.P15Estimator`.

Equation error
--------------
Per record (records are never joined: filtering and differentiation stop at record edges):

1. ``F`` and ``v`` pass a zero-phase Butterworth low-pass (order ``filter_order`` run forward and
   backward) with cut-off ``cutoff`` [Hz] (``"auto"``: ``min(fs / 10, 100)`` per record).
2. ``dF/dt`` and ``d2F/dt2`` are central differences of the filtered force; ``3 fs / cutoff``
   samples are trimmed at both record edges.
3. The quadratics ``w_j(i)`` are expanded in the Bernstein basis of ``s = (i - lo) / (hi - lo)``;
   columns are scaled to unit norm; the condition number of the scaled regression is checked.
4. ``form="free"``: plain least squares; ``"stable"``: every Bernstein coefficient of ``w3`` and
   ``w2`` below zero and of ``w5`` at most zero (bounded least squares); ``"monotone"``: also
   ``w4 <= 0``.

Output error
------------
``method="output-error"``, a parametrisation that is stable by construction. Written as
``m F'' + c F' + g(F) = w1 v + f0`` with ``m = -w3``, ``c = -w2`` and ``g(F) = F + a F^3 + b F^5``
(``a = -w4``, ``b = -w5``), each of the five quadratics ``w1, c, m, a, b`` is written in the
Bernstein basis of ``s = (i - lo) / (hi - lo)`` with coefficients ``exp(theta)``: positive Bernstein
coefficients make the quadratic positive on the whole identified input range ``[lo, hi]`` (the basis
polynomials are non-negative there and sum to one). ``docs/models.md`` proves what this buys (a
unique, globally asymptotically stable equilibrium at every frozen input and velocity, bounded force
for bounded velocity).

Two least-squares stages on the simulated force (:func:`scipy.optimize.least_squares`, trust
region reflective; Jacobian from the exact discrete sensitivities of the compiled SDIRK2 kernel):

1. **Multiple shooting**: every record is cut into segments of ``segment`` seconds; each segment
   is simulated from the measured state (zero-phase filtered force and its central-difference
   rate at the segment's first sample). Short horizons keep the cost surface close to quadratic
   and avoid the local minima of a long simulation.
2. **Free run**: every record simulated whole from the model's rest state (as in prediction),
   with the sensitivity of that rest state to the coefficients.

Each record's residuals are weighted by ``1 / (std(F) sqrt(n n_records))`` (``n`` the residual
samples used): the cost is half the mean per-record ESR over those samples. Residuals use at
most ``max_samples`` samples (every k-th); the simulation always runs on every sample.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares, lsq_linear
from scipy.signal import butter, sosfiltfilt

from mrdamper._warn import warn_user
from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, IdentificationError
from mrdamper.models.p15.kernels import p15i_run
from mrdamper.progress import counted

__all__ = [
    "BERNSTEIN_TO_POWER",
    "SIGNS",
    "bernstein_basis",
    "check_levels",
    "cutoff_hz",
    "equation_error",
    "filtered_state",
    "identify_output_error",
    "rest_state",
    "to_monomial",
]


#: Condition number of the scaled regression above which identification fails / warns.
COND_FAIL, COND_WARN = 1e10, 1e6
#: Samples required per coefficient.
SAMPLES_PER_PARAMETER = 10
#: A shooting stage that used its whole budget continues while the budget cut its cost by more
#: than this share [-] (up to ``shoot_nfev_max`` evaluations in all).
SHOOT_PROGRESS = 0.01


def cutoff_hz(setting: float | str | None, fs: float) -> float | None:
    """Derivative-filter cut-off [Hz] of a record sampled at ``fs`` [Hz]."""
    if setting is None:
        return None
    return float(min(fs / 10.0, 100.0)) if setting == "auto" else float(setting)


def _filtered(
    e: Experiment, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray, float | None]:
    fc = cutoff_hz(cutoff, e.fs)
    if fc is None:
        return e.F, e.v, None
    if not fc < 0.5 * e.fs:
        raise DataValidationError(
            "cutoff",
            f"{fc:g} Hz is not below the Nyquist frequency {0.5 * e.fs:g} Hz of record {e.name!r}",
        )
    sos = butter(order, fc, btype="low", fs=e.fs, output="sos")
    if e.n <= 3 * (2 * len(sos) + 1):
        return e.F, e.v, fc  # too short to filter; regressors() then returns no samples
    return sosfiltfilt(sos, e.F), sosfiltfilt(sos, e.v), fc


def filtered_state(
    e: Experiment, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray]:
    """Filtered force [N] and its central-difference rate [N/s] over the whole record."""
    Ff, _, _ = _filtered(e, cutoff, order)
    return Ff, np.gradient(Ff, e.dt)


def regressors(
    e: Experiment, source: ElectricalSource, cutoff: float | str | None, order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filtered force (target), input and the five regressor signals of one record, trimmed."""
    i = e.electrical(source)
    Ff, vf, fc = _filtered(e, cutoff, order)
    dF = np.gradient(Ff, e.dt)
    ddF = np.gradient(dF, e.dt)
    trim = 2 if fc is None else math.ceil(3.0 * e.fs / fc)
    if fc is not None and e.n <= 2 * trim + 3 * order:
        return np.empty(0), np.empty(0), np.empty((0, 5))
    sl = slice(trim, e.n - trim)
    F = Ff[sl]
    return F, np.asarray(i[sl]), np.stack([vf[sl], dF[sl], ddF[sl], F**3, F**5], axis=1)


def check_levels(i: np.ndarray, lo: float, hi: float, source: str) -> None:
    """Quadratics in the input need at least three distinct input levels."""
    if hi - lo <= 1e-9 * max(1.0, abs(hi)):
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels, but the training input is constant ({lo:g}); rank 1 of 3"
        )
    s = (i - lo) / (hi - lo)
    V = np.stack([np.ones_like(s), s, s * s], axis=1)
    sv = np.linalg.svd(V / np.linalg.norm(V, axis=0), compute_uv=False)
    rank = int(np.sum(sv > sv[0] * 1e-6))
    if rank < 3:
        raise IdentificationError(
            f"{source}: p15 coefficients are quadratics in {source} and need at least 3 distinct "
            f"{source} levels; the training input has numerical rank {rank} of 3"
        )


def _form_bounds(form: str, n_basis: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the scaled Bernstein coefficients (``n_basis`` per quadratic, ``n`` unknowns)
    that impose the sign constraints of ``form``."""
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)

    def row(j: int) -> slice:
        return slice(j * n_basis, (j + 1) * n_basis)

    if form != "free":
        ub[row(1)] = -1e-9  # w2 Bernstein coefficients < 0
        ub[row(2)] = -1e-9  # w3 < 0
        ub[row(4)] = 0.0  # w5 <= 0
    if form == "monotone":
        ub[row(3)] = 0.0  # w4 <= 0: g(F) increasing, no bistable branch
    return lb, ub


def equation_error(
    exps: Sequence[Experiment],
    source: ElectricalSource,
    lo: float,
    hi: float,
    *,
    form: str,
    offset: bool,
    cutoff: float | str | None,
    order: int,
    single: bool = False,
) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Least squares of the P-15 relation on filtered derivatives.

    With ``single`` (training input at one level, ``lo == hi``) each ``w_j`` is a constant: one
    coefficient per quadratic is identified and returned in all three Bernstein columns (the
    Bernstein coefficients of a constant).

    Returns
    -------
    B : ndarray, shape (5, 3)
        Bernstein coefficients of ``w_1 .. w_5`` on ``[lo, hi]``.
    f0 : float
        Force offset [N].
    info : dict
        ``n_samples``, ``condition_number``, ``equation_error_rms`` [N], ``cutoff_hz``.
    """
    parts = [regressors(e, source, cutoff, order) for e in exps]
    y = np.concatenate([p[0] for p in parts])
    n_basis = 1 if single else 3
    n_par = 5 * n_basis + int(offset)
    if y.size < SAMPLES_PER_PARAMETER * n_par:
        raise IdentificationError(
            f"data: p15 has {n_par} parameters and needs at least {SAMPLES_PER_PARAMETER * n_par} "
            f"samples after trimming the filter edges, got {y.size}"
        )
    i_reg = np.concatenate([p[1] for p in parts])
    cols = np.concatenate([p[2] for p in parts], axis=0)  # (n, 5): v, dF, ddF, F^3, F^5
    if single:
        basis = np.ones((y.size, 1))
    else:
        check_levels(i_reg, lo, hi, source)
        s = (i_reg - lo) / (hi - lo)
        basis = np.stack([(1 - s) ** 2, 2 * s * (1 - s), s**2], axis=1)
    X = (cols[:, :, None] * basis[:, None, :]).reshape(y.size, 5 * n_basis)
    if offset:
        X = np.concatenate([X, np.ones((y.size, 1))], axis=1)
    norms = np.sqrt(np.einsum("ij,ij->j", X, X))
    if np.any(norms == 0):
        j = int(np.flatnonzero(norms == 0)[0])
        raise IdentificationError(
            f"data: regressor {j} of p15 is identically zero; nothing to identify"
        )
    ynorm = float(np.linalg.norm(y)) or 1.0
    Xs, ys = X / norms, y / ynorm
    # einsum without BLAS: the same bytes whatever the BLAS thread count
    gram = np.einsum("ij,ik->jk", Xs, Xs)
    ev = np.linalg.eigvalsh(gram)
    cond = float(np.sqrt(ev[-1] / ev[0])) if ev[0] > 0 else math.inf
    if not cond < COND_FAIL:
        raise IdentificationError(
            f"data: p15 regression is ill-conditioned (condition number {cond:.3g} > "
            f"{COND_FAIL:g}); the records do not excite all {5 * n_basis} terms (vary velocity "
            f"amplitude and {source})"
        )
    if cond > COND_WARN:
        warn_user(f"p15: regression condition number {cond:.3g}", RuntimeWarning)
    lb, ub = _form_bounds(form, n_basis, X.shape[1])
    if form == "free":
        theta = np.linalg.solve(gram, np.einsum("ij,i->j", Xs, ys))
    else:
        theta = lsq_linear(Xs, ys, bounds=(lb, ub), method="bvls").x
    coef = theta * ynorm / norms
    resid = float(np.sqrt(np.mean((X @ coef - y) ** 2)))
    info = {
        "n_samples": int(y.size),
        "condition_number": cond,
        "equation_error_rms": resid,
        "cutoff_hz": {e.name: cutoff_hz(cutoff, e.fs) for e in exps},
    }
    B = coef[: 5 * n_basis].reshape(5, n_basis)
    if single:
        B = np.repeat(B, 3, axis=1)
    return B, float(coef[5 * n_basis]) if offset else 0.0, info


#: Sign of each paper coefficient w_j relative to the positive quadratic (w1, c, m, a, b).
SIGNS = np.array([1.0, -1.0, -1.0, -1.0, -1.0])
#: Bernstein (b0, b1, b2) on [0, 1] -> power basis in s.
BERNSTEIN_TO_POWER = np.array([[1.0, 0.0, 0.0], [-2.0, 2.0, 0.0], [1.0, -2.0, 1.0]])
#: Residual per sample of a diverged simulation (in ESR-weighted units).
_PENALTY = 10.0


def to_monomial(B: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Monomial coefficients ``W`` (5 x 3, in ``i``) of Bernstein coefficients ``B``.

    The Bernstein basis is on ``[lo, hi]``.
    """
    R = hi - lo
    to_i = np.array(
        [[1.0, -lo / R, lo**2 / R**2], [0.0, 1.0 / R, -2 * lo / R**2], [0.0, 0.0, 1.0 / R**2]]
    )
    M = to_i @ BERNSTEIN_TO_POWER
    return np.asarray(np.einsum("jk,rk->rj", M, B))


def bernstein_basis(i: float | np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Bernstein basis ``(1-s)^2, 2s(1-s), s^2`` at ``s = (i - lo) / (hi - lo)``.

    ``s`` is clipped to [0, 1].
    """
    s = np.clip((np.asarray(i, dtype=float) - lo) / (hi - lo), 0.0, 1.0)
    return np.stack([(1 - s) ** 2, 2 * s * (1 - s), s * s])


def rest_state(w: np.ndarray, f0: float, v0: float) -> float:
    """Force [N] at rest (``F' = F'' = 0``) for coefficients ``w = (w1 .. w5)`` and velocity ``v0``.

    The root of ``F - f0 - w1 v0 - w4 F^3 - w5 F^5 = 0``. When ``g(F) = F - w4 F^3 - w5 F^5`` is
    increasing (``w4, w5 <= 0``, guaranteed by the output-error fit) there is exactly one real
    root. Otherwise the real root with ``g'(F) > 0`` closest to zero is taken (the one that is
    stable when ``w2, w3 < 0``), or the real root closest to zero if none has ``g' > 0``.
    """
    u = f0 + w[0] * v0
    coef = np.array([-w[4], 0.0, -w[3], 0.0, 1.0, -u])
    roots = np.roots(coef)
    real = np.sort(roots[np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots))].real)
    if real.size == 0:
        return float(u)

    def h(F: np.ndarray) -> np.ndarray:
        return np.asarray(F - u - w[3] * F**3 - w[4] * F**5)

    def gp(F: np.ndarray) -> np.ndarray:
        return np.asarray(1.0 - 3.0 * w[3] * F**2 - 5.0 * w[4] * F**4)

    # polish with Newton (np.roots is accurate only to a few ulps of the largest root)
    for _ in range(3):
        d = gp(real)
        real = np.where(d != 0, real - h(real) / np.where(d != 0, d, 1.0), real)
    good = real[gp(real) > 0]
    pool = good if good.size else real
    return float(pool[np.argmin(np.abs(pool))])


def _rest_sensitivity(
    B: np.ndarray, f0: float, lo: float, hi: float, v0: float, i0: float, F0: float, m: int
) -> np.ndarray:
    """d F_rest / d (Bernstein coefficients of w, row-major; then f0)."""
    phi = bernstein_basis(i0, lo, hi)
    w = B @ phi
    gp = 1.0 - 3.0 * w[3] * F0**2 - 5.0 * w[4] * F0**4
    regs = np.array([v0, 0.0, 0.0, F0**3, F0**5]) / gp
    out = np.zeros(m)
    out[:15] = np.outer(regs, phi).ravel()
    if m > 15:
        out[15] = 1.0 / gp
    return out


@dataclass
class _Rec:
    e: Experiment
    v: np.ndarray
    i: np.ndarray
    F: np.ndarray
    Ff: np.ndarray
    Gf: np.ndarray
    std: float
    n_sub: int


@dataclass
class _Problem:
    recs: list[_Rec]
    lo: float
    hi: float
    bound: float
    f_scale: float
    offset: bool
    max_samples: int
    single: bool = False
    nfev: int = 0
    njev: int = 0
    failures: int = 0

    @property
    def n_coef(self) -> int:
        """Unknown Bernstein coefficients: 15, or 5 at a single level (one per quadratic)."""
        return 5 if self.single else 15

    @property
    def n_par(self) -> int:
        return self.n_coef + int(self.offset)

    def unpack(self, theta: np.ndarray) -> tuple[np.ndarray, float]:
        """Bernstein coefficients of ``w`` (signed, 5 x 3) and ``f0`` from the unknowns (at a
        single level the three coefficients of a quadratic are equal: a constant)."""
        c = self.n_coef
        mag = np.exp(np.clip(theta[:c], -700.0, 700.0)).reshape(5, c // 5)
        B = SIGNS[:, None] * (np.repeat(mag, 3, axis=1) if self.single else mag)
        f0 = float(theta[c] * self.f_scale) if self.offset else 0.0
        return B, f0

    def chain(self, theta: np.ndarray) -> np.ndarray:
        """d (Bernstein coefficients, f0) / d theta.

        Diagonal; 16 entries, the full coefficients.
        """
        B, _ = self.unpack(theta)
        d = np.empty(16 if self.offset else 15)
        d[:15] = B.ravel()
        if self.offset:
            d[15] = self.f_scale
        return d

    def reduce(self, J: np.ndarray) -> np.ndarray:
        """Jacobian columns of the full coefficients -> columns of the unknowns."""
        if not self.single:
            return J
        out = J[:, :15].reshape(J.shape[0], 5, 3).sum(axis=2)
        return np.concatenate([out, J[:, 15:]], axis=1)

    def segments(
        self, r: _Rec, mode: str, seg_len: int, seg_stride: int
    ) -> tuple[np.ndarray, np.ndarray]:
        n = r.F.size
        if mode == "free":
            return np.array([0], dtype=np.int64), np.array([n], dtype=np.int64)
        starts = np.arange(0, max(1, n - 2), seg_stride, dtype=np.int64)
        return starts, np.minimum(starts + seg_len, n).astype(np.int64)

    def evaluate(
        self, theta: np.ndarray, mode: str, seg: tuple[float, int], with_jac: bool
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Weighted residuals (and Jacobian w.r.t. theta) of every record."""
        B, f0 = self.unpack(theta)
        chain = self.chain(theta)
        m = chain.size
        res, jac = [], []
        n_total = sum(r.F.size for r in self.recs)
        stride = max(1, math.ceil(n_total / self.max_samples))
        for r in self.recs:
            seg_len = max(4, round(seg[0] / r.e.dt))
            st, en = self.segments(r, mode, seg_len, max(seg_len, seg_len * seg[1]))
            if mode == "free":
                F0 = np.array(
                    [rest_state(B @ bernstein_basis(r.i[0], self.lo, self.hi), f0, r.v[0])]
                )
                G0 = np.zeros(1)
                S0 = _rest_sensitivity(B, f0, self.lo, self.hi, r.v[0], r.i[0], F0[0], m)[None, :]
            else:
                F0, G0 = r.Ff[st], r.Gf[st]
                S0 = np.zeros((st.size, m))
            F, J, bad = p15i_run(
                r.v,
                r.i,
                r.e.dt,
                B,
                f0,
                1,
                self.lo,
                self.hi,
                r.n_sub,
                self.bound,
                st,
                en,
                F0,
                G0,
                S0,
                with_jac,
                self.offset,
            )
            idx = np.concatenate([np.arange(a, b) for a, b in zip(st, en)])
            idx = idx[::stride] if stride > 1 else idx
            # each record's squared residuals sum to its ESR over the samples used, / n_records
            weight = 1.0 / (r.std * math.sqrt(idx.size * len(self.recs)))
            rr = (F[idx] - r.F[idx]) * weight
            failed = bad >= 0
            if np.any(failed):
                self.failures += 1
                for a, b, k in zip(st[failed], en[failed], bad[failed]):
                    rr[(idx >= k) & (idx < b)] = _PENALTY * weight * r.std
            res.append(rr)
            if with_jac:
                Jr = self.reduce(J[idx] * chain[None, :] * weight)
                if np.any(failed):
                    for a, b, k in zip(st[failed], en[failed], bad[failed]):
                        Jr[(idx >= k) & (idx < b)] = 0.0
                jac.append(Jr)
        return np.concatenate(res), (np.concatenate(jac) if with_jac else None)


def identify_output_error(
    exps: Sequence[Experiment],
    source: ElectricalSource,
    lo: float,
    hi: float,
    B0: np.ndarray,
    f00: float,
    *,
    Ff: Sequence[np.ndarray],
    Gf: Sequence[np.ndarray],
    offset: bool,
    max_step: float,
    segment: float,
    segment_stride: int,
    shoot_nfev: int,
    max_nfev: int,
    shoot_nfev_max: int | None = None,
    max_samples: int,
    jacobian: str,
    bound: float,
    single: bool = False,
) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Run the two stages from Bernstein coefficients ``B0`` (signed, 5 x 3) and offset ``f00``.

    Returns the Bernstein coefficients (signed, positive-form) and offset of the fit, and a
    provenance dictionary. With ``single`` (one input level) each quadratic is a constant: one
    unknown per quadratic, its three Bernstein coefficients equal; ``hi`` may equal ``lo``.
    """
    if single:
        hi = lo + 1.0  # any interval: the basis sums to one and the rows are constant
    recs = []
    for e, ff, gf in zip(exps, Ff, Gf):
        Fstd = float(np.std(e.F)) or 1.0
        n_sub = max(1, math.ceil(e.dt / max_step - 1e-12))
        recs.append(
            _Rec(
                e,
                np.ascontiguousarray(e.v),
                np.ascontiguousarray(e.electrical(source)),
                np.ascontiguousarray(e.F),
                np.ascontiguousarray(ff),
                np.ascontiguousarray(gf),
                Fstd,
                n_sub,
            )
        )
    f_scale = float(max(np.std(e.F) for e in exps)) or 1.0
    prob = _Problem(recs, lo, hi, bound, f_scale, offset, max_samples, single)
    # start: magnitudes of the equation-error Bernstein coefficients with the positive signs,
    # floored at 1e-3 of the largest coefficient of the same quadratic (or a scale-based value)
    mag = SIGNS[:, None] * B0
    floors = np.array([1e-3, 1e-6, 1e-9, 1e-3 / f_scale**2, 1e-3 / f_scale**4])
    start = np.empty((5, 3))
    for j in range(5):
        top = float(np.max(mag[j]))
        floor = 1e-3 * top if top > 0 else floors[j]
        start[j] = np.maximum(mag[j], floor)
    if single:
        start = start[:, :1]
    theta = np.concatenate([np.log(start).ravel(), [f00 / f_scale] if offset else []])
    stages: list[dict[str, Any]] = []

    def solve(theta0: np.ndarray, mode: str, nfev: int, stage: str) -> np.ndarray:
        seg = (segment, segment_stride)
        cache: dict[bytes, tuple[np.ndarray, np.ndarray | None]] = {}

        def get(th: np.ndarray, with_jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            key = th.tobytes()
            hit = cache.get(key)
            if hit is not None and (hit[1] is not None or not with_jac):
                return hit
            out = prob.evaluate(th, mode, seg, with_jac)
            cache.clear()
            cache[key] = out
            return out

        def fun(th: np.ndarray) -> np.ndarray:
            prob.nfev += 1
            return get(th, jacobian == "sensitivity")[0]

        def jac(th: np.ndarray) -> np.ndarray:
            prob.njev += 1
            J = get(th, True)[1]
            assert J is not None
            return J

        r0 = fun(theta0)
        lb = np.full(theta0.size, -np.inf)
        ub = np.full(theta0.size, np.inf)
        c = prob.n_coef
        lb[:c], ub[:c] = theta0[:c] - 40.0, theta0[:c] + 40.0
        sol = least_squares(
            # the evaluation budget counts the calls of fun when the Jacobian is analytic
            counted(fun, stage, nfev if jacobian == "sensitivity" else None),
            theta0,
            jac=jac if jacobian == "sensitivity" else jacobian,
            bounds=(lb, ub),
            method="trf",
            x_scale=1.0,
            max_nfev=nfev,
            ftol=1e-6,
            xtol=1e-10,
            gtol=1e-10,
        )
        cost0 = 0.5 * float(r0 @ r0)
        keep = sol.x if sol.cost <= cost0 else theta0
        stages.append(
            {
                "stage": mode,
                "cost_before": cost0,
                "cost_after": float(min(sol.cost, cost0)),
                "nfev": int(sol.nfev),
                "status": int(sol.status),
                "message": str(sol.message),
            }
        )
        return keep

    if shoot_nfev > 0:
        theta = solve(theta, "shooting", shoot_nfev, "multiple shooting: evaluation")
        # a stage stopped by its budget while still descending continues, one budget at a time
        used, top = stages[-1]["nfev"], shoot_nfev if shoot_nfev_max is None else shoot_nfev_max
        while (
            stages[-1]["status"] == 0
            and used < top
            and stages[-1]["cost_after"] < (1.0 - SHOOT_PROGRESS) * stages[-1]["cost_before"]
        ):
            n = min(shoot_nfev, top - used)
            theta = solve(theta, "shooting", n, "multiple shooting (continued): evaluation")
            used += stages[-1]["nfev"]
    if max_nfev > 0:
        theta = solve(theta, "free", max_nfev, "free-run refinement: evaluation")
    B, f0 = prob.unpack(theta)
    info = {
        "method": (
            "output error: multiple shooting then free run (scipy.optimize.least_squares, trf)"
        ),
        "jacobian": "discrete forward sensitivities (SDIRK2)"
        if jacobian == "sensitivity"
        else f"finite differences ({jacobian})",
        "stages": stages,
        "segment_s": segment,
        "segment_stride": segment_stride,
        "substeps": {r.e.name: r.n_sub for r in recs},
        "nfev_total": prob.nfev,
        "njev_total": prob.njev,
        "simulation_failures": prob.failures,
    }
    return B, f0, info
