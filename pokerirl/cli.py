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


@app.command()
def match(
    agent_a: str = typer.Argument(..., help="Agent A (reported): random, raise or call."),
    agent_b: str = typer.Argument(..., help="Agent B: random, raise or call."),
    hands: int = typer.Option(100_000, help="Hands to play (even with --duplicate)."),
    seed: int = typer.Option(0, help="Seed of the deals and of the agents' random draws."),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats."
    ),
    output_format: str = typer.Option("text", "--format", help="text or json."),
) -> None:
    """Play A against B and print A's result in milli-big-blinds per hand."""
    import json

    from pokerirl.game import make_agent, play_match

    if output_format not in ("text", "json"):
        fail(f"unknown format {output_format!r} (text or json)")
    try:
        result = play_match(
            make_agent(agent_a),
            make_agent(agent_b),
            hands=hands,
            seed=seed,
            duplicate=duplicate,
            progress=True,
        )
    except ValueError as error:
        fail(str(error))
    if output_format == "json":
        summary = {
            "mbb_per_hand": result.mbb_per_hand,
            "std_error": result.std_error,
            "hands": result.hands,
            "hands_per_second": result.hands_per_second,
        }
        typer.echo(json.dumps(summary))
    else:
        typer.echo(
            f"{result.agent_a} vs {result.agent_b}: {result.mbb_per_hand:+.1f} "
            f"+- {result.std_error:.1f} mbb/h over {result.hands:,} hands "
            f"({result.hands_per_second:,.0f} hands/s)"
        )
