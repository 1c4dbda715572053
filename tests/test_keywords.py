"""Every public keyword is documented and estimators refuse unknown settings.

Walks ``mrdamper.__all__``, the ``__all__`` of every subpackage and of every public model module,
and checks each parameter of each public callable's signature against its numpydoc docstring:
functions list their parameters under "Parameters"; classes under "Parameters" or "Attributes"
(frozen dataclasses document their fields as attributes; a subclass documents what it adds to its
bases, an estimator's old setting names are documented with the new ones). A line ``x, y : float``
documents both names, ``**settings`` documents the catch-all. Then every registered estimator
refuses an unknown setting with one line naming it.
"""

from __future__ import annotations

import importlib
import inspect
import re
from collections.abc import Iterator
from typing import Any

import pytest

import mrdamper
from mrdamper.errors import DataValidationError
from mrdamper.kinds import KINDS
from mrdamper.models import get_estimator, model_class

SUBPACKAGES = [
    "analysis",
    "control",
    "data",
    "data.readers",
    "metrics",
    "errors",
    "models",
    "plotting",
    "progress",
    "rig",
    "signals",
    "study",
]
MODEL_MODULES = [
    "base",
    "settings",
    "registry",
    "protocols",
    "rates",
    "augment",
    "lpv",
    "phenomenological",
    "semiphenomenological",
    "spencer",
    "bingham",
    "narx",
    "tanh",
    "boucwen",
    "dahl",
    "lugre",
]
SECTIONS = ("Parameters", "Attributes", "Other Parameters")
_HEADER = re.compile(r"^(\s*)([A-Z][A-Za-z ]+)\n\1-{3,}\s*$", re.MULTILINE)


def _public() -> Iterator[tuple[str, Any]]:
    seen: set[int] = set()
    modules = [("mrdamper", mrdamper)]
    modules += [(f"mrdamper.{m}", importlib.import_module(f"mrdamper.{m}")) for m in SUBPACKAGES]
    modules += [
        (f"mrdamper.models.{m}", importlib.import_module(f"mrdamper.models.{m}"))
        for m in MODEL_MODULES
    ]
    for mod_name, mod in modules:
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)) or id(obj) in seen:
                continue  # type aliases (Literal[...]) are neither
            if getattr(obj, "_is_protocol", False):
                continue  # a Protocol describes members, it is not constructed
            if isinstance(obj, type) and issubclass(obj, BaseException):
                continue
            seen.add(id(obj))
            yield f"{mod_name}.{name}", obj


def documented_names(doc: str, sections: tuple[str, ...] = SECTIONS) -> set[str]:
    """Names listed in the given numpydoc sections of ``doc``."""
    doc = inspect.cleandoc(doc)
    heads = list(_HEADER.finditer(doc))
    names: set[str] = set()
    for k, h in enumerate(heads):
        if h.group(2).strip() not in sections:
            continue
        end = heads[k + 1].start() if k + 1 < len(heads) else len(doc)
        for line in doc[h.end() : end].splitlines():
            if not line.strip() or line.startswith((" ", "\t")):
                continue
            head = line.split(" : ")[0].strip()
            for part in head.split(","):
                names.add(part.strip().lstrip("*"))
    return names


def _parameters(obj: Any) -> list[str]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    out = []
    for p in sig.parameters.values():
        if p.name in ("self", "cls") or p.name.startswith("_"):
            continue
        out.append(p.name)
    return out


PUBLIC = sorted(_public(), key=lambda item: item[0])


def test_the_walk_finds_the_public_api() -> None:
    names = {n.rsplit(".", 1)[1] for n, _ in PUBLIC}
    assert {"run_study", "get_estimator", "LPVEstimator", "inverse_current"} <= names


@pytest.mark.parametrize("name, obj", PUBLIC, ids=[n for n, _ in PUBLIC])
def test_every_keyword_is_documented(name: str, obj: Any) -> None:
    params = _parameters(obj)
    if not params:
        return
    doc = inspect.getdoc(obj) or ""
    documented = documented_names(doc)
    skip: set[str] = set()
    if isinstance(obj, type):
        # a class may document its constructor in __init__, and a subclass only what it adds
        # to its bases; old setting names (renamed_settings) are documented with the new ones
        documented |= documented_names(inspect.getdoc(obj.__init__) or "")
        for base in obj.__mro__[1:]:
            if base.__module__.startswith("mrdamper"):
                documented |= documented_names(base.__doc__ or "")
        skip = set(getattr(obj, "renamed_settings", {}))
    missing = [p for p in params if p not in documented and p not in skip]
    assert not missing, f"{name}: parameters not in the docstring: {missing}"


@pytest.mark.parametrize("kind", [row.kind for row in KINDS])
def test_estimator_settings_are_documented(kind: str) -> None:
    est = type(get_estimator(kind))
    documented = documented_names(inspect.getdoc(est) or "")
    for cls in est.__mro__[1:]:  # settings documented once on a shared base (SP-1..SP-4)
        documented |= documented_names(inspect.getdoc(cls) or "")
    renamed = set(est.renamed_settings)
    missing = [s for s in est.settings_names() if s not in documented and s not in renamed]
    assert not missing, f"{kind}: settings not in the docstring: {missing}"
    fields = [p for p in _parameters(model_class(kind)) if p != "provenance"]
    model_doc = documented_names(inspect.getdoc(model_class(kind)) or "")
    for cls in model_class(kind).__mro__[1:]:
        model_doc |= documented_names(inspect.getdoc(cls) or "")
    missing = [f for f in fields if f not in model_doc]
    assert not missing, f"{kind} model: fields not in the docstring: {missing}"


@pytest.mark.parametrize("kind", [row.kind for row in KINDS])
def test_unknown_setting_is_refused_naming_it(kind: str) -> None:
    with pytest.raises(DataValidationError, match="colour") as info:
        get_estimator(kind, colour="red")
    message = str(info.value)
    assert "\n" not in message and kind in message
    assert info.value.field == "colour"


def test_documented_names_parses_numpydoc() -> None:
    doc = """Summary.

    Parameters
    ----------
    a, b : float
        Two.
    **settings
        Any.

    Returns
    -------
    c : int
    """
    assert documented_names(doc) == {"a", "b", "settings"}


def test_unknown_fit_option_is_refused_naming_it() -> None:
    import numpy as np

    t = np.arange(200) / 100.0
    e = mrdamper.Experiment(t=t, x=0 * t, v=np.sin(t), F=np.sin(t), i=0.5 + 0 * t)
    for kind in ("bingham", "lpv"):
        with pytest.raises(DataValidationError, match="colour") as info:
            get_estimator(kind).fit(e, colour="red")  # checked before any work
        assert info.value.field == "colour" and "\n" not in str(info.value)
