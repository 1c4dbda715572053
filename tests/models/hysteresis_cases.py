"""Shared checks of the one-state hysteresis families (tanh, boucwen, dahl, lugre).

Each family's test module calls these with its own true parameters: a known-answer
identification on records simulated by the true model, the per-sample step against the fused
free run, the JSON round trip, the single-level fit and the one-line parameter errors.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper.data import Experiment, ExperimentSet
from mrdamper.errors import DataValidationError, SchemaError
from mrdamper.models import get_estimator, load_model, model_class
from mrdamper.models.step import STATUS_OK, run_step


def record(
    seed: int, *, duration: float = 2.0, fs: float = 1000.0, amp: float = 0.008, name: str = "r"
) -> Experiment:
    """Multi-sine displacement with a seeded stepped current in [0, 1] A (force left at zero)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs)) / fs
    freqs = np.array([1.1, 2.7, 4.3])
    ph = rng.uniform(0, 2 * np.pi, freqs.size)
    a = amp / np.array([1.0, 2.0, 3.0])
    w = 2 * np.pi * freqs[:, None]
    x = (a[:, None] * np.sin(w * t + ph[:, None])).sum(0)
    v = (a[:, None] * w * np.cos(w * t + ph[:, None])).sum(0)
    levels = rng.uniform(0.0, 1.0, int(np.ceil(duration / 0.25)) + 1)
    i = levels[(t / 0.25).astype(int)]
    return Experiment(t=t, x=x, v=v, F=np.zeros_like(t), i=i, name=name)


def truth(kind: str, params: dict[str, float], **common: Any) -> Any:
    return model_class(kind)(**params, input="i", input_range=(0.0, 1.0), **common)


def simulated(model: Any, seeds: tuple[int, ...], **kw: Any) -> ExperimentSet:
    """Records whose force is the model's own free run."""
    out = []
    for s in seeds:
        e = record(s, name=f"r{s}", **kw)
        out.append(e.replace(F=model.predict(e)))
    return ExperimentSet(out)


def check_known_answer(
    kind: str,
    params: dict[str, float],
    compare: tuple[str, ...],
    rel: float = 2e-2,
    **settings: Any,
) -> Any:
    """Fit records simulated by the true model (with the drive lag ``eta`` of the settings, if
    any); the parameters in ``compare`` come back."""
    model = truth(kind, params, eta=settings.get("eta") or 0.0)
    train = simulated(model, (11, 12))
    est = get_estimator(kind, ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200, **settings)
    fit = est.fit(train)
    assert fit.provenance["mean_record_esr"] < 1e-6, fit.provenance["mean_record_esr"]
    for name in compare:
        assert getattr(fit, name) == pytest.approx(params[name], rel=rel, abs=1e-6), name
    fresh = simulated(model, (99,))[0]
    assert fit.with_range_policy("ignore").score(fresh).esr < 1e-5
    assert fit.provenance["step_check"]["passed"]
    return fit


def check_step_equals_predict(kind: str, params: dict[str, float], **common: Any) -> None:
    """run_step of the model's step reproduces predict exactly on a record."""
    model = truth(kind, params, **common)
    e = record(5, duration=1.0)
    F = model.predict(e)
    step = model.step(dt=e.dt, vmax=float(np.max(np.abs(e.v))))
    assert model.substeps_for(e) == max(1, round(e.dt / step.form.max_h))
    F_step, status, sample = run_step(step, e.x, e.v, e.i, e.dt)
    assert status == STATUS_OK and sample == -1
    np.testing.assert_array_equal(F_step, F)
    assert step.kind == kind and step.dt is None
    assert step.feedthrough == (model.eta == 0.0)  # with a lag the force reads the state u
    np.testing.assert_array_equal(step.initial_state(0.0, 0.0, 0.3), [0.0, 0.3])


def check_round_trip(kind: str, params: dict[str, float], tmp_path: Path) -> None:
    model = truth(kind, params, eta=40.0)
    path = model.save(tmp_path / f"{kind}.json")
    back = load_model(path)
    assert back == model and type(back) is type(model)
    e = record(3, duration=0.5)
    np.testing.assert_array_equal(back.predict(e), model.predict(e))
    with pytest.raises(FileExistsError):
        model.save(path)
    data = model.to_dict()
    data["kind"] = "spencer" if kind != "spencer" else "lpv"
    with pytest.raises(SchemaError, match="^kind: file holds"):
        model_class(kind).from_dict(data)


def check_single_level(kind: str, params: dict[str, float], zero: tuple[str, ...]) -> Any:
    """One current level: the input-dependent terms are constants (fixed at 0), with a note."""
    model = truth(kind, params)
    exps = []
    for s in (7, 8):
        e = record(s, duration=1.0, name=f"c{s}")
        e = e.replace(i=np.full(e.n, 0.5))
        exps.append(e.replace(F=model.predict(e)))
    est = get_estimator(kind, n_starts=1, max_nfev=40)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = est.fit(exps)
    notes = [str(w.message) for w in caught if w.category is UserWarning]
    assert any(n.startswith(f"{kind}: trained at one i level") for n in notes), notes
    assert fit.input_range == (0.5, 0.5)
    for name in zero:
        assert getattr(fit, name) == 0.0, name
    assert fit.provenance["mean_record_esr"] < 1e-2
    return fit


def check_bad_values(kind: str, params: dict[str, float], field: str, value: float) -> None:
    with pytest.raises(DataValidationError, match=f"^{field}: "):
        truth(kind, {**params, field: value})
    with pytest.raises(DataValidationError, match="^eta: "):
        truth(kind, params, eta=-1.0)
    with pytest.raises(DataValidationError, match="^bounds"):
        get_estimator(kind, bounds={"f0": (1.0, 0.0)}).fit(record(1))
    with pytest.raises(DataValidationError, match="^start: unknown parameter"):
        get_estimator(kind, start={"nope": 1.0}).fit(record(1))


def check_kernel_against_reference(kind: str, params: dict[str, float], eta: float = 0.0) -> None:
    """The automatic RK4 sub-steps against ``solve_ivp`` at rtol 1e-10 on the same linearly
    interpolated inputs: below 1e-3 of the force's standard deviation (NRMSE)."""
    from scipy.integrate import solve_ivp

    from mrdamper.models.hysteresis import kernels as K

    model = truth(kind, params, eta=eta)
    e = record(4, duration=1.0)
    p, fam = model.parameter_vector(), K.FAMILIES[kind]

    def rhs(tt: float, s: np.ndarray) -> list[float]:
        vv, ee = np.interp(tt, e.t, e.v), np.interp(tt, e.t, e.i)
        return [K._zdot.py_func(fam, p, vv, s[0]), -eta * (s[1] - ee)]

    sol = solve_ivp(
        rhs,
        (e.t[0], e.t[-1]),
        [0.0, e.i[0]],
        method="LSODA",
        t_eval=e.t,
        rtol=1e-10,
        atol=1e-13,
        max_step=e.dt,
    )
    assert sol.success, sol.message
    u = sol.y[1] if eta > 0 else e.i
    ref = np.array(
        [K._force.py_func(fam, p, x, v, z, uu) for x, v, z, uu in zip(e.x, e.v, sol.y[0], u)]
    )
    F = model.predict(e)
    assert np.sqrt(np.mean((F - ref) ** 2)) / np.std(ref) < 1e-3
