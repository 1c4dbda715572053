"""Compiled-kernel housekeeping (private): one argument type per kernel, compiled once per machine.

numba compiles a kernel for every distinct tuple of argument types it is called with and keeps the
machine code in its on-disk cache (``njit(cache=True)``, files beside the kernel module). On a fresh
installation that cache is empty, and the first run of a command pays the compilation of every
kernel it calls. Two things keep that cost down:

* **One signature per kernel.** A read-only array (a record's channel, a memory-mapped file, a
  frozen model's coefficients) and a writable one are different argument types to numba, so the
  same kernel called with both is compiled twice. The wrappers of the kernel modules pass input
  arrays through :func:`readonly` (a read-only view, never a copy), so each compiles once.
* **Compile ahead, split over the workers.** :data:`KERNELS` lists, per model kind, the kernels
  its identification and simulation call and their argument types. A study with several local
  worker processes first compiles the kernels its model kinds need that are not cached yet, split
  into one group per worker (by module, largest first), so each is compiled once on the machine
  and the workers compile in parallel; the fits then load them from the cache. Kernels already cached are
  not touched (a second run does no extra work).

The costs in :data:`KERNELS` are compile times [s] measured by ``benchmarks/bench_compile.py``
(CPU time on the 2-core reference machine); they only balance the groups.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

__all__ = ["KERNELS", "compile_kernels", "is_cached", "plan", "readonly"]

_LPV = "mrdamper.models._lpv_kernels"
_SPENCER = "mrdamper.models._spencer_kernels"
_SP = "mrdamper.models._sp_kernels"
_NARX = "mrdamper.models._narx_kernels"
_P15 = "mrdamper.models._p15_implicit"

#: One kernel signature: module, kernel (numba dispatcher) name, argument types, compile cost [s].
#: Argument codes: ``F`` float64, ``I`` int64, ``B`` bool; arrays ``f`` (float64) or ``i``
#: (int64), then the number of dimensions, then ``r`` for read-only and ``A`` for any layout
#: (default: C-contiguous, writable).
Item = tuple[str, str, str, float]

_LPV_ITEMS: tuple[Item, ...] = (
    (_LPV, "oe_normal_equations", "f1 f1r f2 f2 f1r F F F B", 2.5),
    (_LPV, "_simulate_fused43", "f1 f1r f2 f2 F", 0.7),
)
_SP_ITEMS: tuple[Item, ...] = (
    (_SP, "_sp_force", "f1r f1r f1r i1r i1r f1r F", 1.1),
    (_SP, "_sp_force_jacobian", "f1r f1r f1r i1r i1r f1r F B", 0.4),
)

#: Kernels (with the argument types of the library's calls) that each model kind's fit and
#: simulation run; kinds without compiled kernels are absent.
KERNELS: dict[str, tuple[Item, ...]] = {
    "lpv": _LPV_ITEMS,
    "lti": _LPV_ITEMS,
    "p15": ((_P15, "p15i_run", "f1r f1r F f2 F I F F I F i1 i1 f1 f1 f2 B B", 3.0),),
    "sp1": _SP_ITEMS,
    "sp2": _SP_ITEMS,
    "sp3": _SP_ITEMS,
    "sp4": _SP_ITEMS,
    "spencer": (
        (_SPENCER, "simulate_sens", "f1r f1r f1r F f1 I F F F i1", 3.9),
        (_SPENCER, "simulate", "f1r f1r f1r F f1 I F F F", 1.3),
    ),
    "narx": (
        (_NARX, "_free_run_sensitivity", "f2 i2r i2r f1r I F", 0.7),
        (_NARX, "_free_run", "f2 i2r i2r f1r I F", 0.6),
        (_NARX, "gram_select", "f2 I F F", 0.6),
        (_NARX, "_fill_candidates", "f2 i2r i2r I I f2A", 0.5),
    ),
}


def readonly(a: Any, dtype: Any = np.float64) -> np.ndarray:
    """``a`` as a C-contiguous array of ``dtype`` that is read-only (a view: no copy when ``a``
    already has that type and layout), so that kernels see one argument type."""
    out = np.ascontiguousarray(a, dtype=dtype)
    if out.flags.writeable:
        out = out.view()
        out.flags.writeable = False
    return out


def _types(code: str) -> tuple[Any, ...]:
    from numba import types as nt

    scalars = {"F": nt.float64, "I": nt.int64, "B": nt.boolean}
    out = []
    for tok in code.split():
        if tok in scalars:
            out.append(scalars[tok])
            continue
        dtype = nt.float64 if tok[0] == "f" else nt.int64
        layout = "A" if "A" in tok else "C"
        out.append(nt.Array(dtype, int(tok[1]), layout, readonly="r" in tok))
    return tuple(out)


def _dispatcher(item: Item) -> Any:
    return getattr(importlib.import_module(item[0]), item[1])


def is_cached(item: Item) -> bool:
    """True when the on-disk cache holds ``item``'s machine code (False when unsure)."""
    try:
        disp = _dispatcher(item)
        cache = disp._cache
        key = cache._index_key(_types(item[2]), disp.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - numba internals; unsure means "compile it"
        return False


def plan(kinds: Iterable[str], groups: int) -> list[list[Item]]:
    """Kernels of ``kinds`` not cached yet, split into at most ``groups`` lists of similar cost.

    The kernels of one module stay in one list (they share helper functions and numba's own
    compiled helpers, which each process would otherwise compile again); modules go largest first
    to the least loaded list. Empty lists are dropped (an empty plan when everything is cached).
    """
    items: dict[tuple[str, str, str], Item] = {}
    for kind in kinds:
        for it in KERNELS.get(str(kind), ()):
            items[it[:3]] = it
    modules: dict[str, list[Item]] = {}
    for it in items.values():
        if not is_cached(it):
            modules.setdefault(it[0], []).append(it)
    out: list[list[Item]] = [[] for _ in range(max(1, groups))]
    load = [0.0] * len(out)
    for todo in sorted(modules.values(), key=lambda m: -sum(it[3] for it in m)):
        j = load.index(min(load))
        out[j].extend(sorted(todo, key=lambda it: -it[3]))
        load[j] += sum(it[3] for it in todo)
    return [g for g in out if g]


def compile_kernels(items: Sequence[Item]) -> int:
    """Compile (or load from the cache) every kernel signature of ``items``; return how many.

    A kernel that fails to compile here is skipped: it is then compiled at its first call, where
    the error surfaces with its context.
    """
    done = 0
    for it in items:
        try:
            _dispatcher(it).compile(_types(it[2]))
            done += 1
        except Exception:  # noqa: BLE001, S112 - see the docstring
            continue
    return done
