"""Fixtures shared by the model tests."""

from __future__ import annotations

import numpy as np
import pytest

from mrdamper import Experiment
from mrdamper.rig import VirtualRig, reference_damper


@pytest.fixture(scope="session")
def rig_data() -> tuple[list[Experiment], list[Experiment]]:
    """Short rig sines at three currents (training) and a 1-10 Hz small-stroke chirp (test)."""
    fs = 1000.0
    rig = VirtualRig(damper=reference_damper("quiroz2022"), fs=fs)
    train, seed = [], 0
    for amp, f in ((0.015, 0.5), (0.005, 2.0), (0.002, 5.0)):
        t = np.arange(round(2.5 / f * fs)) / fs
        x = amp * np.sin(2 * np.pi * f * t) * np.clip(t * f, 0.0, 1.0)
        for cur in (0.0, 0.5, 1.0):
            seed += 1
            train.append(
                rig.run(
                    x,
                    np.full(t.size, cur),
                    seed=seed,
                    name=f"s{amp}_{f}_{cur}",
                    metadata={"current": cur},
                )
            )
    t = np.arange(4000) / fs
    f_inst = 1.0 + 9.0 * t / t[-1]
    x = 0.05 / (2 * np.pi * f_inst) * np.sin(2 * np.pi * np.cumsum(f_inst) / fs)
    test = [rig.run(x, np.full(t.size, 0.5), seed=99, name="chirp", metadata={"current": 0.5})]
    return train, test
