"""Maximum-length-sequence properties of the PRBS generator."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrdamper.errors import DataValidationError
from mrdamper.signals import PRIMITIVE_TAPS, mls, prbs
from mrdamper.signals.aprbs import run_starts


def _prime_factors(m: int) -> list[int]:
    out, p = [], 2
    while p * p <= m:
        if m % p == 0:
            out.append(p)
            while m % p == 0:
                m //= p
        p += 1
    if m > 1:
        out.append(m)
    return out


def _polymulmod(a: int, b: int, mod: int, deg: int) -> int:
    """Product of GF(2) polynomials a*b reduced modulo ``mod`` (degree ``deg``); ints as bit
    sets."""
    r = 0
    while b:
        if b & 1:
            r ^= a
        b >>= 1
        a <<= 1
        if a >> deg & 1:
            a ^= mod
    return r


def _x_pow(e: int, mod: int, deg: int) -> int:
    result, base = 1, 0b10  # the polynomial "x"
    while e:
        if e & 1:
            result = _polymulmod(result, base, mod, deg)
        base = _polymulmod(base, base, mod, deg)
        e >>= 1
    return result


@pytest.mark.parametrize("order", sorted(PRIMITIVE_TAPS))
def test_taps_table_is_primitive(order: int) -> None:
    # x is a generator of GF(2^n)* iff x^(2^n-1) = 1 and x^((2^n-1)/q) != 1 for each prime q | 2^n-1
    taps = PRIMITIVE_TAPS[order]
    assert taps[0] == order
    poly = 1 | sum(1 << t for t in taps)
    m = (1 << order) - 1
    assert _x_pow(m, poly, order) == 1
    for q in _prime_factors(m):
        assert _x_pow(m // q, poly, order) != 1, f"order {order}: x^(m/{q}) = 1, not primitive"


@pytest.mark.parametrize("order", range(2, 19))
def test_period_is_2n_minus_1(order: int) -> None:
    N = (1 << order) - 1
    b = mls(order, seed=order, n_bits=2 * N + 5)
    assert np.array_equal(b[:N], b[N : 2 * N])
    # no shorter period: the N register states are distinct, so no shift d < N reproduces the bits
    windows = np.lib.stride_tricks.sliding_window_view(b[: N + order - 1], order)
    states = windows @ (1 << np.arange(order))
    assert np.unique(states).size == N


@pytest.mark.parametrize("order", [3, 5, 7, 10, 13])
def test_balance_and_run_lengths(order: int) -> None:
    N = (1 << order) - 1
    b = mls(order, seed=1)
    assert int(b.sum()) == 2 ** (order - 1)
    # runs counted circularly: rotate so the sequence starts at a run boundary
    k = int(np.flatnonzero(b != b[-1])[0])
    r = np.roll(b, -k)
    starts = run_starts(r)
    lengths = np.diff(np.append(starts, N))
    values = r[starts]
    assert starts.size == 2 ** (order - 1)
    for length in range(1, order - 1):
        expected = 2 ** (order - length - 2)
        assert np.sum((lengths == length) & (values == 1)) == expected
        assert np.sum((lengths == length) & (values == 0)) == expected
    assert np.sum((lengths == order) & (values == 1)) == 1
    assert np.sum((lengths == order - 1) & (values == 0)) == 1


@pytest.mark.parametrize("order", [4, 6, 9, 11])
def test_two_valued_circular_autocorrelation(order: int) -> None:
    N = (1 << order) - 1
    s = 1.0 - 2.0 * mls(order, seed=7)
    R = np.real(np.fft.ifft(np.abs(np.fft.fft(s)) ** 2)) / N
    assert R[0] == pytest.approx(1.0)
    np.testing.assert_allclose(R[1:], -1.0 / N, atol=1e-9)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32), order=st.integers(2, 12))
def test_seed_is_a_cyclic_shift(seed: int, order: int) -> None:
    N = (1 << order) - 1
    a, b = mls(order, seed=0), mls(order, seed=seed)
    doubled = np.concatenate([a, a])
    shifts = [d for d in range(N) if np.array_equal(doubled[d : d + N], b)]
    assert len(shifts) == 1


def test_prbs_signal_holds_and_levels() -> None:
    x = prbs(1000.0, 3.0, clock_period=0.05, levels=(0.2, 0.9), seed=5)
    assert x.size == 3000
    assert set(np.unique(x).tolist()) == {0.2, 0.9}
    lengths = np.diff(np.append(run_starts(x), x.size))
    assert np.all(lengths[:-1] % 50 == 0)  # whole clock periods (the last run may be cut)
    # the default order covers the record: 60 clocks need order 6 (period 63), no repetition
    assert np.array_equal(prbs(1000.0, 3.0, clock_period=0.05, levels=(0.2, 0.9), seed=5), x)
    assert not np.array_equal(prbs(1000.0, 3.0, clock_period=0.05, levels=(0.2, 0.9), seed=6), x)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"clock_period": 0.0}, "clock_period"),
        ({"clock_period": 1e-5}, "clock_period"),
        ({"clock_period": 0.1, "levels": (1.0, 1.0)}, "levels"),
        ({"clock_period": 0.1, "order": 40}, "order"),
        ({"clock_period": 0.1, "seed": None}, "seed"),
        ({"clock_period": 0.1, "seed": -1}, "seed"),
        ({"clock_period": 0.1, "seed": np.random.default_rng(0)}, "seed"),
    ],
)
def test_prbs_rejects_bad_arguments(kwargs: dict, field: str) -> None:
    kw = {"seed": 0, **kwargs}
    with pytest.raises(DataValidationError) as info:
        prbs(1000.0, 1.0, **kw)
    assert info.value.field == field


def test_bad_time_grid() -> None:
    with pytest.raises(DataValidationError, match="fs"):
        prbs(-1.0, 1.0, clock_period=0.1, seed=0)
    with pytest.raises(DataValidationError, match="duration"):
        prbs(1000.0, float("nan"), clock_period=0.1, seed=0)
