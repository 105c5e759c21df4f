"""Build the HTML API reference of pokerirl's curated surface with pdoc (``make docs``).

    python docs/build_api.py [OUT]     # default: docs/api/ (git-ignored)

Documents the top-level package (``pokerirl.__all__``) and the subpackages whose ``__all__``
is their public surface, from the docstrings (reStructuredText). Names a package imports
lazily, on first use (PEP 562), are resolved first: pdoc reads a module's ``__dict__`` and
would otherwise list them as bare variables. Needs the ``dev`` extra (pdoc).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

API_MODULES = (
    "pokerirl",
    "pokerirl.irl",
    "pokerirl.game",
    "pokerirl.game.encodings",
    "pokerirl.agents",
    "pokerirl.gym",
    "pokerirl.tournaments",
)


def resolve_lazy(modules: tuple[str, ...] = API_MODULES) -> None:
    """Bind every name of each module's ``__all__`` in the module itself (imports torch,
    Gymnasium and SB3 for the names that need them)."""
    for name in modules:
        module = importlib.import_module(name)
        for export in getattr(module, "__all__", ()):
            # Not bound yet, or bound to a submodule of the same name (pokerirl.irl.baselines
            # the module, imported by another, hides baselines the function).
            if isinstance(vars(module).get(export, ModuleType("unbound")), ModuleType):
                setattr(module, export, getattr(module, export))


def build(out: str | Path = "docs/api") -> Path:
    """Write the reference into ``out`` (its ``index.html`` lists the modules); return it."""
    import pdoc  # the dev extra

    resolve_lazy()
    pdoc.render.configure(docformat="restructuredtext", show_source=False)
    pdoc.pdoc(*API_MODULES, output_directory=Path(out))
    return Path(out)


if __name__ == "__main__":
    print(f"API reference: {build(*sys.argv[1:2]) / 'index.html'}")
