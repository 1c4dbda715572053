"""Long-campaign identification: evenly spread windows, chunked least squares, full-data checks.

The window threshold is lowered here so that short virtual-rig records take the long-campaign
path; below the threshold every estimator sees every sample (checked too).
"""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.models import _scale, get_estimator
from mrdamper.models.narx import candidate_structure
from mrdamper.models.narx import kernels as NK


@pytest.fixture(scope="module")
def records():  # type: ignore[no-untyped-def]
    from mrdamper.rig import VirtualRig
    from mrdamper.rig.doe import DoeSequence, make_record, record_seeds

    rig = VirtualRig(fs=1000.0)
    spec = DoeSequence(2, "Road Profile", "APRBS", 30.0, 2, 4.5)
    return [make_record(spec, k + 1, s, rig) for k, s in enumerate(record_seeds(3, 2))]


@pytest.fixture()
def small_windows(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_scale, "WINDOW_THRESHOLD", 20_000)
    for name in (
        "WINDOW_BUDGET",
        "WINDOW_BUDGET_SPENCER",
        "WINDOW_BUDGET_P15",
        "WINDOW_BUDGET_LPV",
    ):
        monkeypatch.setattr(_scale, name, 16_000)
    monkeypatch.setattr(_scale, "WINDOW_SECONDS", 4.0)
    monkeypatch.setattr(_scale, "WINDOW_SECONDS_LPV", 4.0)


def test_plan_windows_spread_and_bounded() -> None:
    assert _scale.plan_windows([1000, 2000], 1000.0, threshold=5000) is None
    plan = _scale.plan_windows(
        [3_600_000, 1_800_000], 1000.0, threshold=1000, budget=600_000, seconds=20.0
    )
    assert plan is not None
    used = sum(b - a for _, a, b in plan)
    assert used <= 600_000 + 20_000
    assert {r for r, _, _ in plan} == {0, 1}
    per = [sum(1 for r, _, _ in plan if r == k) for k in (0, 1)]
    assert per[0] == pytest.approx(2 * per[1], abs=1)  # in proportion to the record length
    for r, a, b in plan:
        assert 0 <= a < b <= (3_600_000, 1_800_000)[r]
    starts = [a for r, a, _ in plan if r == 0]
    assert starts[0] == 0 and starts[-1] == 3_600_000 - 20_000  # from the start to the end


def test_chunked_qr_matches_lstsq(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(0)
    base, cand = candidate_structure(2, 1, 2)
    terms = cand[:8]
    recs = [np.ascontiguousarray(rng.standard_normal((5, n))) for n in (700, 1300)]
    w = [0.5, 2.0]
    monkeypatch.setattr(_scale, "QR_BLOCK", 256)  # several blocks per record
    R, z = _scale.chunked_qr(recs, w, base, terms, 2, NK.fill_candidates)
    rows, rhs = [], []
    for S, wk in zip(recs, w):
        Phi = np.empty((S.shape[1] - 2, terms.shape[0]))
        NK.fill_candidates(S, base, terms, 2, S.shape[1], Phi)
        rows.append(Phi * np.sqrt(wk))
        rhs.append(S[0, 2:] * np.sqrt(wk))
    X, y = np.vstack(rows), np.concatenate(rhs)
    ref = np.linalg.lstsq(X, y, rcond=None)[0]
    got = np.linalg.solve(R, z)
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        np.linalg.svd(R, compute_uv=False), np.linalg.svd(X, compute_uv=False), rtol=1e-9
    )


@pytest.mark.slow
def test_below_threshold_uses_every_sample(records) -> None:  # type: ignore[no-untyped-def]
    m = get_estimator("narx").fit(records)
    assert "refine_windows" not in m.provenance and "full_data_check" not in m.provenance
    m = get_estimator("lpv").fit(records)
    assert "oe_windows" not in m.provenance


@pytest.mark.parametrize("kind", ["lpv", "narx", "spencer", "p15"])
def test_windows_and_full_data_check(kind: str, records, small_windows) -> None:  # type: ignore[no-untyped-def]
    settings = {"n_starts": 1, "max_nfev": 20} if kind == "spencer" else {}
    m = get_estimator(kind, **settings).fit(records)
    prov = dict(m.provenance)
    win = prov.get("windows") or prov.get("oe_windows") or prov.get("refine_windows")
    assert win is not None, sorted(prov)
    assert win["samples_total"] == sum(r.n for r in records)
    assert win["samples_used"] < win["samples_total"]
    check = prov["full_data_check"]
    assert check and all(np.isfinite(float(v)) for v in check.values())
    lo, hi = m.input_range
    assert lo <= min(float(r.i.min()) for r in records) and hi >= max(
        float(r.i.max()) for r in records
    )
    for r in records:  # every record simulates in the identified range
        assert np.all(np.isfinite(m.predict(r)))


def test_lpv_qr_factor_matches_full_regression(monkeypatch: pytest.MonkeyPatch) -> None:
    from mrdamper.models.lpv import kernels as LK

    rng = np.random.default_rng(1)
    n = 3000
    y, u, rho = rng.standard_normal(n), rng.standard_normal(n), rng.uniform(0, 1, n)
    starts = np.array([0, 1100, n], dtype=np.int64)
    w = np.array([0.7, 1.6])
    monkeypatch.setattr(_scale, "QR_BLOCK", 300)
    for with_const in (False, True):
        X, t = LK.build_regressors(y, u, rho, starts, w, 3, 3, with_const)
        R, z = _scale.lpv_qr_factor(y, u, rho, starts, w, 3, 3, with_const, LK.build_regressors)
        np.testing.assert_allclose(
            np.linalg.solve(R, z), np.linalg.lstsq(X, t, rcond=None)[0], rtol=1e-8
        )
        np.testing.assert_allclose(
            np.linalg.svd(R, compute_uv=False), np.linalg.svd(X, compute_uv=False), rtol=1e-9
        )


def test_lpv_least_squares_record_by_record_matches_concatenated(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from mrdamper.models.lpv import fit as _lpv_fit

    rng = np.random.default_rng(2)
    U = [rng.standard_normal(n) for n in (1500, 2500)]
    R = [rng.uniform(0, 1, n) for n in (1500, 2500)]
    F = [
        np.convolve(u, [0.0, 0.5, 0.2], mode="full")[: u.size] * (1 + r)
        + 3.0
        + 0.01 * rng.standard_normal(u.size)
        for u, r in zip(U, R)
    ]
    rec = _lpv_fit.Records(F=F, u=U, rho=R, weights=np.array([0.8, 1.2]))
    ref = _lpv_fit.ls_identify(rec, 2, 2, True)
    monkeypatch.setattr(_scale, "WINDOW_THRESHOLD", 100)
    got = _lpv_fit.ls_identify(rec, 2, 2, True)
    np.testing.assert_allclose(got.theta, ref.theta, rtol=1e-9, atol=1e-12)
    assert got.offset == pytest.approx(ref.offset, rel=1e-9)
    assert got.n_eq == ref.n_eq and got.solver == ref.solver
    assert _scale.distinct_levels([np.array([0.0, 0.0, 1.0]), np.array([2.0, 1.0])], 1e-9) == 3
