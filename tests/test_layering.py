"""The package is layered: no import circles, no private module or name used across packages.

Every module of ``src/mrdamper`` is parsed with :mod:`ast` (imports inside functions and under
``TYPE_CHECKING`` included, since a circle hidden in a function is still a circle). Lazy imports
count too: in a module that calls ``importlib.import_module``, every string constant naming a
module of the package is an import of it, and the kind table's module names
(:mod:`mrdamper.kinds`) are imports of the registry and of :mod:`mrdamper.compiled`. The rules:

* the graph "module A imports module B" has no cycle, and neither has the graph of packages;
* packages import only packages of a lower layer (:data:`LAYERS`);
* a module never imports a private module (a path part with a leading underscore) or a private
  name of another package. ``mrdamper._io`` and ``mrdamper._warn`` are shared by design; within
  one subpackage (for example ``models.lpv.estimator`` -> ``models._scale``) private imports are
  the point of privacy.

A failure prints every offending edge.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "mrdamper"
#: Private modules every package may use.
SHARED_PRIVATE = ("mrdamper._io", "mrdamper._warn")
#: Modules whose job is to import the kernel modules of other packages by name (to compile them
#: ahead); they may name private modules.
KERNEL_IMPORTERS = ("mrdamper.compiled",)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def _resolve(current: str, is_pkg: bool, level: int, module: str | None) -> str:
    if level == 0:
        return module or ""
    base = current.split(".") if is_pkg else current.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join([*base, module] if module else base)


def _imports(name: str, path: Path, known: set[str]) -> Iterator[tuple[str, str | None, int]]:
    """``(imported module, imported name or None, line)`` for every import of ``mrdamper``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_pkg = path.name == "__init__.py"
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "mrdamper":
                    yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(name, is_pkg, node.level, node.module)
            if mod.split(".")[0] != "mrdamper":
                continue
            for alias in node.names:
                sub = f"{mod}.{alias.name}"
                if sub in known:  # "from mrdamper.study import writer": a module
                    yield sub, None, node.lineno
                else:
                    yield mod, alias.name, node.lineno


def _dynamic_imports(path: Path, known: set[str]) -> Iterator[tuple[str, None, int]]:
    """Modules named by string constants in a module that calls ``importlib.import_module``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    uses = any(
        isinstance(n, ast.Call)
        and (
            (isinstance(n.func, ast.Attribute) and n.func.attr == "import_module")
            or (isinstance(n.func, ast.Name) and n.func.id == "import_module")
        )
        for n in ast.walk(tree)
    )
    if not uses:
        return
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in known:
            yield node.value, None, node.lineno


def _table_imports(name: str, known: set[str]) -> Iterator[tuple[str, None, int]]:
    """Imports that the kind table declares as data: the registry imports every kind's module,
    :mod:`mrdamper.compiled` every kernel module."""
    from mrdamper import kinds

    if name == "mrdamper.models.registry":
        targets = {row.module for row in kinds.KINDS}
    elif name == "mrdamper.compiled":
        targets = {item[0] for row in kinds.KINDS for item in row.kernels}
    else:
        return
    for target in sorted(targets & known):
        yield target, None, 0


def _package(module: str, known_pkgs: set[str]) -> str:
    """The subpackage a module belongs to (``mrdamper.study.runner`` -> ``mrdamper.study``)."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 and ".".join(parts[:2]) in known_pkgs else module


def _is_private(module: str) -> bool:
    return any(part.startswith("_") and part != "__init__" for part in module.split(".")[1:])


def _graph() -> tuple[dict[str, set[str]], list[str]]:
    mods = _modules()
    known = set(mods)
    pkgs = {m for m, p in mods.items() if p.name == "__init__.py"}
    edges: dict[str, set[str]] = {m: set() for m in mods}
    private: dict[str, None] = {}  # ordered, one entry per offending import
    for name, path in mods.items():
        found = [
            *_imports(name, path, known),
            *_dynamic_imports(path, known),
            *_table_imports(name, known),
        ]
        for target, imported, line in found:
            if target not in known:
                continue
            if target != name:
                edges[name].add(target)
            if _package(target, pkgs) == _package(name, pkgs):
                continue
            where = f"{path.relative_to(SRC)}:{line}"
            if _is_private(target) and not target.startswith(SHARED_PRIVATE):
                if name in KERNEL_IMPORTERS:
                    continue
                private[f"{name} -> {target} (private module, {where})"] = None
            elif (
                imported is not None and imported.startswith("_") and not imported.startswith("__")
            ):
                private[f"{name} -> {target}.{imported} (private name, {where})"] = None
    return edges, list(private)


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected component with more than one module (Tarjan), as a cycle path."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    comps: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return comps


def _cycle_edges(comp: list[str], edges: dict[str, set[str]]) -> list[str]:
    members = set(comp)
    return [f"{a} -> {b}" for a in comp for b in sorted(edges[a] & members)]


#: Layer of every package and top-level module (higher layers import lower ones only). Ground:
#: the kind table and the controllers' names (plain data), errors, progress reporting; output
#: safety, metrics; data and signals; analysis and figures; the model families; the virtual rig;
#: what runs models in loops and exports (control); the compile-ahead of every kernel (models'
#: and rig's); the comparison study; the curated public namespace; the command line.
LAYERS: dict[str, int] = {
    "mrdamper.kinds": 0,
    "mrdamper.controller_names": 0,
    "mrdamper.version": 0,
    "mrdamper.errors": 0,
    "mrdamper.progress": 0,
    "mrdamper._io": 1,
    "mrdamper._warn": 1,
    "mrdamper.metrics": 1,
    "mrdamper.data": 2,
    "mrdamper.signals": 2,
    "mrdamper.analysis": 3,
    "mrdamper.plotting": 3,
    "mrdamper.models": 4,
    "mrdamper.rig": 5,
    "mrdamper.uncertainty": 5,
    "mrdamper.control": 6,
    "mrdamper.compiled": 6,
    "mrdamper.conformance": 6,
    "mrdamper.study": 7,
    "mrdamper": 8,
    "mrdamper.cli": 9,
    "mrdamper.__main__": 10,
}


def _package_edges() -> dict[str, set[str]]:
    edges = _graph()[0]
    mods = _modules()
    pkgs = {m for m, p in mods.items() if p.name == "__init__.py"}
    out: dict[str, set[str]] = {}
    for a, targets in edges.items():
        pa = _package(a, pkgs)
        out.setdefault(pa, set())
        for b in targets:
            pb = _package(b, pkgs)
            if pb != pa:
                out[pa].add(pb)
                out.setdefault(pb, set())
    return out


def test_every_package_has_a_layer() -> None:
    missing = sorted(set(_package_edges()) - set(LAYERS))
    assert not missing, f"packages without a layer in LAYERS: {missing}"


def test_packages_import_only_lower_layers() -> None:
    edges = _package_edges()
    bad = [
        f"{a} (layer {LAYERS[a]}) -> {b} (layer {LAYERS[b]})"
        for a in sorted(edges)
        for b in sorted(edges[a])
        if a in LAYERS and b in LAYERS and LAYERS[b] >= LAYERS[a]
    ]
    assert not bad, "imports against the layer order:\n" + "\n".join(bad)


def test_no_package_cycles() -> None:
    edges = _package_edges()
    comps = _cycles(edges)
    text = "\n\n".join("\n".join(_cycle_edges(c, edges)) for c in comps)
    assert not comps, f"{len(comps)} circle(s) between packages:\n{text}"


def test_dynamic_imports_are_seen(tmp_path: Path) -> None:
    mod = tmp_path / "lazy.py"
    mod.write_text(
        "import importlib\n"
        'M = {"a": "mrdamper.models.lpv", "b": "not a module"}\n'
        'importlib.import_module(M["a"])\n'
    )
    found = list(_dynamic_imports(mod, {"mrdamper.models.lpv"}))
    assert [f[0] for f in found] == ["mrdamper.models.lpv"]


def test_modules_found() -> None:
    mods = _modules()
    assert "mrdamper.study.runner" in mods and "mrdamper.models.base" in mods


def test_no_import_cycles() -> None:
    edges = _graph()[0]
    comps = _cycles(edges)
    text = "\n\n".join("\n".join(_cycle_edges(c, edges)) for c in comps)
    assert not comps, f"{len(comps)} import circle(s); edges inside each:\n{text}"


def test_no_private_imports_across_packages() -> None:
    private = _graph()[1]
    assert not private, "private imports across packages:\n" + "\n".join(private)


@pytest.mark.parametrize(
    ("current", "is_pkg", "level", "module", "expected"),
    [
        ("mrdamper.study.runner", False, 1, "tables", "mrdamper.study.tables"),
        ("mrdamper.study", True, 1, "runner", "mrdamper.study.runner"),
        ("mrdamper.study.runner", False, 2, "data", "mrdamper.data"),
        ("mrdamper.study.runner", False, 0, "mrdamper.data", "mrdamper.data"),
    ],
)
def test_relative_imports_resolved(
    current: str, is_pkg: bool, level: int, module: str, expected: str
) -> None:
    assert _resolve(current, is_pkg, level, module) == expected


def test_cycle_finder_finds_a_circle() -> None:
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(edges) == [["a", "b", "c"]]
