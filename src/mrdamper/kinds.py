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
:func:`add`, and then appears in :func:`mrdamper.known_kinds`, the study, ``select``, the command
line's help and the report like any other.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "KINDS",
    "VARIANTS",
    "Item",
    "KindSpec",
    "Variant",
    "add",
    "default_kinds",
    "input_text",
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
_SPENCER = "mrdamper.models._spencer_kernels"
_SP = "mrdamper.models._sp_kernels"
_NARX = "mrdamper.models._narx_kernels"
_P15 = "mrdamper.models._p15_kernels"
_LPV_MOD = "mrdamper.models.lpv"
_SP_MOD = "mrdamper.models.semiphenomenological"

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
        "mrdamper.models.phenomenological",
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
        "mrdamper.models.spencer",
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
        "mrdamper.models.bingham",
        "BinghamEstimator",
        "BinghamModel",
        "Bingham plastic model (Stanway et al. 1987)",
        "tab:brown",
    ),
    KindSpec(
        "narx",
        "mrdamper.models.narx",
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
        "mrdamper.models.tanh",
        "TanhEstimator",
        "TanhModel",
        "hyperbolic-tangent model (Kwok et al. 2006)",
        "darkgoldenrod",
        default=False,
    ),
    KindSpec(
        "boucwen",
        "mrdamper.models.boucwen",
        "BoucWenEstimator",
        "BoucWenModel",
        "classic Bouc-Wen model (current-dependent alpha and c0)",
        "slateblue",
        default=False,
        cost_rank=0,
    ),
    KindSpec(
        "dahl",
        "mrdamper.models.dahl",
        "DahlEstimator",
        "DahlModel",
        "modified Dahl model (Zhou et al.)",
        "darkcyan",
        default=False,
    ),
    KindSpec(
        "lugre",
        "mrdamper.models.lugre",
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


def rows() -> tuple[KindSpec, ...]:
    """Every row: this version's kinds, then those added at run time, in display order."""
    return KINDS + tuple(_ADDED.values())


def spec(kind: str) -> KindSpec | None:
    """The row of ``kind`` (None for an unknown kind)."""
    for row in rows():
        if row.kind == kind:
            return row
    return None


def default_kinds() -> tuple[str, ...]:
    """Kinds the study runs when no model list is given, in display order."""
    return tuple(row.kind for row in rows() if row.default)


def add(row: KindSpec) -> None:
    """Add (or replace) the row of a kind defined at run time.

    Parameters
    ----------
    row : KindSpec
        The kind's row; a kind of this version cannot be replaced.
    """
    if any(k.kind == row.kind for k in KINDS):
        raise ValueError(f"kind: {row.kind!r} is a kind of this version and cannot be replaced")
    _ADDED[row.kind] = row
