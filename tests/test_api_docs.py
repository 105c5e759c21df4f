"""The API reference (``make docs``: docs/build_api.py, pdoc) builds, and every name of
``pokerirl.__all__`` and of each documented subpackage's ``__all__`` is in it; each class and
function as one (not as a bare variable) with a docstring of its own."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[1]


def build_api() -> ModuleType:
    spec = importlib.util.spec_from_file_location("build_api", ROOT / "docs" / "build_api.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def own_docstring(value: object) -> str:
    """A class's or function's docstring, empty when it has none of its own (a dataclass
    without one gets its signature as its __doc__)."""
    doc = (inspect.getdoc(value) or "").strip()
    name = getattr(value, "__name__", "")
    return "" if inspect.isclass(value) and doc.startswith(f"{name}(") else doc


def sections(page: str) -> dict[str, str]:
    """Each top-level entry of a pdoc page: its id and its HTML up to the next entry."""
    parts = re.split(r'<section id="([A-Za-z_][A-Za-z0-9_]*)">', page)
    return dict(zip(parts[1::2], parts[2::2], strict=True))


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, tuple[str, ...]]:
    pytest.importorskip("pdoc")  # the dev extra
    module = build_api()
    return module.build(tmp_path_factory.mktemp("api")), module.API_MODULES


@pytest.mark.slow
def test_the_reference_covers_every_exported_name(built: tuple[Path, tuple[str, ...]]) -> None:
    out, modules = built
    assert {"pokerirl", "pokerirl.irl", "pokerirl.game", "pokerirl.agents",
            "pokerirl.gym"} <= set(modules)  # fmt: skip
    assert (out / "index.html").is_file()
    checked = 0
    for name in modules:
        module = importlib.import_module(name)
        entries = sections((out / (name.replace(".", "/") + ".html")).read_text())
        exported = getattr(module, "__all__", None) or [
            n for n, v in vars(module).items()
            if not n.startswith("_") and getattr(v, "__module__", None) == name
        ]  # fmt: skip
        for export in exported:
            assert export in entries, f"{name}.{export} is not in the reference"
            value = getattr(module, export)
            if inspect.isclass(value) or inspect.isroutine(value):
                kind = "class" if inspect.isclass(value) else "function"
                assert f'class="attr {kind}"' in entries[export], f"{name}.{export}: not a {kind}"
                assert own_docstring(value), f"{name}.{export} has no docstring"
                assert 'class="docstring"' in entries[export], f"{name}.{export}: no docstring"
            checked += 1
    assert checked > 100  # the subpackages' surfaces, not only the top level's
