"""Output-error identification of P-15 with a parametrisation that is stable by construction.

Private machinery of :class:`~mrdamper.models.phenomenological.P15Estimator` (``method =
"output-error"``). Written as ``m F'' + c F' + g(F) = w1 v + f0`` with ``m = -w3``,
``c = -w2`` and ``g(F) = F + a F^3 + b F^5`` (``a = -w4``, ``b = -w5``), each of the five
quadratics ``w1, c, m, a, b`` is written in the Bernstein basis of ``s = (i - lo) / (hi - lo)``
with coefficients ``exp(theta)``: positive Bernstein coefficients make the quadratic positive on
the whole identified input range ``[lo, hi]`` (the basis polynomials are non-negative there and
sum to one). ``docs/models.md`` proves what this buys (a unique, globally asymptotically stable
equilibrium at every frozen input and velocity, bounded force for bounded velocity).

Two least-squares stages on the simulated force (:func:`scipy.optimize.least_squares`, trust
region reflective; Jacobian from the exact discrete sensitivities of the compiled SDIRK2 kernel):

1. **Multiple shooting**: every record is cut into segments of ``segment`` seconds; each segment
   is simulated from the measured state (zero-phase filtered force and its central-difference
   rate at the segment's first sample). Short horizons keep the cost surface close to quadratic
   and avoid the local minima of a long simulation.
2. **Free run**: every record simulated whole from the model's rest state (as in prediction),
   with the sensitivity of that rest state to the coefficients.

Each record's residuals are weighted by ``1 / (std(F) sqrt(n n_records))`` (``n`` the residual
samples used): the cost is half the mean per-record ESR over those samples. Residuals use at most ``max_samples`` samples (every k-th); the simulation
always runs on every sample.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from mrdamper.data import Experiment
from mrdamper.data.experiment import ElectricalSource
from mrdamper.models._p15_implicit import p15i_run

__all__ = [
    "BERNSTEIN_TO_POWER",
    "SIGNS",
    "bernstein_basis",
    "identify_output_error",
    "rest_state",
    "to_monomial",
]

#: Sign of each paper coefficient w_j relative to the positive quadratic (w1, c, m, a, b).
SIGNS = np.array([1.0, -1.0, -1.0, -1.0, -1.0])
#: Bernstein (b0, b1, b2) on [0, 1] -> power basis in s.
BERNSTEIN_TO_POWER = np.array([[1.0, 0.0, 0.0], [-2.0, 2.0, 0.0], [1.0, -2.0, 1.0]])
#: Residual per sample of a diverged simulation (in ESR-weighted units).
_PENALTY = 10.0


def to_monomial(B: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Monomial coefficients ``W`` (5 x 3, in ``i``) of Bernstein coefficients ``B`` on ``[lo, hi]``."""
    R = hi - lo
    to_i = np.array(
        [[1.0, -lo / R, lo**2 / R**2], [0.0, 1.0 / R, -2 * lo / R**2], [0.0, 0.0, 1.0 / R**2]]
    )
    M = to_i @ BERNSTEIN_TO_POWER
    return np.einsum("jk,rk->rj", M, B)


def bernstein_basis(i: float | np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Bernstein basis ``(1-s)^2, 2s(1-s), s^2`` at ``s = (i - lo) / (hi - lo)`` clipped to [0, 1]."""
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
        return F - u - w[3] * F**3 - w[4] * F**5

    def gp(F: np.ndarray) -> np.ndarray:
        return 1.0 - 3.0 * w[3] * F**2 - 5.0 * w[4] * F**4

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
        """d (Bernstein coefficients, f0) / d theta (diagonal; 16 entries, the full coefficients)."""
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
    t0 = time.perf_counter()
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

    def solve(theta0: np.ndarray, mode: str, nfev: int) -> np.ndarray:
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
            fun,
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
        theta = solve(theta, "shooting", shoot_nfev)
    if max_nfev > 0:
        theta = solve(theta, "free", max_nfev)
    B, f0 = prob.unpack(theta)
    info = {
        "method": "output error: multiple shooting then free run (scipy.optimize.least_squares, trf)",
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
        "elapsed_s": time.perf_counter() - t0,
    }
    return B, f0, info
