"""The ``pokerirl`` command group (:data:`app`): its ``--debug`` option and ``version``; the
commands live beside it, by group (poker, studies, gym, ...), and register on it.

What the commands share lives in modules named for it: the error contract and how lines are
shown (:mod:`pokerirl.cli.errors`), seeds (:mod:`pokerirl.cli.seeds`), options made from config
dataclasses and the shared ones (:mod:`pokerirl.cli.options`), and where a fan-out command's
units run (:mod:`pokerirl.cli.fanout`).
"""

from __future__ import annotations

import os

import typer

from pokerirl.cli.errors import OneLineErrors
from pokerirl.errors import DEBUG_VARIABLE

app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    cls=OneLineErrors,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: fits 80 columns, no boxes cutting flag names
)


@app.callback()
def main(
    debug: bool = typer.Option(
        False, "--debug", help=f"Print the traceback of any error (as {DEBUG_VARIABLE}=1 does)."
    ),
) -> None:
    if debug:  # the environment: worker processes and every command's contract read it
        os.environ[DEBUG_VARIABLE] = "1"


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)
