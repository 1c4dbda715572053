"""Invertibility is a capability of the model (a protocol), not a list of classes in the caller."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper.models import InvertibleModel, ScheduledForm, StaticMapForm
from mrdamper.models.bingham import BinghamModel
from mrdamper.models.lpv import LPVModel, LTIModel, TransferFunctionModel
from mrdamper.models.semiphenomenological import SP2Model
from mrdamper.models.spencer import spencer1997


def test_lpv_and_static_maps_are_invertible_lti_and_spencer_are_not() -> None:
    lpv = LPVModel(alpha=np.array([[-0.5, 0.1]]), beta=np.array([[2.0, 1.0]]), input_signal="v")
    lti = LTIModel(alpha=np.array([[-0.5]]), beta=np.array([[2.0]]), input_signal="v")
    sp2 = SP2Model(S=(800.0, 60.0, 0.0, 1000.0, 0.0), input_range=(0.0, 1.0))
    bingham = BinghamModel(fc=(100.0, 500.0), c0=(1000.0,), input_range=(0.0, 1.0))
    assert isinstance(lpv, InvertibleModel) and isinstance(lpv.inverse_form(), ScheduledForm)
    for m in (sp2, bingham):
        assert isinstance(m, InvertibleModel) and isinstance(m.inverse_form(), StaticMapForm)
    assert not isinstance(lti, InvertibleModel) and not isinstance(lti, LPVModel)
    assert isinstance(lti, TransferFunctionModel) and isinstance(lpv, TransferFunctionModel)
    assert not isinstance(spencer1997(), InvertibleModel)


@pytest.mark.parametrize("v_eps", [0.0, 0.01])
def test_bingham_static_form_reproduces_its_force(v_eps: float) -> None:
    from mrdamper.control.inverse._inverse_kernels import sp_force1

    m = BinghamModel(fc=(100.0, 500.0), c0=(1000.0, 300.0), f0=5.0, v_eps=v_eps)
    f = m.inverse_form()
    for v, i in ((0.1, 0.3), (-0.05, 0.9), (0.002, 0.5)):
        expected = float(m.force(np.array([0.0]), np.array([v]), np.array([i]))[0])
        got = sp_force1(0.0, v, i, f.comp, f.power, f.theta, f.f0)
        assert got == pytest.approx(expected, rel=1e-12)
