"""Every public function and class of ``mrdamper.study`` documents each of its parameters.

Functions list their parameters in the numpydoc "Parameters" section; classes in "Parameters" or
"Attributes" (frozen dataclasses document their fields as attributes). ``a, b : float``
documents both names; ``**kwargs`` documents the catch-all; ``self`` and ``cls`` are implied.
"""

from __future__ import annotations

import inspect
import re
from typing import Any

import pytest

import mrdamper.study

_SECTION = re.compile(r"^([A-Z][A-Za-z ]+)\n-{3,}$", re.MULTILINE)


def _sections(doc: str) -> dict[str, str]:
    """Section title -> body of a numpydoc docstring."""
    doc = inspect.cleandoc(doc)
    heads = list(_SECTION.finditer(doc))
    return {
        h.group(1): doc[h.end() : heads[k + 1].start() if k + 1 < len(heads) else len(doc)]
        for k, h in enumerate(heads)
    }


def _names(body: str) -> set[str]:
    """Names of the entries of one section (the lines that are not indented)."""
    out: set[str] = set()
    for line in body.splitlines():
        if not line.strip() or line.startswith((" ", "\t")):
            continue
        head = line.split(" : ")[0]
        out.update(n.strip() for n in head.split(","))
    return out


def documented(obj: Any) -> set[str]:
    """Parameter names documented by ``obj`` (and, for a class, by its ``__init__``)."""
    docs = [inspect.getdoc(obj) or ""]
    if inspect.isclass(obj) and "__init__" in vars(obj):
        docs.append(inspect.getdoc(vars(obj)["__init__"]) or "")
    titles = ("Parameters", "Attributes") if inspect.isclass(obj) else ("Parameters",)
    out: set[str] = set()
    for doc in docs:
        for title, body in _sections(doc).items():
            if title in titles:
                out |= _names(body)
    return out


def expected(obj: Any) -> set[str]:
    """Parameter names of ``obj``'s signature as a docstring spells them."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):  # pragma: no cover - builtins without a signature
        return set()
    out = set()
    for p in sig.parameters.values():
        if p.name in ("self", "cls"):
            continue
        prefix = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "")
        out.add(prefix + p.name)
    return out


PUBLIC = [
    (name, getattr(mrdamper.study, name))
    for name in mrdamper.study.__all__
    if inspect.isfunction(getattr(mrdamper.study, name))
    or inspect.isclass(getattr(mrdamper.study, name))
]


def test_there_is_something_to_check() -> None:
    assert len(PUBLIC) > 15


@pytest.mark.parametrize(("name", "obj"), PUBLIC, ids=[n for n, _ in PUBLIC])
def test_every_parameter_is_documented(name: str, obj: Any) -> None:
    missing = sorted(expected(obj) - documented(obj))
    assert not missing, f"mrdamper.study.{name}: undocumented parameter(s) {missing}"


def test_the_checker_sees_a_missing_parameter() -> None:
    def f(a: int, b: int, **extra: Any) -> None:
        """Do.

        Parameters
        ----------
        a, c : int
            Documented.
        """

    assert expected(f) - documented(f) == {"b", "**extra"}
