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
    assert form.gains is s.gains
