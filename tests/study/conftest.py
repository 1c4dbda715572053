"""Test doubles for the study tests: tiny registered model kinds and a short synthetic DoE.

The doubles stand in for the real estimators where a test is about the study machinery (failure
rows, determinism, executors); the tests that exercise the real pieces use the registry's kinds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import IdentificationError, SimulationDivergedError
from mrdamper.models import Estimator, FittedModel, register


@dataclass(frozen=True)
class ToyModel(FittedModel):
    """F = theta0 * tanh(v / 0.02) + theta1 * i * tanh(v / 0.02) + theta2 * v (static, free run)."""

    kind = "toy"
    theta: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def predict(self, experiment: Experiment) -> np.ndarray:
        i = self.electrical_input(experiment)
        s = np.tanh(experiment.v / 0.02)
        return self.theta[0] * s + self.theta[1] * i * s + self.theta[2] * experiment.v


@dataclass
class ToyEstimator(Estimator):
    kind = "toy"
    input: str = "i"
    seed: int = 0
    noise: float = 0.0  # perturb the solution with seeded noise (tests seed propagation)

    def fit(self, data):  # type: ignore[no-untyped-def]
        exps = self._as_set(data)
        X = np.concatenate(
            [
                np.column_stack(
                    [np.tanh(e.v / 0.02), e.electrical(self.input) * np.tanh(e.v / 0.02), e.v]
                )
                for e in exps
            ]
        )
        y = np.concatenate([e.F for e in exps])
        theta = np.linalg.lstsq(X, y, rcond=None)[0]
        theta = theta + self.noise * np.random.default_rng(self.seed).standard_normal(3)
        i_all = np.concatenate([e.electrical(self.input) for e in exps])
        return ToyModel(
            theta=theta,
            input=self.input,
            input_range=(float(i_all.min()), float(i_all.max())),
            provenance={"records": [e.name for e in exps]},
        )


@dataclass(frozen=True)
class FailModel(FittedModel):
    kind = "toyfail"

    def predict(self, experiment: Experiment) -> np.ndarray:  # pragma: no cover - never fitted
        return np.zeros(experiment.n)


@dataclass
class FailEstimator(Estimator):
    kind = "toyfail"
    input: str = "i"

    def fit(self, data):  # type: ignore[no-untyped-def]
        raise IdentificationError("toyfail: regression matrix is singular (rank 1 < 3)")


@dataclass(frozen=True)
class DivergeModel(FittedModel):
    kind = "toydiverge"

    def predict(self, experiment: Experiment) -> np.ndarray:
        raise SimulationDivergedError("toydiverge", 7, "state exceeded 1e6 N")


@dataclass
class DivergeEstimator(Estimator):
    kind = "toydiverge"
    input: str = "i"

    def fit(self, data):  # type: ignore[no-untyped-def]
        return DivergeModel(input=self.input, input_range=(0.0, 1.0))


register(ToyEstimator, ToyModel)
register(FailEstimator, FailModel)
register(DivergeEstimator, DivergeModel)


def _record(
    name: str, fs: float, duration: float, i: np.ndarray | float, seed: int, **meta: object
) -> Experiment:
    rng = np.random.default_rng(seed)
    t = np.arange(round(duration * fs)) / fs
    f = 1.5 + 0.5 * rng.random()
    x = 0.01 * np.sin(2 * np.pi * f * t)
    v = 0.01 * 2 * np.pi * f * np.cos(2 * np.pi * f * t)
    cur = np.broadcast_to(np.asarray(i, dtype=float), t.shape).copy()
    F = (200 + 600 * cur) * np.tanh(v / 0.02) + 300 * v + 5 * rng.standard_normal(t.size)
    return Experiment(t=t, x=x, v=v, F=F, i=cur, name=name, metadata=meta)


def small_doe(fs: float = 200.0, reps: int = 3, seed: int = 0) -> ExperimentSet:
    """A tiny DoE-like set: experiments 1-3 (varying current) and 6-8 (stepped current)."""
    recs = []
    rng = np.random.default_rng(seed)
    for exp, pattern in ((1, "ICPS"), (2, "APRBS"), (3, "PRBS"), (6, "SC"), (7, "SC"), (8, "SC")):
        for rep in range(1, reps + 1):
            s = int(rng.integers(1 << 30))
            if pattern == "SC":
                n = int(1.5 * fs)
                cur = np.concatenate([np.full(n, lev) for lev in (0.0, 0.5, 1.0)])
                recs.append(
                    _record(
                        f"exp{exp}_rep{rep:02d}",
                        fs,
                        4.5,
                        cur,
                        s,
                        experiment=exp,
                        replicate=rep,
                        pattern=pattern,
                    )
                )
            else:
                n = int(2.0 * fs)
                cur = np.repeat(np.random.default_rng(s).uniform(0, 1, 8), n // 8)
                recs.append(
                    _record(
                        f"exp{exp}_rep{rep:02d}",
                        fs,
                        2.0,
                        cur,
                        s,
                        experiment=exp,
                        replicate=rep,
                        pattern=pattern,
                    )
                )
    return ExperimentSet(recs, name="small-doe")


@pytest.fixture(scope="session")
def doe() -> ExperimentSet:
    return small_doe()


@pytest.fixture(scope="session")
def rig_damper():
    """The shipped reference damper when installed, else a toy damper (rig mechanics still real)."""
    try:
        from mrdamper.rig import reference_damper

        return reference_damper()
    except (ImportError, FileNotFoundError):
        return ToyModel(theta=np.array([300.0, 900.0, 800.0]), input_range=(0.0, 1.0))
