"""Reference-model records: reproducible from the seed, inside the training velocity and input
ranges, force from the reference model; bad settings refused."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper import DataValidationError, Experiment
from mrdamper.models.augment import reference_records
from mrdamper.rig import reference_damper


def _train() -> list[Experiment]:
    out = []
    for k, (amp, f, lev) in enumerate(((0.01, 1.0, 0.0), (0.005, 3.0, 0.5), (0.002, 5.0, 1.0))):
        t = np.arange(2000) / 500.0
        out.append(
            Experiment(
                t=t,
                x=amp * np.sin(2 * np.pi * f * t),
                v=amp * 2 * np.pi * f * np.cos(2 * np.pi * f * t),
                F=np.zeros(t.size),
                i=np.full(t.size, lev),
                name=f"r{k}",
            )
        )
    return out


@pytest.mark.parametrize("motion", ["sweep", "noise"])
def test_reference_records(motion: str) -> None:
    ref = reference_damper()
    train = _train()
    a, used = reference_records(
        train, reference=ref, n_records=2, duration=4.0, motion=motion, seed=3
    )
    b, _ = reference_records(train, reference=ref, n_records=2, duration=4.0, motion=motion, seed=3)
    c, _ = reference_records(train, reference=ref, n_records=2, duration=4.0, motion=motion, seed=4)
    assert used.kind == "spencer" and a.names == ["reference_0", "reference_1"]
    v_max = max(float(np.abs(e.v).max()) for e in train)
    for ea, eb, ec in zip(a, b, c):
        assert ea.fs == 500.0 and ea.n == 2000
        assert ea.F.tobytes() == eb.F.tobytes() and ea.v.tobytes() == eb.v.tobytes()
        assert not np.array_equal(ea.v, ec.v)
        assert float(np.abs(ea.v).max()) <= v_max * (1 + 1e-12)
        assert 0.0 <= ea.i.min() and ea.i.max() <= 1.0 and np.unique(ea.i).size > 1
        np.testing.assert_array_equal(ea.F, used.predict(ea))


def test_reference_records_refuses_bad_settings() -> None:
    with pytest.raises(DataValidationError, match="max_frequency"):
        reference_records(_train(), reference=reference_damper(), max_frequency=400.0)
    with pytest.raises(DataValidationError, match="motion"):
        reference_records(_train(), reference=reference_damper(), motion="pink")
    with pytest.raises(DataValidationError, match="n_records"):
        reference_records(_train(), reference=reference_damper(), n_records=0)
