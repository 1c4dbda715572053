"""Compiled kernels of the numba modules: one argument type per kernel, compiled once per machine.

numba compiles a kernel for every distinct tuple of argument types it is called with and keeps the
machine code in its on-disk cache (``njit(cache=True)``, files beside the kernel module). On a fresh
installation that cache is empty, and the first run of a command pays the compilation of every
kernel it calls. Two things keep that cost down:

* **One signature per kernel.** A read-only array (a record's channel, a memory-mapped file, a
  frozen model's coefficients) and a writable one are different argument types to numba, so the
  same kernel called with both is compiled twice. The wrappers of the kernel modules pass input
  arrays through ``models._arrays.readonly`` (a read-only view, never a copy), so each compiles
  once.
* **Compile ahead, in parallel, once per machine.** :data:`KERNELS` lists, per model kind, the
  kernels its identification and simulation call and their argument types. A study with several
  local worker processes first has every worker compile the kernels its model kinds need that are
  not cached yet, module by module, each module claimed by one process (:func:`compile_claimed`),
  so each kernel is compiled once on the machine and the workers compile in parallel; the fits
  then load them from the cache. ``mrdamper demo`` starts this in a background process before it
  generates its records (:func:`compile_ahead`). Kernels already cached are not touched: a second
  run only reads the cache indexes.

The costs in :data:`KERNELS` are compile times [s] measured by ``benchmarks/bench_compile.py``
(CPU time on the 2-core reference machine); they only order the modules, largest first, so the
processes finish at about the same time.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from mrdamper.kinds import KINDS, Item

__all__ = [
    "KERNELS",
    "RIG_ITEMS",
    "RIG_KERNELS",
    "RIG_READY",
    "claim_folder",
    "compile_ahead",
    "compile_claimed",
    "compile_kernels",
    "finish_ahead",
    "is_cached",
    "start_early",
    "wait_rig",
]

_SPENCER = "mrdamper.models.spencer.kernels"

#: Model kernels (module, name) that generating records on the virtual rig compiles: its damper is
#: a Spencer model.
RIG_KERNELS: tuple[tuple[str, str], ...] = ((_SPENCER, "simulate"),)

#: Every kernel (with the argument types of its calls) that generating records on the virtual rig
#: runs: signals, current driver, actuator and the reference damper (a Spencer model).
RIG_ITEMS: tuple[Item, ...] = (
    (_SPENCER, "simulate", "f1r f1r f1r F f1 I F F F", 1.0),
    ("mrdamper.rig._rig_kernels", "second_order_track", "f1 f2 f1 F F", 0.4),
    ("mrdamper.rig._rig_kernels", "first_order_lag", "f1 F F", 0.15),
    ("mrdamper.signals._signal_kernels", "lfsr_bits", "I i1 I I", 0.25),
)

#: File the early background compilation creates in its claim folder once the model kernel the
#: virtual rig runs is cached (:func:`start_early`, :func:`wait_rig`).
RIG_READY = "rig-kernels-ready"

#: Kernels (with the argument types of the library's calls) that each model kind's fit and
#: simulation run, from the kind table (:mod:`mrdamper.kinds`); kinds without compiled kernels are
#: absent.
KERNELS: dict[str, tuple[Item, ...]] = {row.kind: row.kernels for row in KINDS if row.kernels}


def _types(code: str) -> tuple[Any, ...]:
    from numba import types as nt

    scalars = {"F": nt.float64, "I": nt.int64, "B": nt.boolean}
    out: list[Any] = []
    for tok in code.split():
        if tok in scalars:
            out.append(scalars[tok])
            continue
        dtype: Any = nt.float64 if tok[0] == "f" else nt.int64
        layout: Any = "A" if "A" in tok else "C"
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


def _todo(kinds: Iterable[str], last: Iterable[tuple[str, str]] = ()) -> list[list[Item]]:
    """Kernels of ``kinds`` not cached yet, by module (largest module first; within a module, the
    kernels named in ``last`` after the others).

    The kernels of one module are compiled together, in one process: they share helper functions
    and numba's own compiled helpers, which another process would compile again.
    """
    items: dict[tuple[str, str, str], Item] = {}
    for kind in kinds:
        for it in KERNELS.get(str(kind), ()):
            items[it[:3]] = it
    modules: dict[str, list[Item]] = {}
    for it in items.values():
        if not is_cached(it):
            modules.setdefault(it[0], []).append(it)
    late = set(last)
    ordered = [sorted(m, key=lambda it: it[:2] in late) for m in modules.values()]
    return sorted(ordered, key=lambda m: -sum(it[3] for it in m))


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


def compile_claimed(
    kinds: Sequence[str], claim_dir: str, last: Sequence[tuple[str, str]] = ()
) -> int:
    """Compile the uncached kernels of ``kinds``, module by module, skipping modules that another
    process has claimed: a module is claimed by creating a file named after it in ``claim_dir``
    (atomic). Every process given the same ``claim_dir`` runs this; each module is compiled once.
    Kernels named in ``last`` (module, name) come after the others of their module (a kernel
    another process has cached by then is loaded, not compiled again). Returns the number of
    kernel signatures handled here."""
    done = 0
    for items in _todo(kinds, last):
        try:
            os.close(os.open(os.path.join(claim_dir, items[0][0]), os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            continue
        except OSError:  # claim folder gone: the study has started without us
            break
        done += compile_kernels(items)
    return done


@dataclass
class _Ahead:
    process: Any
    claim_dir: str
    rig: bool = False


_AHEAD: _Ahead | None = None


def compile_ahead(kinds: Sequence[str], last: Sequence[tuple[str, str]] = ()) -> None:
    """Start compiling the uncached kernels of ``kinds`` in a background process, now.

    For a command that has other work to do first (``mrdamper demo`` generates its records): the
    compilation runs on another core meanwhile. ``last``: kernels (module, name) the command itself
    is about to compile (the virtual rig simulates a Spencer model, :data:`RIG_KERNELS`); the
    background process takes each after the other kernels of its module, when it is likely cached
    (and then only loads it). The study picks it up (:func:`claim_folder`) and compiles the
    modules not yet claimed in its own processes, then waits for this one (:func:`finish_ahead`).
    Nothing starts when every kernel is cached.
    """
    global _AHEAD
    if _AHEAD is not None or not _todo(kinds):
        return
    claim_dir = tempfile.mkdtemp(prefix="mrdamper-kernels-")
    _AHEAD = _Ahead(_background(compile_claimed, list(kinds), claim_dir, list(last)), claim_dir)


def _background(target: Any, *args: Any) -> Any:
    """Start ``target(*args)`` in a daemon process (forked where the platform can) and return it."""
    methods = multiprocessing.get_all_start_methods()
    ctx: Any = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    proc = ctx.Process(target=target, args=args, daemon=True)
    proc.start()
    return proc


def _rig_then_claimed(kinds: Sequence[str], claim_dir: str) -> None:
    """Body of the early background process: the virtual rig's kernels first (the command waits
    for them, :func:`wait_rig`), then the claimed model kernel modules."""
    try:  # the model kernels the rig runs; the rig's own kernels are left to the command
        compile_kernels([it for it in RIG_ITEMS if it[:2] in RIG_KERNELS and not is_cached(it)])
    finally:
        try:
            os.close(os.open(os.path.join(claim_dir, RIG_READY), os.O_CREAT | os.O_EXCL))
        except OSError:
            pass  # claim folder gone: the command has moved on
    compile_claimed(kinds, claim_dir)


def start_early(kinds: Sequence[str]) -> None:
    """Start, at once, a background process that compiles the model kernel the virtual rig runs
    (:data:`RIG_KERNELS`) and then the uncached kernels of ``kinds`` (as :func:`compile_ahead`).

    For ``mrdamper demo``, called before the command line is even parsed: the other core
    compiles while this process imports its libraries, so the rig's damper kernel is usually
    cached when the demo generates its records (:func:`wait_rig` compiles the rig's own kernels
    meanwhile, then waits for it instead of compiling it again) and the models' kernels are
    compiled during the generation. The
    process checks the cache itself (a second run costs it about a second of the other core and
    compiles nothing), so this call returns without importing numba.
    """
    global _AHEAD
    if _AHEAD is not None:
        return
    claim_dir = tempfile.mkdtemp(prefix="mrdamper-kernels-")
    _AHEAD = _Ahead(_background(_rig_then_claimed, list(kinds), claim_dir), claim_dir, rig=True)


def wait_rig(timeout: float = 120.0) -> float:
    """Make the virtual rig's kernels ready in this process, sharing the work with the early
    background process (:func:`start_early`).

    This process compiles (or loads) the rig's own kernels (signals, driver, actuator) while the
    background process compiles the model kernel the rig runs (:data:`RIG_KERNELS`, the
    reference damper's simulation); it then waits until that one is cached, the background
    process has stopped, or ``timeout`` [s] has passed. Without an early process it returns at
    once (each kernel is then compiled at its first call).

    Returns
    -------
    float
        Time spent waiting for the background process [s].
    """
    import time

    if _AHEAD is None or not _AHEAD.rig:
        return 0.0
    compile_kernels([it for it in RIG_ITEMS if it[:2] not in RIG_KERNELS])
    ready = os.path.join(_AHEAD.claim_dir, RIG_READY)
    t0 = time.perf_counter()
    while not os.path.exists(ready) and _AHEAD.process.is_alive():
        if time.perf_counter() - t0 > timeout:
            break
        time.sleep(0.01)
    return time.perf_counter() - t0


def claim_folder() -> str | None:
    """Claim folder of the background compilation started by :func:`compile_ahead`, if any."""
    return None if _AHEAD is None else _AHEAD.claim_dir


def finish_ahead(cancel: bool = False) -> None:
    """Wait for the background compilation (it stops after the modules it claimed) and clean up;
    ``cancel`` stops it instead (the command failed or was interrupted)."""
    global _AHEAD
    if _AHEAD is None:
        return
    if cancel and _AHEAD.process.is_alive():
        _AHEAD.process.terminate()
    _AHEAD.process.join()
    shutil.rmtree(_AHEAD.claim_dir, ignore_errors=True)
    _AHEAD = None
