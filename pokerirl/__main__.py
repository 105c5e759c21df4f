"""``python -m pokerirl``: the ``pokerirl`` command line (:mod:`pokerirl.cli`), under its name."""

from __future__ import annotations

from pokerirl.cli import app

app(prog_name="pokerirl")
