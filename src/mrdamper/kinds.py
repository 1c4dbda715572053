"""The kind table: every fact about a model kind, in one place.

One row (:class:`KindSpec`) per model kind says where its code lives (module, estimator and
fitted-model class names), how it is shown (help text, colour), whether the study runs it by
default, how expensive its fit is (the order in which a study submits fits) and which compiled
kernels its fit and simulation call (so that they can be compiled ahead, see
:mod:`mrdamper.compiled`). Capabilities (a per-sample step, an inverse, a C rendering) are not
listed here: they are methods of the model, asked of the model.

The table is plain data (no imports), so the console script reads it before anything heavy is
imported. The registry (:mod:`mrdamper.models.registry`) imports a kind's module when the kind is
first used; a family added at run time with :func:`mrdamper.models.register` adds its row with
:func:`add`, and then appears in :func:`mrdamper.known_kinds`, the study, ``select`` and the
report like any other, in that process (and the study's local workers, :func:`added`).

A family in another package joins every process (the command line, a study's workers under any
start method, Dask workers) through an entry point of the group ``mrdamper.kinds`` that names its
row: ``viscous = "mrd_viscous:KIND"``, where ``KIND`` is a :class:`KindSpec` in a module that
imports nothing heavy. The entry points are read on the first call of :func:`rows` (or :func:`spec`,
:func:`default_kinds`), once per process; the family's own module is imported only when the kind is
used. A plug-in that cannot be loaded is left out with one warning naming its entry point
(:func:`plugin_errors`), so the other kinds and commands work as before.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

__all__ = [
    "GROUP",
    "KINDS",
    "VARIANTS",
    "Item",
    "KindSpec",
    "Variant",
    "add",
    "added",
    "cost_rank",
    "default_kinds",
    "input_text",
    "kind_list",
    "plugin_errors",
    "rows",
    "spec",
]

#: One kernel signature: module, kernel (numba dispatcher) name, argument types, compile cost [s].
#: Argument codes: ``F`` float64, ``I`` int64, ``B`` bool; arrays ``f`` (float64) or ``i``
#: (int64), then the number of dimensions, then ``r`` for read-only and ``A`` for any layout
#: (default: C-contiguous, writable). Costs are CPU seconds measured by
#: ``benchmarks/bench_compile.py``; they only order the compilation.
Item = tuple[str, str, str, float]


@dataclass(frozen=True)
class KindSpec:
    """One model kind.

    Attributes
    ----------
    kind : str
        Name of the kind (``"lpv"``), as saved in model files.
    module : str
        Module that defines the estimator and the fitted model.
    estimator, model : str
        Class names of the estimator and of the fitted model in ``module``.
    summary : str
        One line for help texts and reports.
    color : str
        Matplotlib colour of the kind in every figure.
    default : bool
        Run by the study (and the demo) when no model list is given.
    cost_rank : int
        Identification cost rank (0 the most expensive); the study submits expensive fits first.
    kernels : tuple of Item
        Compiled kernels (with the argument types of the library's calls) that the kind's fit and
        simulation run.
    interpolation_only : bool
        A black-box kind that nothing in its structure carries beyond its training envelope:
        ``select`` scores it but does not recommend it when it validates beyond the envelope.
    """

    kind: str
    module: str
    estimator: str
    model: str
    summary: str
    color: str
    default: bool = True
    cost_rank: int = 9
    kernels: tuple[Item, ...] = ()
    interpolation_only: bool = False


_LPV = "mrdamper.models.lpv.kernels"
_SPENCER = "mrdamper.models.spencer.kernels"
_SP = "mrdamper.models.sp.kernels"
_NARX = "mrdamper.models.narx.kernels"
_P15 = "mrdamper.models.p15.kernels"
_LPV_MOD = "mrdamper.models.lpv"
_SP_MOD = "mrdamper.models.sp.model"

_LPV_ITEMS: tuple[Item, ...] = (
    (_LPV, "oe_normal_equations", "f1 f1r f2 f2 f1r f1r F F F F B B", 1.2),
    (_LPV, "_simulate_fused43", "f1 f1r f2 f2 F", 0.5),
    (_LPV, "residual_sse", "f1 f1r F f1r F", 0.1),
    ("mrdamper.analysis.hysteretic", "_dahl", "f1r F F F", 0.3),  # the hysteretic input
)
_SP_ITEMS: tuple[Item, ...] = (
    (_SP, "_sp_force", "f1r f1r f1r i1r i1r f1r F", 0.4),
    (_SP, "_sp_force_jacobian", "f1r f1r f1r i1r i1r f1r F B", 0.3),
)

#: Every kind of this version, in default display order.
KINDS: tuple[KindSpec, ...] = (
    KindSpec(
        "lpv",
        _LPV_MOD,
        "LPVEstimator",
        "LPVModel",
        "LPV input-output model scheduled by the current (the paper's model)",
        "tab:red",
        cost_rank=1,
        kernels=_LPV_ITEMS,
    ),
    KindSpec(
        "p15",
        "mrdamper.models.p15.model",
        "P15Estimator",
        "P15Model",
        "phenomenological model P-15 (the paper's)",
        "tab:blue",
        cost_rank=2,
        kernels=((_P15, "p15i_run", "f1r f1r F f2 F I F F I F i1 i1 f1 f1 f2 B B", 1.9),),
    ),
    KindSpec(
        "sp1",
        _SP_MOD,
        "SP1Estimator",
        "SP1Model",
        "semi-phenomenological static map SP-1 (the paper's)",
        "tab:green",
        cost_rank=3,
        kernels=_SP_ITEMS,
    ),
    KindSpec(
        "sp2",
        _SP_MOD,
        "SP2Estimator",
        "SP2Model",
        "semi-phenomenological static map SP-2 (the paper's)",
        "tab:olive",
        kernels=_SP_ITEMS,
    ),
    KindSpec(
        "sp3",
        _SP_MOD,
        "SP3Estimator",
        "SP3Model",
        "semi-phenomenological static map SP-3 (the paper's)",
        "tab:cyan",
        kernels=_SP_ITEMS,
    ),
    KindSpec(
        "sp4",
        _SP_MOD,
        "SP4Estimator",
        "SP4Model",
        "semi-phenomenological static map SP-4 (the paper's)",
        "tab:purple",
        cost_rank=4,
        kernels=_SP_ITEMS,
    ),
    KindSpec(
        "lti",
        _LPV_MOD,
        "LTIEstimator",
        "LTIModel",
        "LTI model of the LPV structure (no scheduling)",
        "tab:gray",
        cost_rank=5,
        kernels=_LPV_ITEMS,
    ),
    KindSpec(
        "spencer",
        "mrdamper.models.spencer.model",
        "SpencerEstimator",
        "SpencerModel",
        "Spencer et al. (1997) modified Bouc-Wen model",
        "tab:orange",
        cost_rank=0,
        kernels=(
            (_SPENCER, "simulate_sens", "f1r f1r f1r F f1 I F F F i1", 2.3),
            (_SPENCER, "simulate", "f1r f1r f1r F f1 I F F F", 1.0),
        ),
    ),
    KindSpec(
        "bingham",
        "mrdamper.models.bingham.model",
        "BinghamEstimator",
        "BinghamModel",
        "Bingham plastic model (Stanway et al. 1987)",
        "tab:brown",
    ),
    KindSpec(
        "narx",
        "mrdamper.models.narx.model",
        "NARXEstimator",
        "NARXModel",
        "polynomial NARX black-box peer",
        "tab:pink",
        kernels=(
            (_NARX, "_free_run_sensitivity", "f2 i2r i2r f1r I F", 0.8),
            (_NARX, "_free_run", "f2 i2r i2r f1r I F", 0.2),
            (_NARX, "_fill_candidates", "f2 i2r i2r I I f2A", 0.3),
        ),
        interpolation_only=True,
    ),
    KindSpec(
        "tanh",
        "mrdamper.models.hysteresis.tanh",
        "TanhEstimator",
        "TanhModel",
        "hyperbolic-tangent model (Kwok et al. 2006)",
        "darkgoldenrod",
        default=False,
    ),
    KindSpec(
        "boucwen",
        "mrdamper.models.hysteresis.boucwen",
        "BoucWenEstimator",
        "BoucWenModel",
        "classic Bouc-Wen model (current-dependent alpha and c0)",
        "slateblue",
        default=False,
        cost_rank=0,
    ),
    KindSpec(
        "dahl",
        "mrdamper.models.hysteresis.dahl",
        "DahlEstimator",
        "DahlModel",
        "modified Dahl model (Zhou et al.)",
        "darkcyan",
        default=False,
    ),
    KindSpec(
        "lugre",
        "mrdamper.models.hysteresis.lugre",
        "LuGreEstimator",
        "LuGreModel",
        "LuGre model of an MR damper (Jimenez and Alvarez-Icaza 2005)",
        "crimson",
        default=False,
    ),
)


@dataclass(frozen=True)
class Variant:
    """A labelled setting of a kind that the study runs by default beside the kind itself.

    Attributes
    ----------
    label : str
        Name in tables and figures (unique among the models of a study).
    kind : str
        The kind (a row of :data:`KINDS`).
    settings : tuple of (str, object)
        Estimator settings.
    summary : str
        One line for reports.
    """

    label: str
    kind: str
    settings: tuple[tuple[str, object], ...]
    summary: str


#: Variants the study (and the demo) runs right after their kind when no model list is given:
#: the paper's own LPV model (static zone-law input ``u``) beside the default LPV (hysteretic
#: input), so that the paper's headline is compared on the paper's model.
VARIANTS: tuple[Variant, ...] = (
    Variant(
        "lpv-paper",
        "lpv",
        (("input_signal", "u"),),
        "the paper's LPV model: static zone-law input u",
    ),
)

#: LPV input signals in words (:func:`input_text`).
_LPV_INPUTS = {
    "hysteretic": "zone-law input with a hysteretic pre-yield state (default)",
    "u": "static zone-law input u (the paper's)",
    "v": "velocity (ablation)",
}


def input_text(kind: str, settings: dict[str, object]) -> str:
    """Which input an LPV-structure model uses, in words (``""`` for other kinds).

    Parameters
    ----------
    kind : str
        Model kind.
    settings : dict
        Its estimator settings (``input_signal`` or ``stiffness`` absent: the default). A
        ``stiffness`` of ``"auto"`` reads as none: it identifies one only when the fit is given
        records to choose on, which a study's fits are not.
    """
    if kind != "lpv":
        return ""
    text = _LPV_INPUTS.get(str(settings.get("input_signal", "hysteretic")), "")
    stiffness = settings.get("stiffness", "auto")
    if stiffness == "identify":
        return text + "; parallel stiffness k_x identified"
    if stiffness in (0, "auto"):
        return text
    return text + f"; parallel stiffness k_x = {stiffness} N/m"


_ADDED: dict[str, KindSpec] = {}

#: Entry-point group of the plug-in families.
GROUP = "mrdamper.kinds"
#: Rows of the plug-ins, by kind (None until the entry points are read).
_PLUGINS: dict[str, KindSpec] | None = None
#: Kind (the entry point's name) -> why its plug-in was left out.
_BROKEN: dict[str, str] = {}


def _entry_text(ep: Any) -> str:
    dist = getattr(ep, "dist", None)
    where = f" of {dist.name} {dist.version}" if dist is not None else ""
    return f"plug-in entry point '{ep.name} = {ep.value}' (group {GROUP}{where})"


def _plugin_row(ep: Any, seen: dict[str, KindSpec]) -> KindSpec:
    """The row an entry point names, checked (raises TypeError or ValueError with the reason)."""
    if any(k.kind == ep.name for k in KINDS):
        raise ValueError(f"{ep.name!r} is a kind of this version and cannot be replaced")
    try:
        row = ep.load()
    except Exception as exc:  # whatever the plug-in's import raises
        reason = " ".join(str(exc).split())
        raise ValueError(f"cannot be loaded ({type(exc).__name__}: {reason})") from exc
    if not isinstance(row, KindSpec):
        raise TypeError(
            f"names a {type(row).__name__}; expected a mrdamper.kinds.KindSpec (the family's row)"
        )
    if row.kind != ep.name:
        raise ValueError(f"its row is of kind {row.kind!r}; expected the entry point's name")
    if row.kind in seen:
        raise ValueError(f"kind {row.kind!r} is already given by module {seen[row.kind].module}")
    for field in ("module", "estimator", "model"):
        value = getattr(row, field)
        if not (isinstance(value, str) and value):
            raise ValueError(f"row field {field!r}: expected a non-empty name, got {value!r}")
    return row


def _load_plugins() -> dict[str, KindSpec]:
    """Read the entry points of :data:`GROUP` once; warn (one line each) about broken ones."""
    global _PLUGINS
    if _PLUGINS is not None:
        return _PLUGINS
    from importlib.metadata import entry_points

    found: dict[str, KindSpec] = {}
    _PLUGINS = found  # a plug-in that reads the table while it loads sees the rows so far
    try:
        eps = sorted(entry_points(group=GROUP), key=lambda e: e.name)
    except Exception as exc:  # noqa: BLE001 - unreadable metadata of an installed distribution
        reason = " ".join(str(exc).split())
        warnings.warn(
            f"plug-ins: the entry points of the group {GROUP} cannot be read "
            f"({type(exc).__name__}: {reason}); no plug-in kinds",
            stacklevel=3,
        )
        return found
    for ep in eps:
        try:
            found[ep.name] = _plugin_row(ep, found)
        except (TypeError, ValueError) as exc:
            text = f"{_entry_text(ep)}: {exc}; the entry point is ignored"
            _BROKEN[ep.name] = text
            warnings.warn(text, stacklevel=3)
    return found


def added() -> tuple[KindSpec, ...]:
    """The rows added at run time with :func:`add` (by :func:`mrdamper.models.register`), which
    a process hands to the worker processes it starts (:func:`mrdamper._io.processes.init_worker`):
    a worker started by spawn sees the kind if its module imports there."""
    return tuple(_ADDED.values())


def plugin_errors() -> dict[str, str]:
    """Plug-ins left out because their entry point could not be loaded: kind -> the reason (one
    line naming the entry point)."""
    _load_plugins()
    return dict(_BROKEN)


def rows() -> tuple[KindSpec, ...]:
    """Every row: this version's kinds, then the plug-ins' (entry points, by kind), then those
    added at run time, in display order."""
    plugins = tuple(r for k, r in _load_plugins().items() if k not in _ADDED)
    return KINDS + plugins + tuple(_ADDED.values())


def spec(kind: str) -> KindSpec | None:
    """The row of ``kind`` (None for an unknown kind)."""
    for row in rows():
        if row.kind == kind:
            return row
    return None


def kind_list() -> str:
    """Every kind, comma-separated in display order (for help texts)."""
    return ", ".join(row.kind for row in rows())


def cost_rank(kind: str) -> int:
    """Identification cost rank of ``kind`` (0 the most expensive; 9 for a kind without a row).
    Fits are submitted in this order so the longest task starts first and the others fill the
    remaining workers; results do not depend on it."""
    row = spec(kind)
    return row.cost_rank if row is not None else 9


def default_kinds() -> tuple[str, ...]:
    """Kinds the study runs when no model list is given, in display order."""
    return tuple(row.kind for row in rows() if row.default)


def add(row: KindSpec) -> None:
    """Add (or replace) the row of a kind defined at run time.

    Parameters
    ----------
    row : KindSpec
        The kind's row; a kind of this version cannot be replaced (a plug-in's can).
    """
    if any(k.kind == row.kind for k in KINDS):
        raise ValueError(f"kind: {row.kind!r} is a kind of this version and cannot be replaced")
    _ADDED[row.kind] = row
