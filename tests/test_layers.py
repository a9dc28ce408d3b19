"""The layer contract of docs/architecture.md, read from the source (no import of pinflex).

Every ``import`` of every module counts, also those inside functions and methods (they run
when called; only ``if TYPE_CHECKING:`` blocks are left out, they never run):

* no import cycle between modules;
* a package imports only packages of its own layer or below (``LAYERS``);
* no module reads a private name (``_name``) of another package: neither
  ``from pinflex.other import _name``, nor ``module._name`` of an imported pinflex module,
  nor ``obj._name`` where ``_name`` is defined only in another package's source.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "pinflex"

#: Packages and top-level modules of pinflex by layer, lowest first. A module may import its
#: own layer (without cycles) and the layers below, never above.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("exceptions", "lazy", "resources", "validation", "progress", "outputs", "linalg", "jets",
     "beam", "sections", "materials", "summaries", "fields"),
    ("description", "checks"),
    ("native", "trajectory"),
    ("erls",),
    ("parametric", "prbdm"),
    ("assignment", "dynamics", "lumped"),
    ("batch",),
    ("visualization", "cases"),
    ("cli", "__main__", "pinflex"),
)

#: Import cycles that are known and owned elsewhere; the test fails when one disappears too
#: (then remove it here). Each entry: the modules of one cycle.
KNOWN_CYCLES: tuple[frozenset[str], ...] = ()

#: Imports against the layers, each with its reason: (module, imported module): why.
KNOWN_UPWARD: dict[tuple[str, str], str] = {
    ("pinflex.assignment.study", "pinflex.cases.benchmark_a_path"):
        "a study file may name a shipped trajectory (builtin = 'benchmark_a')",
}


class _Module:
    def __init__(self, name: str, path: Path, package: bool):
        self.name, self.path, self.package = name, path, package
        self.tree = ast.parse(path.read_text(), str(path))


def _modules() -> dict[str, _Module]:
    out = {}
    for path in sorted(SRC.rglob("*.py")):
        parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
        package = parts[-1] == "__init__"
        if package:
            parts = parts[:-1]
        out[".".join(parts)] = _Module(".".join(parts), path, package)
    return out


MODULES = _modules()


def _group(name: str) -> str:
    """The layer unit of a module: its first package under pinflex (or ``pinflex``)."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else "pinflex"


def _walk(tree: ast.AST):
    """Every node except those under ``if TYPE_CHECKING:``."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            stack.extend(node.orelse)
            continue
        yield node
        stack.extend(ast.iter_child_nodes(node))


def _source(mod: _Module, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = mod.name.split(".")
    if not mod.package:
        base = base[:-1]
    base = base[: len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _exports(mod: _Module) -> dict[str, str]:
    """Names a package's ``__init__`` binds, and the module each comes from."""
    out: dict[str, str] = {}
    for node in _walk(mod.tree):
        if isinstance(node, ast.ImportFrom):
            for a in node.names:
                out[a.asname or a.name] = _source(mod, node)
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Dict) and any(
                getattr(t, "id", "") == "_EXPORTS" for t in node.targets):  # lazy exports
            for k, v in zip(node.value.keys, node.value.values):
                if isinstance(k, ast.Constant) and isinstance(v, ast.Constant):
                    out[k.value] = v.value
    return out


EXPORTS = {name: _exports(m) for name, m in MODULES.items() if m.package}


def _target(src: str, name: str) -> str:
    """The module that ``from src import name`` loads: a submodule, or the defining one."""
    full = f"{src}.{name}"
    if full in MODULES:
        return full
    seen = set()
    while src in EXPORTS and name in EXPORTS[src] and src not in seen:
        seen.add(src)
        nxt = EXPORTS[src][name]
        if nxt == src or nxt not in MODULES:
            break
        src = nxt
    return src


def _imports(mod: _Module) -> dict[str, int]:
    """``{imported pinflex module: first line}`` of a module."""
    out: dict[str, int] = {}
    for node in _walk(mod.tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "pinflex":
                    tgt = a.name if a.name in MODULES else a.name.rsplit(".", 1)[0]
                    out.setdefault(tgt, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            src = _source(mod, node)
            if src.split(".")[0] != "pinflex":
                continue
            for a in node.names:
                tgt = src if src == mod.name else _target(src, a.name)
                out.setdefault(tgt, node.lineno)
    out.pop(mod.name, None)
    return {k: v for k, v in out.items() if k in MODULES}


GRAPH = {name: _imports(m) for name, m in MODULES.items()}


def _cycles() -> list[frozenset[str]]:
    """Strongly connected components with more than one module (iterative Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out = []
    counter = 0
    for root in GRAPH:
        if root in index:
            continue
        work = [(root, iter(GRAPH[root]))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(GRAPH[w])))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = set()
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.add(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(frozenset(comp))
    return out


def test_every_package_has_a_layer():
    """A new package or top-level module must be placed in LAYERS (and the docs)."""
    placed = {g for layer in LAYERS for g in layer}
    assert {_group(m) for m in MODULES} <= placed, {_group(m) for m in MODULES} - placed


def test_no_import_cycles():
    """No two modules import each other, directly or around a loop (imports in functions too)."""
    found = _cycles()
    unknown = [sorted(c) for c in found if c not in KNOWN_CYCLES]
    assert not unknown, f"import cycles: {unknown}"
    gone = [sorted(c) for c in KNOWN_CYCLES if c not in found]
    assert not gone, f"fixed cycles still listed in KNOWN_CYCLES: {gone}"


def test_layers_import_only_downwards():
    """A package imports only its own layer and the layers below."""
    level = {g: i for i, layer in enumerate(LAYERS) for g in layer}
    bad = []
    for name, targets in GRAPH.items():
        for tgt, line in targets.items():
            a, b = _group(name), _group(tgt)
            if a != b and level[b] > level[a] and (name, tgt) not in KNOWN_UPWARD:
                bad.append(f"{MODULES[name].path.relative_to(SRC.parent)}:{line} imports {tgt} "
                           f"(layer {level[b]} above {level[a]})")
    assert not bad, "\n".join(bad)


def _defined_private() -> dict[str, set[str]]:
    """``{_name: groups whose source defines it}`` (functions, classes, attributes, slots)."""
    out: dict[str, set[str]] = {}
    for name, mod in MODULES.items():
        group = _group(name)
        for node in ast.walk(mod.tree):
            names = []
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                names.append(node.name)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                names.append(node.attr)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.append(node.id)
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names.append(node.target.id)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                names.append(node.value)  # __slots__ entries, setattr names
            for n in names:
                if n.startswith("_") and not n.startswith("__"):
                    out.setdefault(n, set()).add(group)
    return out


def test_no_private_names_read_across_packages():
    """No ``pinflex.other._name`` (import or attribute) from another package."""
    defined = _defined_private()
    bad = []
    for name, mod in MODULES.items():
        group = _group(name)
        modules: dict[str, str] = {}  # local name -> pinflex module it is bound to
        for node in _walk(mod.tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.split(".")[0] == "pinflex":
                        modules[a.asname or a.name.split(".")[0]] = a.name
            elif isinstance(node, ast.ImportFrom):
                src = _source(mod, node)
                if src.split(".")[0] != "pinflex":
                    continue
                for a in node.names:
                    if f"{src}.{a.name}" in MODULES:
                        modules[a.asname or a.name] = f"{src}.{a.name}"
                    private = a.name.startswith("_") and not a.name.startswith("__")
                    if private and _group(src) != group:
                        bad.append(f"{mod.path.name}:{node.lineno} imports {src}.{a.name}")
        for node in _walk(mod.tree):
            if not isinstance(node, ast.Attribute) or not node.attr.startswith("_") or (
                    node.attr.startswith("__")):
                continue
            where = f"{mod.path.relative_to(SRC.parent)}:{node.lineno}"
            value = node.value
            if isinstance(value, ast.Name) and value.id in modules:
                if _group(modules[value.id]) != group:
                    bad.append(f"{where} reads {modules[value.id]}.{node.attr}")
                continue
            if isinstance(value, ast.Name) and value.id in ("self", "cls"):
                continue
            owners = defined.get(node.attr, set())
            if owners and group not in owners:
                bad.append(f"{where} reads .{node.attr} (defined in {', '.join(sorted(owners))})")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("package", ["erls", "parametric", "native", "jets"])
def test_core_packages_do_not_import_the_cases(package):
    """Published cases and demo data sit above the library (pinflex.cases)."""
    bad = [name for name, targets in GRAPH.items() if _group(name) == package
           and any(_group(t) == "cases" for t in targets)]
    assert not bad, bad
