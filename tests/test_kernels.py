"""Kernel housekeeping (mrdamper.compiled): canonical argument types and compile-once claims."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numba import typeof

from mrdamper import compiled
from mrdamper.models._arrays import readonly
from mrdamper.models.narx import kernels as _narx_kernels
from mrdamper.models.sp import kernels as _sp_kernels


def test_readonly_is_a_view_and_read_only() -> None:
    a = np.arange(5.0)
    r = readonly(a)
    assert np.shares_memory(a, r) and not r.flags.writeable and a.flags.writeable
    assert readonly(r) is r  # already read-only: passed through
    c = readonly(np.arange(10)[::2], np.float64)  # strided ints: contiguous float copy
    assert c.dtype == np.float64 and c.flags.c_contiguous and not c.flags.writeable


def test_every_listed_kernel_is_a_numba_dispatcher_with_parseable_types() -> None:
    from numba.core.registry import CPUDispatcher

    for kind, items in compiled.KERNELS.items():
        for it in items:
            disp = compiled._dispatcher(it)
            assert isinstance(disp, CPUDispatcher), (kind, it[1])
            n_args = disp.py_func.__code__.co_argcount
            assert len(compiled._types(it[2])) == n_args, (kind, it[1])
            assert it[3] > 0


def test_sp_wrappers_pass_the_listed_argument_types() -> None:
    """Writable and read-only records reach the SP kernel with one signature (the listed one)."""
    x = np.linspace(0.0, 1.0, 4)
    comp, power, theta = np.array([0, 1]), np.array([0, 1]), np.array([1.0, 2.0])
    listed = {it[1]: compiled._types(it[2]) for it in compiled.KERNELS["sp1"]}
    for arr in (x, readonly(x)):
        args = _sp_kernels._args(arr, arr, arr, comp, power, theta)
        assert tuple(typeof(a) for a in args) + (typeof(0.5),) == listed["_sp_force"]


def test_narx_wrappers_pass_read_only_term_tables() -> None:
    base = np.array([[0, 1], [1, 0]])
    assert not _narx_kernels._ri(base).flags.writeable
    assert np.shares_memory(_narx_kernels._ri(base), base)


def test_claimed_modules_are_left_to_their_claimant(tmp_path: Path) -> None:
    kinds = list(compiled.KERNELS)
    for items in compiled._todo(kinds):
        (tmp_path / items[0][0]).touch()
    assert compiled.compile_claimed(kinds, str(tmp_path)) == 0
    assert compiled._todo(["bingham", "no-such-kind"]) == []


def test_compile_ahead_does_nothing_without_work() -> None:
    compiled.compile_ahead(["bingham"])  # no compiled kernels: no background process
    assert compiled.claim_folder() is None
    compiled.finish_ahead()  # no-op


def test_kernels_named_last_come_after_the_others_of_their_module(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(compiled, "is_cached", lambda item: False)  # as on a fresh install
    kinds = ["spencer", "lpv", "p15", "narx", "sp1"]
    plain = compiled._todo(kinds)
    late = compiled._todo(kinds, last=compiled.RIG_KERNELS)
    assert [m[0][0] for m in plain] == [m[0][0] for m in late]  # modules: costliest first
    assert plain[0][0][0] == "mrdamper.models.spencer.kernels"
    assert [it[1] for it in late[0]] == ["simulate_sens", "simulate"]  # the rig's kernel last
    assert [sorted(m) for m in plain] == [sorted(m) for m in late]


@pytest.mark.slow
def test_rig_items_are_the_signatures_the_virtual_rig_compiles() -> None:
    """RIG_ITEMS must follow the rig: the early compilation is of no use if they drift."""
    import subprocess
    import sys

    code = (
        "from mrdamper.rig.doe import table_ii; from mrdamper import compiled\n"
        "table_ii(seed=0, scale=0.07)\n"
        "for it in compiled.RIG_ITEMS:\n"
        "    disp = compiled._dispatcher(it)\n"
        "    print(it[1], disp.signatures == [compiled._types(it[2])])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = out.stdout.split("\n")
    assert [ln for ln in lines if ln] == [f"{it[1]} True" for it in compiled.RIG_ITEMS]


def test_start_early_marks_the_rig_ready_and_cleans_up() -> None:
    compiled.start_early(["bingham"])  # bingham has no kernels: only the rig's damper kernel
    try:
        claim = compiled.claim_folder()
        assert claim is not None
        waited = compiled.wait_rig(timeout=300.0)
        assert waited >= 0.0
        assert (Path(claim) / compiled.RIG_READY).exists()
        compiled.start_early(["lpv"])  # one background process at a time
        assert compiled.claim_folder() == claim
    finally:
        compiled.finish_ahead()
    assert compiled.claim_folder() is None and not Path(claim).exists()
    assert compiled.wait_rig() == 0.0  # nothing started: returns at once


@pytest.mark.parametrize(
    ("args", "kinds"),
    [
        (["demo"], list(compiled.KERNELS)),
        (["demo", "--quick", "--models", "lpv,sp1"], ["lpv", "sp1"]),
        (["--debug", "demo", "--models=spencer"], ["spencer"]),
        (["demo", "--help"], None),
        (["study", "data", "--out", "x"], None),
        ([], None),
    ],
)
def test_launcher_starts_early_only_for_a_demo(args: list[str], kinds: list[str] | None) -> None:
    from mrdamper.cli.launch import demo_kinds

    assert demo_kinds(args) == kinds


@pytest.mark.parametrize("fs", [500.0, 200.0])  # the model rate, and records up-sampled to it
def test_lpv_fit_passes_the_listed_argument_types(
    fs: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The default LPV fit and prediction call each listed kernel with its listed signature only,
    on records at the model rate and on slower, up-sampled ones (one compilation per kernel)."""
    import warnings

    from mrdamper import Experiment
    from mrdamper.analysis import hysteretic
    from mrdamper.models.lpv import LPVEstimator
    from mrdamper.models.lpv import kernels as K

    listed = {it[1]: (it[0], compiled._types(it[2])) for it in compiled.KERNELS["lpv"]}
    seen: dict[str, set[tuple[object, ...]]] = {name: set() for name in listed}
    for name, (module, _) in listed.items():
        owner = hysteretic if module == hysteretic.__name__ else K
        kernel = getattr(owner, name)

        def spy(*args: object, _k: object = kernel, _n: str = name) -> object:
            seen[_n].add(tuple(typeof(a) for a in args))
            return _k(*args)  # type: ignore[operator]

        monkeypatch.setattr(owner, name, spy)
    rng = np.random.default_rng(0)
    records = []
    for k, level in enumerate((0.0, 0.5, 1.0)):
        t = np.arange(600) / fs
        v = 0.1 * np.sin(2 * np.pi * 1.5 * t) + 0.01 * rng.standard_normal(t.size)
        F = (300 + 900 * level) * np.tanh(v / 0.01) + 50 * v
        records.append(
            Experiment(t=t, x=np.cumsum(v) / fs, v=v, F=F, i=np.full(t.size, level), name=f"r{k}")
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = LPVEstimator(stroke=2e-4, blend=0.5, max_nfev=2).fit(records)
        model.predict(records[0])
    for name, (_, types) in listed.items():
        assert seen[name] == {types}, name
