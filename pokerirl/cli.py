"""The ``pokerirl`` command line: thin typer commands over the library."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail(message: str, code: int = 1) -> None:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {message}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)
