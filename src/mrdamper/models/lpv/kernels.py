"""Numba kernels of the LPV input-output model (paper eqs. 7-9), on plain arrays.

Model, for one record, with ``a_j(rho) = sum_p alpha[j-1, p] rho**p`` and
``b_j(rho) = sum_p beta[j-1, p] rho**p`` (frozen-coefficient form, reading notes item 4)::

    y[k] = -sum_{j=1..n} a_j(rho[k]) y[k-j] + sum_{j=1..n} b_j(rho[k]) u[k-j]

with zero initial conditions (``y[k] = u[k] = 0`` for ``k < 0``) in free run. The regression vector
of sample ``k`` is ordered ``[-rho^p y[k-j] (j-major, p-minor), rho^p u[k-j], rho^p (offset)]`` so
that ``theta = [alpha.ravel(), beta.ravel(), delta]``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit
from scipy.linalg import blas as _blas

from mrdamper.models._lag import first_order_lag

__all__ = [
    "build_regressors",
    "first_order_lag",
    "frozen_poles",
    "gram_pass",
    "largest_frozen_pole",
    "oe_normal_equations",
    "residual_sse",
    "simulate_record",
    "simulate_sensitivity",
    "split_theta",
]

_BLOCK = 512
#: Blocks of the regression filled at once by :func:`gram_pass` (memory ``P x 16384`` values).
_CHUNK = 32

#: Argument types of the kernels (numba types the values passed; these are for mypy).
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def _fill_blocks(
    bt: np.ndarray,
    yb: np.ndarray,
    y: np.ndarray,
    u: np.ndarray,
    rho: np.ndarray,
    a: int,
    n_m: int,
    n_p: int,
    with_const: bool,
    sw: float,
) -> None:
    """Regression columns of the samples from ``a`` on, in blocks: ``bt[k, :, q]`` is sample
    ``a + k * L + q`` (``bt`` of shape ``(nb, P, L)``), ``yb[k, q]`` its weighted target."""
    nb, _, L = bt.shape
    n = nb * L
    pw = np.empty((n_p, nb, L))
    pw[0] = sw
    for p in range(1, n_p):
        np.multiply(pw[p - 1], rho[a : a + n].reshape(nb, L), out=pw[p])
    neg = -pw
    c = 0
    for j in range(1, n_m + 1):
        yj = y[a - j : a - j + n].reshape(nb, L)
        for p in range(n_p):
            np.multiply(neg[p], yj, out=bt[:, c])
            c += 1
    for j in range(1, n_m + 1):
        uj = u[a - j : a - j + n].reshape(nb, L)
        for p in range(n_p):
            np.multiply(pw[p], uj, out=bt[:, c])
            c += 1
    if with_const:
        for p in range(n_p):
            bt[:, c] = pw[p]
            c += 1
    np.multiply(y[a : a + n].reshape(nb, L), sw, out=yb)


def gram_pass(
    y: np.ndarray,
    u: np.ndarray,
    rho: np.ndarray,
    starts: np.ndarray,
    weights: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Accumulate ``X^T W X``, ``X^T W y`` and ``y^T W y`` without materialising ``X``.

    The regression is filled with NumPy (:data:`_CHUNK` blocks at a time) in blocks of
    :data:`_BLOCK` samples stored transposed (``P x _BLOCK``), and each block is added to the
    sums with one BLAS ``dgemm`` (and ``dgemv``, ``ddot``), block after block in sample order:
    the operations and their order of the compiled kernel this replaced (same sums bit for bit,
    ``tests/models/test_lpv.py``), without its compilation.

    Parameters
    ----------
    y, u, rho : float64[:]
        Records concatenated (output, LPV input, scheduling variable).
    starts : int64[:]
        Record boundaries, length ``R + 1``; record r is ``starts[r]:starts[r+1]``.
    weights : float64[:]
        Weight of each record's equations (length R).
    n_m, n_p : int
        Model order and number of polynomial terms (``n_rho + 1``).
    with_const : bool
        Add ``n_p`` offset columns ``rho**p``.

    Returns
    -------
    G, g, yy, n_eq
    """
    n_m, n_p = int(n_m), int(n_p)
    P = 2 * n_m * n_p + (n_p if with_const else 0)
    G = np.zeros((P, P))
    g = np.zeros(P)
    yy = 0.0
    n_eq = 0
    bt = np.empty((_CHUNK, P, _BLOCK))
    yb = np.empty((_CHUNK, _BLOCK))
    for r in range(len(starts) - 1):
        sw = float(np.sqrt(weights[r]))
        a, end = int(starts[r]) + n_m, int(starts[r + 1])
        while a < end:
            nb = min(_CHUNK, (end - a) // _BLOCK)
            if nb > 0:
                bts, ybs, L = bt[:nb], yb[:nb], _BLOCK
            else:  # the record's last, partial block
                nb, L = 1, end - a
                bts, ybs = np.empty((1, P, L)), np.empty((1, L))
            _fill_blocks(bts, ybs, y, u, rho, a, n_m, n_p, bool(with_const), sw)
            # one product per block, then the blocks' sums added in order (np.add.reduce
            # along the first axis adds row after row)
            Gk = np.empty((nb + 1, P, P))
            Gk[0] = G
            for k in range(nb):
                Gk[k + 1] = _blas.dgemm(1.0, bts[k].T, bts[k].T, trans_a=1).T
            G = np.add.reduce(Gk, axis=0)
            gk = np.empty((nb + 1, P))
            gk[0] = g
            np.matmul(bts, ybs[:, :, None], out=gk[1:, :, None])
            g = np.add.reduce(gk, axis=0)
            for k in range(nb):
                yy += float(ybs[k] @ ybs[k])
            n_eq += nb * L
            a += nb * L
    return G, g, float(yy), n_eq


def build_regressors(
    y: np.ndarray,
    u: np.ndarray,
    rho: np.ndarray,
    starts: np.ndarray,
    weights: np.ndarray,
    n_m: int,
    n_p: int,
    with_const: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Materialise the weighted regression matrix ``X`` and target (QR fall-back, benchmarks).

    Plain NumPy, one column of a record at a time (no compiled kernel: nothing here is
    recursive). Row ``i`` of record ``r`` (sample ``k``) holds ``sqrt(w_r) rho[k]**p`` times
    ``-y[k-j]``, ``u[k-j]`` and, with ``with_const``, one; the powers are formed as running
    products ``(sqrt(w_r) rho) rho ...``, the same operations as in :func:`gram_pass`.

    Returns
    -------
    X : float64[:, :]
        Shape ``(n_eq, 2 n_m n_p [+ n_p])``.
    t : float64[:]
        ``sqrt(w_r) y[k]`` [N].
    """
    n_m, n_p = int(n_m), int(n_p)
    P = 2 * n_m * n_p + (n_p if with_const else 0)
    lengths = np.maximum(np.diff(np.asarray(starts, dtype=np.int64)) - n_m, 0)
    X = np.empty((int(lengths.sum()), P))
    t = np.empty(X.shape[0])
    i = 0
    for r, L in enumerate(lengths.tolist()):
        if L == 0:
            continue
        a = int(starts[r]) + n_m
        b = a + L
        pw = np.empty((n_p, L))
        pw[0] = np.sqrt(weights[r])
        for p in range(1, n_p):
            np.multiply(pw[p - 1], rho[a:b], out=pw[p])
        Xr = X[i : i + L]
        c = 0
        for j in range(1, n_m + 1):
            yk = -y[a - j : b - j]
            for p in range(n_p):
                np.multiply(yk, pw[p], out=Xr[:, c])
                c += 1
        for j in range(1, n_m + 1):
            for p in range(n_p):
                np.multiply(u[a - j : b - j], pw[p], out=Xr[:, c])
                c += 1
        if with_const:
            Xr[:, c : c + n_p] = pw.T
        np.multiply(y[a:b], pw[0], out=t[i : i + L])
        i += L
    return X, t


def simulate_record(
    u: np.ndarray, rho: np.ndarray, alpha: np.ndarray, beta: np.ndarray, bound: float
) -> tuple[np.ndarray, int]:
    """Free-run output of one record from zero initial conditions (dispatcher).

    Orders ``n_m <= 4`` with ``n_rho <= 2`` run in a fused kernel with the coefficients held in
    registers (zero-padded to ``n_m = 4``, ``n_rho = 2``; the padding adds exact zeros); other
    shapes run in the generic chunked kernel. Same return values as :func:`_simulate_generic`.
    """
    n_m, n_p = alpha.shape
    if n_m <= 4 and n_p <= 3:
        al = np.zeros((4, 3))
        be = np.zeros((4, 3))
        al[:n_m, :n_p] = alpha
        be[:n_m, :n_p] = beta
        return _simulate_fused43(u, rho, al, be, float(bound))
    return _simulate_generic(u, rho, alpha, beta, float(bound))


@njit(cache=True)
def _simulate_fused43(
    u: FloatArray, rho: FloatArray, al: FloatArray, be: FloatArray, bound: float
) -> tuple[FloatArray, int]:  # pragma: no cover - numba
    """Fused recursion for ``n_m = 4``, ``n_p = 3`` (zero-padded coefficients)."""
    n = u.size
    y = np.empty(n)
    for k in range(min(4, n)):
        r = rho[k]
        acc = 0.0
        for j in range(k):
            aj = al[j, 0] + r * (al[j, 1] + r * al[j, 2])
            bj = be[j, 0] + r * (be[j, 1] + r * be[j, 2])
            acc += bj * u[k - 1 - j] - aj * y[k - 1 - j]
        if not (abs(acc) <= bound):
            y[k:] = 0.0
            return y, k
        y[k] = acc
    a10, a11, a12 = al[0, 0], al[0, 1], al[0, 2]
    a20, a21, a22 = al[1, 0], al[1, 1], al[1, 2]
    a30, a31, a32 = al[2, 0], al[2, 1], al[2, 2]
    a40, a41, a42 = al[3, 0], al[3, 1], al[3, 2]
    b10, b11, b12 = be[0, 0], be[0, 1], be[0, 2]
    b20, b21, b22 = be[1, 0], be[1, 1], be[1, 2]
    b30, b31, b32 = be[2, 0], be[2, 1], be[2, 2]
    b40, b41, b42 = be[3, 0], be[3, 1], be[3, 2]
    checked = 4
    for k in range(4, n):
        r = rho[k]
        w = (
            (b10 + r * (b11 + r * b12)) * u[k - 1]
            + (b20 + r * (b21 + r * b22)) * u[k - 2]
            + (b30 + r * (b31 + r * b32)) * u[k - 3]
            + (b40 + r * (b41 + r * b42)) * u[k - 4]
        )
        acc = (
            ((w - (a40 + r * (a41 + r * a42)) * y[k - 4]) - (a30 + r * (a31 + r * a32)) * y[k - 3])
            - (a20 + r * (a21 + r * a22)) * y[k - 2]
        ) - (a10 + r * (a11 + r * a12)) * y[k - 1]
        y[k] = acc
        if (k & 255) == 0 or k == n - 1:
            # a diverging run grows without bound or turns NaN; check the last stretch
            for q in range(max(checked, 4), k + 1):
                if not (abs(y[q]) <= bound):
                    y[q:] = 0.0
                    return y, q
            checked = k + 1
    return y, -1


@njit(cache=True)
def _simulate_generic(
    u: FloatArray, rho: FloatArray, alpha: FloatArray, beta: FloatArray, bound: float
) -> tuple[FloatArray, int]:  # pragma: no cover - numba
    """Free-run output of one record from zero initial conditions, any order.

    Works in chunks of ``_BLOCK`` samples: the time-varying coefficients and the input part
    ``w[k] = sum_j b_j(rho[k]) u[k-j]`` are computed for a chunk with loops over ``k`` (which
    vectorise, in small buffers that stay in cache), then the scalar recursion
    ``y[k] = w[k] - sum_j a_j(rho[k]) y[k-j]`` runs. Only the output is allocated at full length.

    Returns
    -------
    y : float64[:]
        Output (without offset).
    bad : int
        Index of the first sample whose output is non-finite or exceeds ``bound`` in magnitude,
        or -1 when the run stayed bounded (``y`` is then complete).
    """
    n = u.size
    n_m, n_p = alpha.shape
    y = np.empty(n)
    # start-up: fewer than n_m past samples exist (zero initial conditions)
    for k in range(min(n_m, n)):
        r = rho[k]
        acc = 0.0
        for j in range(k):
            aj = 0.0
            bj = 0.0
            for p in range(n_p - 1, -1, -1):
                aj = aj * r + alpha[j, p]
                bj = bj * r + beta[j, p]
            acc += bj * u[k - 1 - j] - aj * y[k - 1 - j]
        if not (abs(acc) <= bound):
            y[k:] = 0.0
            return y, k
        y[k] = acc
    A = np.empty((n_m, _BLOCK))
    w = np.empty(_BLOCK)
    bq = np.empty(_BLOCK)
    pw = np.empty((n_p, _BLOCK))
    s = n_m
    while s < n:
        e = min(s + _BLOCK, n)
        L = e - s
        for q in range(L):
            w[q] = 0.0
            pw[0, q] = 1.0
        for p in range(1, n_p):
            for q in range(L):
                pw[p, q] = pw[p - 1, q] * rho[s + q]
        for j in range(n_m):
            a0 = alpha[j, 0]
            b0 = beta[j, 0]
            for q in range(L):
                A[j, q] = a0
                bq[q] = b0
            for p in range(1, n_p):
                ap = alpha[j, p]
                bp = beta[j, p]
                for q in range(L):
                    A[j, q] += ap * pw[p, q]
                    bq[q] += bp * pw[p, q]
            off = s - 1 - j
            for q in range(L):
                w[q] += bq[q] * u[off + q]
        if n_m == 1:
            for q in range(L):
                k = s + q
                y[k] = w[q] - A[0, q] * y[k - 1]
        elif n_m == 2:
            for q in range(L):
                k = s + q
                y[k] = (w[q] - A[1, q] * y[k - 2]) - A[0, q] * y[k - 1]
        elif n_m == 3:
            for q in range(L):
                k = s + q
                y[k] = ((w[q] - A[2, q] * y[k - 3]) - A[1, q] * y[k - 2]) - A[0, q] * y[k - 1]
        else:
            for q in range(L):
                k = s + q
                acc = w[q]
                for j in range(n_m - 1, -1, -1):
                    acc -= A[j, q] * y[k - 1 - j]
                y[k] = acc
        for k in range(s, e):
            if not (abs(y[k]) <= bound):
                y[k:] = 0.0
                return y, k
        s = e
    return y, -1


@njit(cache=True)
def _padded(u: FloatArray, n_m: int) -> FloatArray:  # pragma: no cover - numba
    """``u`` after ``n_m`` zeros (zero initial conditions): sample ``k`` at ``k + n_m``."""
    up = np.zeros(u.size + n_m)
    for k in range(u.size):
        up[k + n_m] = u[k]
    return up


@njit(cache=True, inline="always")
def _sample(
    k: int,
    up: FloatArray,
    yp: FloatArray,
    r: float,
    alpha: FloatArray,
    beta: FloatArray,
    pw: FloatArray,
    a: FloatArray,
) -> float:  # pragma: no cover - numba
    """One sample of the free run, shared by the sensitivity kernels: fills ``pw`` with the
    powers of ``r = rho[k]`` and ``a`` with the denominator coefficients ``a_j(r)``, and returns
    the output ``y[k] = sum_j b_j(r) u[k-1-j] - a_j(r) y[k-1-j]`` from the zero-padded input and
    outputs ``up``, ``yp`` (sample ``k`` at ``k + n_m``, :func:`_padded`)."""
    n_m, n_p = alpha.shape
    pw[0] = 1.0
    for p in range(1, n_p):
        pw[p] = pw[p - 1] * r
    acc = 0.0
    for j in range(n_m):
        aj = 0.0
        bj = 0.0
        for p in range(n_p):
            aj += alpha[j, p] * pw[p]
            bj += beta[j, p] * pw[p]
        a[j] = aj
        acc += bj * up[k + n_m - 1 - j] - aj * yp[k + n_m - 1 - j]
    return acc


@njit(cache=True, inline="always")
def _sensitivity_row(
    J: FloatArray, q: int, k: int, up: FloatArray, yp: FloatArray, pw: FloatArray, a: FloatArray
) -> None:  # pragma: no cover - numba
    """Row ``q`` of ``J``: the sensitivity of ``y[k]`` to ``theta``, the regressors
    ``[-y[k-1-j] r^p ..., u[k-1-j] r^p ...]`` minus ``sum_l a_l(r) J[q-1-l]`` (rows ``q-1-l``
    hold the previous samples' sensitivities, zeros before the first)."""
    n_m = a.size
    n_p = pw.size
    h = n_m * n_p
    for j in range(n_m):
        yv = -yp[k + n_m - 1 - j]
        uv = up[k + n_m - 1 - j]
        for p in range(n_p):
            J[q, j * n_p + p] = yv * pw[p]
            J[q, h + j * n_p + p] = uv * pw[p]
    for ll in range(n_m):
        al = a[ll]
        for c in range(2 * h):
            J[q, c] -= al * J[q - 1 - ll, c]


@njit(cache=True)
def simulate_sensitivity(
    u: FloatArray, rho: FloatArray, alpha: FloatArray, beta: FloatArray, bound: float
) -> tuple[FloatArray, FloatArray, int]:  # pragma: no cover - numba
    """Free-run output and its derivatives with respect to ``theta = [alpha, beta]``.

    The sensitivities of an LPV input-output model are its regressors (built from the simulated
    output) filtered by the same time-varying denominator:
    ``J[k] = phi_k(y_hat) - sum_l a_l(rho[k]) J[k-l]``.

    Returns
    -------
    y : float64[:]
    J : float64[:, :]
        ``dy/dtheta``, shape ``(n, 2 * n_m * n_p)``.
    bad : int
        First diverged sample or -1.
    """
    n = u.size
    n_m, n_p = alpha.shape
    P = 2 * n_m * n_p
    yp = np.zeros(n + n_m)
    up = _padded(u, n_m)
    Jp = np.zeros((n + n_m, P))  # sample k at row k + n_m, zero rows before the first
    a = np.empty(n_m)
    pw = np.empty(n_p)
    bad = -1
    for k in range(n):
        acc = _sample(k, up, yp, rho[k], alpha, beta, pw, a)
        if not (abs(acc) <= bound):
            bad = k
            break
        yp[k + n_m] = acc
        _sensitivity_row(Jp, k + n_m, k, up, yp, pw, a)
    y = np.zeros(n)
    J = np.zeros((n, P))
    for k in range(n):
        y[k] = yp[k + n_m]
        for c in range(P):
            J[k, c] = Jp[k + n_m, c]
    return y, J, bad


#: Samples per block of :func:`oe_normal_equations` whose Jacobian rows are added to ``J^T J``
#: together.
_OE_BLOCK = 256


@njit(cache=True, fastmath={"reassoc", "contract"})
def _add_gram_block(H: FloatArray, T: FloatArray, L: int) -> None:  # pragma: no cover - numba
    """``H += T[:, :L] T[:, :L]^T`` on the upper triangle (``T`` holds one Jacobian column per
    row; the sums over the block may be reordered, so that they vectorise)."""
    Q = T.shape[0]
    for i in range(Q):
        for j in range(i, Q):
            s = 0.0
            for r in range(L):
                s += T[i, r] * T[j, r]
            H[i, j] += s


@njit(cache=True)
def oe_normal_equations(
    u: FloatArray,
    rho: FloatArray,
    alpha: FloatArray,
    beta: FloatArray,
    F: FloatArray,
    xd: FloatArray,
    offset: float,
    stiffness: float,
    weight: float,
    bound: float,
    with_offset: bool,
    with_stiffness: bool,
) -> tuple[float, FloatArray, FloatArray, int]:  # pragma: no cover
    """Weighted free-run cost, gradient and Gauss-Newton matrix of one record.

    Residual ``e[k] = y_hat[k] + offset + stiffness xd[k] - F[k]`` (``xd`` the displacement [m],
    used only when ``stiffness != 0`` or ``with_stiffness``); the unknowns are ``theta``, then
    the offset (``with_offset``), then the stiffness (``with_stiffness``, Jacobian column
    ``xd``). The free run and its sensitivity rows
    ``J[k] = phi_k(y_hat) - sum_l a_l(rho[k]) J[k-1-l]`` (:func:`_sample`,
    :func:`_sensitivity_row`, as in :func:`simulate_sensitivity`) are formed in blocks of
    :data:`_OE_BLOCK` samples (the Jacobian is never stored whole): each row is added to
    ``J^T e`` as it is formed, and each block to the upper triangle of ``J^T J``
    (:func:`_add_gram_block`), mirrored at the end.

    Returns
    -------
    cost : float
        ``weight * sum(e^2)`` [N^2].
    g : float64[:]
        ``weight * J^T e`` (length ``2 n_m n_p``, plus one with the offset, plus one with the
        stiffness).
    H : float64[:, :]
        ``weight * J^T J``.
    bad : int
        First diverged sample or -1 (cost, g, H are then meaningless).
    """
    n = u.size
    n_m, n_p = alpha.shape
    h = n_m * n_p
    P = 2 * h
    Q = P + (1 if with_offset else 0) + (1 if with_stiffness else 0)
    use_x = with_stiffness or stiffness != 0.0
    H = np.zeros((Q, Q))
    g = np.zeros(Q)
    cost = 0.0
    # output and input with n_m leading zeros (zero initial conditions): sample k at k + n_m
    yp = np.zeros(n + n_m)
    up = _padded(u, n_m)
    # Jacobian rows of the block at rows n_m.., the previous block's last n_m rows above them
    Jb = np.zeros((n_m + _OE_BLOCK, Q))
    T = np.empty((Q, _OE_BLOCK))  # the block's rows again, transposed
    if with_offset:
        for q in range(n_m + _OE_BLOCK):
            Jb[q, P] = 1.0
    a = np.zeros(n_m)
    pw = np.zeros(n_p)
    L = 0
    for k in range(n):
        q = n_m + L
        acc = _sample(k, up, yp, rho[k], alpha, beta, pw, a)
        if not (abs(acc) <= bound):
            return np.inf, g, H, k
        yp[k + n_m] = acc
        _sensitivity_row(Jb, q, k, up, yp, pw, a)
        if with_stiffness:
            Jb[q, Q - 1] = xd[k]
        e = acc + offset - F[k]
        if use_x:
            e += stiffness * xd[k]
        cost += e * e
        for i in range(Q):
            g[i] += Jb[q, i] * e
            T[i, L] = Jb[q, i]
        L += 1
        if L == _OE_BLOCK or k == n - 1:
            _add_gram_block(H, T, L)
            for ll in range(n_m):  # the block's last n_m rows start the next block's recursion
                for c in range(Q):
                    Jb[ll, c] = Jb[L + ll, c]
            L = 0
    for i in range(Q):
        g[i] *= weight
        for j in range(i, Q):  # the upper triangle, mirrored (exactly symmetric)
            H[i, j] *= weight
            H[j, i] = H[i, j]
    return weight * cost, g, H, -1


@njit(cache=True)
def residual_sse(
    y: FloatArray, F: FloatArray, offset: float, xd: FloatArray, stiffness: float
) -> float:  # pragma: no cover - numba
    """``sum_k (y[k] + offset + stiffness xd[k] - F[k])^2`` [N^2], in sample order, without
    allocating the residual (``xd`` is read only when ``stiffness != 0``)."""
    total = 0.0
    for k in range(y.size):
        e = y[k] + offset - F[k]
        if stiffness != 0.0:
            e += stiffness * xd[k]
        total += e * e
    return total


# ----------------------------------------------------------------------------- coefficients, poles
def split_theta(theta: np.ndarray, n_m: int, n_p: int) -> tuple[np.ndarray, np.ndarray]:
    """``theta = [alpha.ravel(), beta.ravel()]`` -> ``alpha, beta`` of shape ``(n_m, n_p)``."""
    k = n_m * n_p
    return theta[:k].reshape(n_m, n_p).copy(), theta[k : 2 * k].reshape(n_m, n_p).copy()


def frozen_poles(alpha: np.ndarray, rho_grid: np.ndarray) -> np.ndarray:
    """Poles of ``z^n + a_1(rho) z^(n-1) + ... + a_n(rho)`` for each ``rho``; shape (len, n_m)."""
    n_m, n_p = alpha.shape
    out = np.empty((rho_grid.size, n_m), dtype=complex)
    for k, r in enumerate(rho_grid):
        a = alpha @ (r ** np.arange(n_p))
        out[k] = np.roots(np.r_[1.0, a]) if n_m else np.empty(0)
    return out


def largest_frozen_pole(alpha: np.ndarray, rho_grid: np.ndarray) -> tuple[float, float, complex]:
    """Largest frozen-pole modulus over ``rho_grid``, the ``rho`` where it occurs and the pole.

    The poles are the eigenvalues of the companion matrices of ``z^n + a_1(rho) z^(n-1) + ...``,
    computed for the whole grid at once.
    """
    n_m, n_p = alpha.shape
    a = (np.asarray(rho_grid, float)[:, None] ** np.arange(n_p)) @ alpha.T  # (G, n_m)
    C = np.zeros((a.shape[0], n_m, n_m))
    C[:, 0, :] = -a
    if n_m > 1:
        C[:, np.arange(1, n_m), np.arange(n_m - 1)] = 1.0
    ev = np.linalg.eigvals(C)
    if not np.all(np.isfinite(ev)):
        return float("inf"), float(rho_grid[0]), complex("nan")
    mod = np.abs(ev)
    g, j = np.unravel_index(int(np.argmax(mod)), mod.shape)
    return float(mod[g, j]), float(rho_grid[g]), complex(ev[g, j])
