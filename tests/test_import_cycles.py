"""Import cycles between ``pokerirl`` modules: none but the :data:`KNOWN_CYCLES`.

test_layers.py checks components (``irl`` never imports ``gym``); this checks modules, inside a
component too (``pokerirl.execution.local`` and ``pokerirl.execution.scratch`` may not import
each other, even lazily). An edge A -> B is any import of B written in A, read with ``ast``:
at module level, inside functions (a lazy import is still a loop), in ``TYPE_CHECKING``
blocks, and ``importlib.import_module`` with a literal name. ``import a.b.c`` and
``from a.b import c`` lead to the module ``a.b.c`` when it exists, else to the longest
module prefix (``from pokerirl.holdem import ACTIONS``: ``pokerirl.holdem``); the
packages above it, which Python imports first, are not edges (else every package whose
``__init__`` re-exports its modules would be a loop with each of them). Names built at run
time (``pokerirl.__getattr__``'s table) are not seen.

A cycle is a strongly connected component of that graph with more than one module. The
test fails on a component not in :data:`KNOWN_CYCLES` (a new loop, or a known one that grew)
and on a listed one that no longer exists, so the list only shrinks.
"""

from __future__ import annotations

import ast
from collections import deque
from collections.abc import Iterator
from pathlib import Path

import pytest
from test_layers import PACKAGE, _is_import_module, _literal_prefix, module_name

# The modules of each cycle left -> why it is left. Empty: issue 44 broke the six there were
# (agents/names.py, gym/envs.py, poker/reward_sources.py, NetSpec.of in irl/nets.py,
# irl/folder.py, game/cases.py). A loop someone must keep goes here with its reason.
KNOWN_CYCLES_WHY: dict[tuple[str, ...], str] = {}
KNOWN_CYCLES: frozenset[frozenset[str]] = frozenset(map(frozenset, KNOWN_CYCLES_WHY))


def module_paths(package: Path = PACKAGE) -> dict[str, Path]:
    return {module_name(path, package): path for path in sorted(package.rglob("*.py"))}


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The module ``name`` leads to: itself, or its longest prefix that is a module."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        candidate = ".".join(parts[:end])
        if candidate in modules:
            return candidate
    return None


def imported_names(module: str, path: Path) -> Iterator[str]:
    """Every dotted name the module at ``path`` imports, relative imports made absolute."""
    base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            origin = node.module or ""
            if node.level:  # from .x import y, from .. import z
                origin = ".".join([*base[: len(base) - node.level + 1], *filter(None, [origin])])
            yield from (f"{origin}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Call) and _is_import_module(node.func) and node.args:
            yield _literal_prefix(node.args[0])


def import_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports (itself left out)."""
    modules = module_paths(package)
    graph: dict[str, set[str]] = {}
    for module, path in modules.items():
        targets = {_resolve(name, modules) for name in imported_names(module, path)}
        graph[module] = {target for target in targets if target is not None and target != module}
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """Tarjan's components of more than one module, iteratively (no recursion limit)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(frozenset(component))
    return sorted(found, key=sorted)


def one_loop(component: frozenset[str], graph: dict[str, set[str]]) -> list[str]:
    """A shortest loop through the component's first module, to show in a message."""
    start = min(component)
    came_from: dict[str, str] = {}
    todo = deque([start])
    while todo:
        node = todo.popleft()
        for child in sorted(graph[node] & component):
            if child == start:
                loop = [node]
                while loop[-1] != start:
                    loop.append(came_from[loop[-1]])
                return [*reversed(loop), start]
            if child not in came_from:
                came_from[child] = node
                todo.append(child)
    raise AssertionError(f"no loop through {start}")  # a component always has one


def describe(components: list[frozenset[str]], graph: dict[str, set[str]]) -> str:
    return "; ".join(
        f"{len(c)} modules, e.g. {' -> '.join(one_loop(c, graph))}" for c in components
    )


def test_no_new_import_cycle() -> None:
    graph = import_graph()
    new = [c for c in strongly_connected(graph) if c not in KNOWN_CYCLES]
    assert not new, "import cycles not in KNOWN_CYCLES: " + describe(new, graph)


def test_the_known_cycles_are_still_there() -> None:
    """A cycle broken (or changed) must leave KNOWN_CYCLES too, so the list only shrinks."""
    found = strongly_connected(import_graph())
    gone = sorted(sorted(c) for c in KNOWN_CYCLES if c not in found)
    assert not gone, f"no longer cycles: remove from KNOWN_CYCLES: {gone}"


def _layout(tmp_path: Path, files: dict[str, str]) -> Path:
    package = tmp_path / "pokerirl"
    for name, source in files.items():
        path = package / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source + "\n")
    return package


@pytest.mark.parametrize(
    ("files", "expected"),
    [
        ({"a.py": "import pokerirl.b", "b.py": "from pokerirl import a"},
         [{"pokerirl.a", "pokerirl.b"}]),
        ({"a.py": "def f():\n    from pokerirl.b import x", "b.py": "from pokerirl.a import y"},
         [{"pokerirl.a", "pokerirl.b"}]),
        ({"a.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pokerirl import b",
          "b.py": "import importlib\nimportlib.import_module('pokerirl.c')",
          "c.py": "from pokerirl.a import z"}, [{"pokerirl.a", "pokerirl.b", "pokerirl.c"}]),
        ({"p/__init__.py": "from pokerirl.p.x import f", "p/x.py": "from .y import g",
          "p/y.py": "from . import x"}, [{"pokerirl.p.x", "pokerirl.p.y"}]),
        # a package re-exporting its modules, which import each other one way: no loop
        ({"p/__init__.py": "from .x import f\nfrom .y import g",
          "p/x.py": "from pokerirl.p.y import g", "p/y.py": "import os"}, []),
        # a module of a package importing the package itself: a loop through its __init__
        ({"p/__init__.py": "from .x import f", "p/x.py": "from pokerirl.p import g"},
         [{"pokerirl.p", "pokerirl.p.x"}]),
        ({"a.py": "import pokerirl.a\nfrom pokerirl import a"}, []),  # itself: no loop
    ],
)  # fmt: skip
def test_the_checker_sees_each_kind_of_loop(
    tmp_path: Path, files: dict[str, str], expected: list[set[str]]
) -> None:
    package = _layout(tmp_path, {"__init__.py": "", **files})
    assert [set(c) for c in strongly_connected(import_graph(package))] == expected


def test_a_message_names_a_loop(tmp_path: Path) -> None:
    package = _layout(tmp_path, {"__init__.py": "", "a.py": "import pokerirl.b",
                                 "b.py": "import pokerirl.c",
                                 "c.py": "import pokerirl.a\nimport pokerirl.b"})  # fmt: skip
    graph = import_graph(package)
    assert describe(strongly_connected(graph), graph) == (
        "3 modules, e.g. pokerirl.a -> pokerirl.b -> pokerirl.c -> pokerirl.a"
    )
