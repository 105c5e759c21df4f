"""The import boundaries: a layer never imports a higher one, components do not import each
other in a cycle, and ``irl/`` knows nothing of poker (nor of Gymnasium, the agents, the
studies or the command line).

Imports are read with ``ast`` from every module of the package: module-level and
function-level ones alike (lazy imports are still dependencies), ``TYPE_CHECKING`` ones too,
and ``importlib.import_module("pokerirl....")`` with a literal name.

:data:`KNOWN_VIOLATIONS` lists the violations of today's tree, module by module, each with its
reason. The tests fail on any violation not in it, and on any entry that is no longer a
violation, so the list only shrinks. It is empty since issue 18 moved the poker table reader
and the toy table to ``datasets/`` and ``pokerirl train`` to ``poker/``.
"""

from __future__ import annotations

import ast
import itertools
import re
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "pokerirl"

# Lowest first. A component may import those of its own layer and of lower ones.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("holdem", "atomic", "seeds", "versions", "errors", "jsonio", "parquet", "meanstd", "figures",
     "scalars", "serial", "stacking", "settings", "cache"),
    ("execution",),
    ("store",),
    ("parsers", "datasets", "game"),
    ("irl",),
    ("poker",),  # decision tables as Transitions, `pokerirl train`, the poker rewards
    ("agents", "gym"),  # DQN agents learn from poker rewards; poker knows no agent
    ("tournaments",),
    ("studies",),
    ("cli", "__main__"),
)
LAYER = {component: rank for rank, names in enumerate(LAYERS) for component in names}

# irl/ trains on Transitions with the nets it is given: no poker below it either, and
# (named here too, so that a change to LAYERS cannot let them in) nothing above it.
IRL_FORBIDDEN = frozenset(
    {"holdem", "parsers", "datasets", "game"}  # poker, below irl/
    | {"agents", "gym", "poker", "tournaments", "studies", "cli", "__main__"}
)

# (module, component it must not import) -> why it still does. Empty: add an entry only with
# its reason, and a plan to remove it.
KNOWN_VIOLATIONS_WHY: dict[tuple[str, str], str] = {}
KNOWN_VIOLATIONS: frozenset[tuple[str, str]] = frozenset(KNOWN_VIOLATIONS_WHY)


@dataclass(frozen=True)
class Import:
    module: str  # the importing module, e.g. pokerirl.irl.table
    component: str  # the imported component, e.g. holdem
    line: int


def component_of(name: str, package: Path) -> str | None:
    """``holdem`` for ``pokerirl.holdem.ACTIONS``, None outside the package or for the
    package itself (``from pokerirl import __version__``)."""
    parts = name.split(".")
    if parts[0] != package.name or len(parts) < 2:
        return None
    head = parts[1]
    if (package / head).is_dir() or (package / f"{head}.py").is_file():
        return head
    return None


def module_name(path: Path, package: Path) -> str:
    parts = list(path.relative_to(package.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path, package: Path) -> Iterator[Import]:
    """Every import of another component in the module at ``path``."""
    module = module_name(path, package)
    own = component_of(module, package)
    base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            origin = node.module or ""
            if node.level:  # relative: from .x import y, from .. import z
                origin = ".".join([*base[: len(base) - node.level + 1], *filter(None, [origin])])
            # from pokerirl import execution: the names may be components themselves
            names = [f"{origin}.{alias.name}" for alias in node.names] + [origin]
        elif isinstance(node, ast.Call) and _is_import_module(node.func) and node.args:
            names = [_literal_prefix(node.args[0])]
        for name in names:
            found = component_of(name, package)
            if found is not None and found != own:
                yield Import(module, found, node.lineno)


def _is_import_module(func: ast.expr) -> bool:
    return (isinstance(func, ast.Attribute) and func.attr == "import_module") or (
        isinstance(func, ast.Name) and func.id in ("import_module", "__import__")
    )


def _literal_prefix(argument: ast.expr) -> str:
    """The constant start of a module name given as a string or an f-string."""
    if isinstance(argument, ast.Constant) and isinstance(argument.value, str):
        return argument.value
    if isinstance(argument, ast.JoinedStr) and argument.values:
        first = argument.values[0]
        if isinstance(first, ast.Constant) and isinstance(first.value, str):
            return first.value.rstrip(".") if first.value.endswith(".") else ""
    return ""


def all_imports(package: Path = PACKAGE) -> list[Import]:
    return [found for path in sorted(package.rglob("*.py")) for found in imports_of(path, package)]


def violations(found: list[Import], package: Path = PACKAGE) -> dict[tuple[str, str], int]:
    """(module, component) -> first line, for every import against the layers or of poker
    under irl/."""
    bad: dict[tuple[str, str], int] = {}
    for item in found:
        own = component_of(item.module, package)
        assert own is not None
        upward = LAYER[item.component] > LAYER[own]
        poker_in_irl = own == "irl" and item.component in IRL_FORBIDDEN
        if upward or poker_in_irl:
            bad.setdefault((item.module, item.component), item.line)
    return bad


def cycles(found: list[Import], package: Path = PACKAGE) -> list[tuple[str, str]]:
    """Pairs of components that import each other (peers of one layer may import each other
    one way only)."""
    edges: defaultdict[str, set[str]] = defaultdict(set)
    for item in found:
        own = component_of(item.module, package)
        assert own is not None
        edges[own].add(item.component)
    return sorted((a, b) for a, b in itertools.combinations(sorted(edges), 2) if b in edges[a]
                  and a in edges[b])  # fmt: skip


def test_every_component_has_a_layer() -> None:
    components = {component_of(module_name(p, PACKAGE), PACKAGE) for p in PACKAGE.rglob("*.py")}
    unknown = sorted(c for c in components - {None} if c not in LAYER)
    assert not unknown, f"add these to LAYERS in tests/test_layers.py: {unknown}"


def test_no_new_import_crosses_a_layer_or_brings_poker_into_irl() -> None:
    found = violations(all_imports())
    new = {pair: line for pair, line in found.items() if pair not in KNOWN_VIOLATIONS}
    assert not new, "imports against the layers (module -> component: line): " + ", ".join(
        f"{module} -> {component}: {line}" for (module, component), line in sorted(new.items())
    )


def test_the_known_violations_are_still_there() -> None:
    """A violation fixed must leave KNOWN_VIOLATIONS too, so the list only shrinks."""
    gone = sorted(KNOWN_VIOLATIONS - violations(all_imports()).keys())
    assert not gone, f"fixed: remove from KNOWN_VIOLATIONS: {gone}"


def test_irl_imports_nothing_of_poker_gym_or_above() -> None:
    """The boundary on its own: every import under ``irl/``, lazy ones included, stays in
    ``irl/`` or reaches only the generic layers below it."""
    found = sorted(
        {f"{item.module} -> {item.component}: {item.line}"
        for item in all_imports()
        if item.module.startswith("pokerirl.irl") and item.component in IRL_FORBIDDEN}
    )  # fmt: skip
    assert found == []


# The library does not know the command line: its errors name no flag (the CLI adds its own,
# see pokerirl.errors.Remedy). Checked everywhere but the cli; (module, function) -> why not.
FLAG_FREE_BUT = ("cli",)  # every component of the library but the command line
FLAG_EXCEPTIONS: dict[tuple[str, str], str] = {
    ("pokerirl.execution.ray_private", "ray_head"): "names Ray's own command, `ray start --head`",
}
FLAG = re.compile(r"(?<![\w-])--[a-z]")


def flags_in_raises(path: Path, package: Path = PACKAGE) -> Iterator[tuple[str, str, int]]:
    """(module, function, line) of each ``raise`` whose message text names a ``--flag``."""
    module = module_name(path, package)
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    functions = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]
    owner = {id(node): f.name for f in functions for node in ast.walk(f)}
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)):
            continue
        texts = [
            part.value
            for argument in node.exc.args
            for part in ast.walk(argument)
            if isinstance(part, ast.Constant) and isinstance(part.value, str)
        ]
        if any(FLAG.search(text) for text in texts):
            yield module, owner.get(id(node), "<module>"), node.lineno


def test_library_errors_name_no_flag() -> None:
    paths = [
        path
        for path in sorted(PACKAGE.rglob("*.py"))
        if component_of(module_name(path, PACKAGE), PACKAGE) not in FLAG_FREE_BUT
    ]
    found = [hit for path in paths for hit in flags_in_raises(path)]
    new = [f"{m}.{f}: {line}" for m, f, line in found if (m, f) not in FLAG_EXCEPTIONS]
    assert new == [], "library errors that name a command-line flag (the CLI adds its own)"
    gone = set(FLAG_EXCEPTIONS) - {(m, f) for m, f, _ in found}
    assert not gone, f"fixed: remove from FLAG_EXCEPTIONS: {sorted(gone)}"


def test_the_flag_check_sees_a_flag_in_an_f_string(tmp_path: Path) -> None:
    module = tmp_path / "pokerirl" / "irl" / "new.py"
    module.parent.mkdir(parents=True)
    module.write_text(
        "def f(out):\n    raise ValueError(f'{out} is taken; pass --overwrite')\n"
        "def g(out):\n    raise ValueError(f'{out} is taken', 'x--y')\n"
    )
    assert list(flags_in_raises(module, tmp_path / "pokerirl")) == [("pokerirl.irl.new", "f", 2)]


def test_no_two_components_import_each_other() -> None:
    known = [i for i in all_imports() if (i.module, i.component) not in KNOWN_VIOLATIONS]
    assert cycles(known) == []


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("import pokerirl.holdem", {("pokerirl.irl.new", "holdem")}),
        ("from pokerirl.holdem import ACTIONS", {("pokerirl.irl.new", "holdem")}),
        ("from pokerirl import datasets", {("pokerirl.irl.new", "datasets")}),
        ("from .. import game", {("pokerirl.irl.new", "game")}),
        ("def f():\n    from pokerirl.cli import app", {("pokerirl.irl.new", "cli")}),
        ("import importlib as i\ni.import_module('pokerirl.gym')", {("pokerirl.irl.new", "gym")}),
        ("from pokerirl import __version__\nfrom pokerirl.execution import map_units", set()),
        ("from . import run\nfrom pokerirl.store import run_units", set()),
        ("def f():\n    from pokerirl.poker import read_table", {("pokerirl.irl.new", "poker")}),
        ("from pokerirl.parquet import fixed_width", set()),
    ],
)  # fmt: skip
def test_the_checker_sees_each_kind_of_import(
    tmp_path: Path, source: str, expected: set[tuple[str, str]]
) -> None:
    """A copy of the layout with one new module under irl/: what the checker reports."""
    package = tmp_path / "pokerirl"
    for name in ("irl", "datasets", "game", "cli", "gym", "store", "poker"):
        (package / name).mkdir(parents=True)
        (package / name / "__init__.py").write_text("")
    for name in ("holdem", "execution", "parquet"):
        (package / f"{name}.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "irl" / "run.py").write_text("")
    (package / "irl" / "new.py").write_text(source + "\n")
    assert set(violations(all_imports(package), package)) == expected


def test_a_cycle_between_peers_is_seen(tmp_path: Path) -> None:
    package = tmp_path / "pokerirl"
    for name, source in (("agents", "from pokerirl import gym"), ("gym", "import pokerirl.agents")):
        (package / name).mkdir(parents=True)
        (package / name / "__init__.py").write_text(source + "\n")
    assert cycles(all_imports(package), package) == [("agents", "gym")]
