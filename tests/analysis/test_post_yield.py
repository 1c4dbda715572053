"""Outer slopes re-estimated on post-yield samples (``post_yield_slopes``, ``outer_slopes=``)."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment
from mrdamper.analysis import (
    fit_zone_laws,
    fit_zones,
    post_yield_slopes,
    zone_fits_binned,
    zone_fits_by_level,
)


def _unyielded_data(slope: float = 1000.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Post-yield line ``200 + slope |v|`` beyond 10 mm/s, with a share of samples past the
    limit that have not yielded (force 30 % below the line up to 30 mm/s, within three zone
    limits)."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(-0.2, 0.2, 20000)
    F = np.sign(v) * np.minimum(2e4 * np.abs(v), 200 + slope * np.abs(v))
    late = (np.abs(v) < 0.03) & (rng.uniform(size=v.size) < 0.7)
    F[late] *= 0.7
    return v, F


def test_post_yield_slope_is_the_line_beyond_three_limits() -> None:
    v, F = _unyielded_data()
    zf = fit_zones(v, F)
    py = post_yield_slopes(zf, v, F)
    assert zf.m[2] > 1100.0 and zf.m[0] > 1100.0  # the unyielded samples steepen the lines
    assert py.m[0] == pytest.approx(1000.0, rel=1e-6)
    assert py.m[2] == pytest.approx(1000.0, rel=1e-6)
    assert py.m[1] == zf.m[1] and (py.v_low, py.v_high) == (zf.v_low, zf.v_high)
    # continuous at both limits: the central line's value there
    for j, lim in ((0, zf.v_low), (2, zf.v_high)):
        assert py.m[j] * lim + py.c[j] == pytest.approx(zf.m[1] * lim + zf.c[1], abs=1e-9)


def test_a_side_without_enough_post_yield_samples_keeps_its_zone_slope() -> None:
    v, F = _unyielded_data()
    zf = fit_zones(v, F)
    assert post_yield_slopes(zf, v, F, min_samples=10**6) == zf
    narrow = 0.2 / (1.2 * zf.v_high)  # beyond it the velocities span 1.2 x: ill-determined
    assert post_yield_slopes(zf, v, F, factor=narrow) == zf


def test_a_slope_outside_the_range_of_eq_20_keeps_the_zone_slope() -> None:
    v, F = _unyielded_data()
    F = np.where(np.abs(v) > 0.1, F - 3000 * (np.abs(v) - 0.1) * np.sign(v), F)  # falls off
    zf = fit_zones(v, F)
    py = post_yield_slopes(zf, v, F, factor=8.0)  # only the falling part: negative slope
    assert py.m == zf.m


def test_level_fits_take_the_outer_slope_option_and_refuse_an_unknown_one() -> None:
    v, F = _unyielded_data()
    rho = np.repeat([0.0, 1.0], v.size // 2)
    exps = [
        Experiment(
            t=np.arange(v.size // 2) * 1e-3,
            x=np.zeros(v.size // 2),
            v=v[k::2],
            F=F[k::2] * (1 + lev),
            i=np.full(v.size // 2, lev),
            name=f"l{lev}",
            metadata={"current": lev},
        )
        for k, lev in enumerate((0.0, 1.0))
    ]
    zones = zone_fits_by_level(exps)
    post = zone_fits_by_level(exps, outer_slopes="post-yield")
    for z, p, lev in zip(zones, post, (0.0, 1.0), strict=True):
        assert p.m[2] == pytest.approx(1000.0 * (1 + lev), rel=1e-6)
        assert z.m[2] > 1.1 * p.m[2]
    binned = zone_fits_binned([v], [F], [rho], n_bins=2, outer_slopes="post-yield")
    assert all(f.m[2] < 1100.0 for f in binned)
    laws = fit_zone_laws(exps, degree=1, outer_slopes="post-yield")
    assert laws.m(0.5)[2] == pytest.approx(1500.0, rel=0.03)
    with pytest.raises(DataValidationError, match="outer_slopes"):
        zone_fits_by_level(exps, outer_slopes="steep")  # type: ignore[arg-type]


def test_data_of_another_length_is_refused() -> None:
    v, F = _unyielded_data()
    zf = fit_zones(v, F)
    with pytest.raises(DataValidationError, match="F: has 19999 samples but 'v' has 20000"):
        post_yield_slopes(zf, v, F[:-1])


class _Laws:
    """Stands for ZoneLaws in the rule below (it reads only ``problems()``)."""

    def __init__(self, name: str, bad: bool) -> None:
        self.name, self.bad = name, bad

    def problems(self) -> list[str]:
        return [f"{self.name}: m3/m2 at rho=1 is 1.2, expected in [0, 1]"] if self.bad else []


def _fitter(post_bad: bool, zones_bad: bool, calls: list[str]):  # type: ignore[no-untyped-def]
    import warnings

    from mrdamper.errors import IdentificationError

    def fit(outer: str, strict: bool) -> _Laws:
        calls.append(outer)
        laws = _Laws(outer, post_bad if outer == "post-yield" else zones_bad)
        if laws.bad and strict:
            raise IdentificationError("zone laws break the paper's assumptions")
        warnings.warn(f"fitted {outer}", UserWarning, stacklevel=1)
        return laws

    return fit


def test_the_eq_20_rule_takes_the_regression_only_where_it_alone_keeps_eq_20() -> None:
    from mrdamper.analysis.laws import laws_keeping_eq_20
    from mrdamper.errors import IdentificationError

    calls: list[str] = []
    with pytest.warns(UserWarning, match="fitted post-yield"):
        laws, used, note = laws_keeping_eq_20(_fitter(False, False, calls), strict=True)
    assert (laws.name, used, note, calls) == ("post-yield", "post-yield", "", ["post-yield"])

    calls = []
    with pytest.warns(UserWarning) as seen:  # the discarded post-yield fit's warnings are not shown
        laws, used, note = laws_keeping_eq_20(_fitter(True, False, calls), strict=True)
    assert [str(w.message) for w in seen] == ["fitted zones"]
    assert (laws.name, used, calls) == ("zones", "zones", ["post-yield", "zones"])
    assert note.startswith("post-yield outer slopes give laws that break eq. (20) (post-yield: m3")

    # neither keeps eq. (20): not strict, the post-yield laws and their warnings; strict, an error
    with pytest.warns(UserWarning) as seen:
        laws, used, note = laws_keeping_eq_20(_fitter(True, True, []), strict=False)
    assert "fitted post-yield" in [str(w.message) for w in seen]
    assert (laws.name, used, note) == ("post-yield", "post-yield", "")
    with pytest.raises(IdentificationError, match="break the paper's assumptions"):
        laws_keeping_eq_20(_fitter(True, True, []), strict=True)
