"""The controller's forms: built once in Python with the types the compiled kernels take."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.control.inverse._forms import ControllerForm, InverseForm, inverse_form
from mrdamper.control.loop._loop import controller_form, loop_setup
from mrdamper.control.loop.car import Controller, LinearDamper, QuarterCar, bump_road


def test_inverse_form_has_the_kernels_types() -> None:
    inv = inverse_form(lam=3.0, n_grid=16, comp=[3], power=[0], theta=[1500])
    assert isinstance(inv, InverseForm)
    assert inv.lam2 == 9.0 and inv.n_grid == 16 and inv.horizon == 1 and inv.lag == -1.0
    assert inv.comp.dtype == np.int64 and inv.power.dtype == np.int64
    assert inv.theta.dtype == np.float64 and inv.alpha.shape == (1, 1)
    assert all(type(getattr(inv, f)) is float for f in ("f0", "offset", "lag", "blend", "stroke"))
    assert not inv.is_lpv and type(inv.mode) is int


def test_controller_form_of_a_run() -> None:
    road = bump_road(duration=0.5, fs=1000.0)
    s = loop_setup(
        LinearDamper(1500.0),
        road,
        Controller("skyhook"),
        QuarterCar(),
        reg=None,
        v_ref=0.3,
        rate=None,
        i_range=None,
        substeps=2,
    )
    form = controller_form(s, 8)
    assert isinstance(form, ControllerForm)
    # the control sample as the kernels count it (n_sub plant steps of h), the road's sample
    assert form.dt_c == s.n_sub * s.h == pytest.approx(1.0 / road.fs, rel=1e-12)
    assert form.inverse.n_grid == 8
    assert form.lo == s.lo and form.hi == s.hi and form.inverse.lam2 == s.lam**2
    np.testing.assert_array_equal(form.gains, s.gains)
    assert not form.gains.flags.writeable


def test_every_form_array_is_read_only_so_the_loop_compiles_once() -> None:
    """A static map's form and an LPV model's (whose frozen coefficients are read-only) have one
    numba type: the quarter-car loop kernels compile one signature for every kind."""
    numba = pytest.importorskip("numba")
    static = inverse_form(lam=3.0, n_grid=16, comp=[3], power=[0], theta=[1500.0])
    frozen_alpha = np.ones((2, 3))
    frozen_alpha.flags.writeable = False
    lpv = inverse_form(
        lam=3.0,
        n_grid=16,
        is_lpv=True,
        alpha=frozen_alpha,
        beta=np.ones((2, 3)),
        gm=np.ones((3, 2)),
        gc=np.ones((3, 2)),
        mu_high=np.ones(2),
        mu_low=np.ones(2),
    )
    arrays = [a for a in static if isinstance(a, np.ndarray)]
    assert arrays and not any(a.flags.writeable for a in arrays)
    assert numba.typeof(static) == numba.typeof(lpv)
    given = np.array([1.0, 2.0])
    assert inverse_form(lam=1.0, n_grid=4, mu_high=given).mu_high.base is given  # a view, no copy
