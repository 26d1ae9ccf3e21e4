"""The package's layers, read from its source: no import circle (lazy name tables counted),
no module taking a helper from the front of a package it belongs to, no private name imported
across modules, and a core that never imports the outer wing (simulation, evaluation, export,
control, cli, benchmark)."""

from __future__ import annotations

import ast
import functools
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1] / "pysindy_xl"
OUTER = ("simulation", "evaluation", "export", "control", "cli", "benchmark", "quality",
         "held_out")
FACES = {"pysindy_xl", "pysindy_xl.mujoco"}  # fronts that hand on names of both wings
# the estimator's methods that hand a fitted model to the outer wing when called
DELEGATIONS = {"pysindy_xl.fitted.dynamics"}


def _name(path):
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


FILES = {_name(p): p for p in ROOT.rglob("*.py")}
PACKAGES = {_name(p) for p in ROOT.rglob("__init__.py")}


def _known(target):
    while target and target not in FILES:
        target = target.rpartition(".")[0]
    return target


@functools.cache
def _imports(name):
    """``(target module, imported name or None, line, at module level)`` of every import
    (read once per module)."""
    return tuple(_read_imports(name))


def _read_imports(name):
    path = FILES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    # statements at module level: the module's own, and those of its top-level if/try blocks
    top = {id(node) for node in tree.body}
    top |= {id(node) for block in tree.body if isinstance(block, (ast.If, ast.Try))
            for node in block.body}
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if _known(alias.name):
                    yield _known(alias.name), None, node.lineno, id(node) in top
        elif isinstance(node, ast.ImportFrom):
            stem = node.module or ""
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                stem = ".".join(base + ([node.module] if node.module else []))
            if not stem.startswith("pysindy_xl"):
                continue
            for alias in node.names:
                full = f"{stem}.{alias.name}"
                if full in FILES:
                    yield full, None, node.lineno, id(node) in top
                else:
                    yield _known(stem), alias.name, node.lineno, id(node) in top


def _lazy_targets(name):
    """Submodules named by the ``_LAZY`` table of a package front."""
    tree = ast.parse(FILES[name].read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "_LAZY"
                                                for t in node.targets):
            for leaf in ast.walk(node.value):
                if isinstance(leaf, ast.Constant) and isinstance(leaf.value, str):
                    stripped = leaf.value.lstrip(".")
                    up = max(len(leaf.value) - len(stripped) - 1, 0)
                    base = name.split(".")[:len(name.split(".")) - up]
                    target = ".".join(base + [stripped])
                    if target in FILES:
                        yield target


def _outer(name):
    return any(name == f"pysindy_xl.{o}" or name.startswith(f"pysindy_xl.{o}.") for o in OUTER)


def test_no_import_circle_even_through_lazy_name_tables():
    graph = {name: {t for t, *_ in _imports(name) if t != name} for name in FILES}
    for name in PACKAGES:
        graph[name] |= set(_lazy_targets(name))
    index, low, stack, circles = {}, {}, [], []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = stack[stack.index(v):]
            del stack[stack.index(v):]
            if len(component) > 1:
                circles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    assert circles == []


@pytest.mark.parametrize("rule", ["own front", "private name"])
def test_no_module_takes_a_helper_from_its_front_or_a_private_name_from_a_sibling(rule):
    found = []
    for name in FILES:
        for target, imported, line, _ in _imports(name):
            if imported is None or target == name:
                continue
            if rule == "own front" and target in PACKAGES and name.startswith(target + ".") \
                    and not imported.startswith("__"):  # a front's own data (__version__) aside
                found.append(f"{name}:{line} {imported}")
            if rule == "private name" and imported.startswith("_") \
                    and not imported.startswith("__"):
                found.append(f"{name}:{line} {target}.{imported}")
    assert found == []


def test_the_core_never_imports_the_outer_wing():
    found = [f"{name}:{line} -> {target}" for name in FILES
             if not _outer(name) and name not in FACES
             for target, _, line, top in _imports(name)
             if _outer(target) and (top or name not in DELEGATIONS)]
    assert found == []
