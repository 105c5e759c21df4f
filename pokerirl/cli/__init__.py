"""The ``pokerirl`` command line: thin typer commands over the library, one module per group.

Importing the package registers every command on :data:`app` (the ``pokerirl`` script).
"""

from __future__ import annotations

# isort: off  (the order of registration is the order of `pokerirl --help`)
from pokerirl.cli import (
    data,  # noqa: F401  (pokerirl data: the named IRC data)
    exploit,  # noqa: F401  (pokerirl exploit: local best response)
    gym,  # noqa: F401
    leduc,  # noqa: F401  (pokerirl leduc: CFR+, exact best response)
    play,  # noqa: F401  (pokerirl match, tournament)
    poker,  # noqa: F401
    studies,  # noqa: F401
    sweep,  # noqa: F401  (pokerirl sweep: the poker sweep)
)
from pokerirl.cli.app import app

# isort: on

__all__ = ["app"]
