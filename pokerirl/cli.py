"""The ``pokerirl`` command line: thin typer commands over the library."""

from __future__ import annotations

import json
from pathlib import Path
from typing import NoReturn

import typer

app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail(message: str, code: int = 1) -> NoReturn:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {message}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)


@app.command()
def ingest(
    sources: list[Path] = typer.Argument(
        ..., help="Month folders, folders of months, month .tgz archives or IRCdata.tgz."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The Parquet table to write."),
    strict: bool = typer.Option(False, "--strict", help="Stop at the first malformed line."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no summary."),
) -> None:
    """Turn IRC Poker Database hand histories into a Parquet state-action table.

    Writes TABLE and TABLE.summary.json (where every hand went) and prints the summary.
    """
    from pokerirl.datasets.ingest import ingest as run_ingest
    from pokerirl.parsers.irc import IngestError

    try:
        summary = run_ingest(sources, out, strict=strict, progress=not quiet)
    except IngestError as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    if not quiet:
        typer.echo(json.dumps(summary, indent=2))


@app.command()
def synth(
    out: Path = typer.Option(..., "--out", "-o", help="Folder to write <out>/holdem/<YYYYMM>/ in."),
    hands: int = typer.Option(10_000, "--hands", "-n", min=1, help="Number of hands."),
    seed: int = typer.Option(0, "--seed", help="Random seed: the same seed, the same files."),
) -> None:
    """Write a synthetic IRC-format month of heads-up 10-20 limit hold'em between two bots."""
    from pokerirl.game.synth import write_synthetic_month

    try:
        folder = write_synthetic_month(out, hands=hands, seed=seed)
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    typer.echo(f"wrote {hands} hands to {folder}")


@app.command()
def demo(
    out: Path = typer.Option(Path("demo-output"), "--out", "-o", help="Where the demo writes."),
    hands: int = typer.Option(20_000, "--hands", "-n", min=1, help="Synthetic hands to play."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
) -> None:
    """Run the pipeline on built-in synthetic data: synth, then ingest."""
    from pokerirl.datasets.ingest import ingest as run_ingest
    from pokerirl.datasets.ingest import summary_path
    from pokerirl.game.synth import write_synthetic_month

    out.mkdir(parents=True, exist_ok=True)
    typer.echo(f"[1/2] synth: {hands} heads-up hands, seed {seed}")
    folder = write_synthetic_month(out / "irc", hands=hands, seed=seed)
    table = out / "expert.parquet"
    typer.echo(f"[2/2] ingest: {folder} -> {table}")
    summary = run_ingest([folder], table, progress=True)
    typer.echo(json.dumps(summary, indent=2))
    typer.echo(f"\ndone: table {table}, summary {summary_path(table)}")


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


@app.command()
def tournament(
    agents: list[str] = typer.Argument(
        None,
        help="A B (one matchup, A's payoff), or with --vs the agents to play against BASE. "
        "Each: a built-in (random, raise, call), an agent folder, or an agent set (a folder "
        "of seed-<k> agent folders: seed k plays seed-k).",
        show_default=False,
    ),
    vs: str | None = typer.Option(
        None, "--vs", metavar="BASE", help="Play every AGENT against BASE (several matchups)."
    ),
    hands: int = typer.Option(1_000_000, "--hands", "-n", help="Hands per seed."),
    seeds: str = typer.Option("0-19", "--seeds", help="Seeds, e.g. 0-19 or 0-4,10."),
    out: Path = typer.Option(..., "--out", "-o", help="Report folder (resumes what it holds)."),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats, paired."
    ),
    jobs: int = typer.Option(2, "--jobs", "-j", help="Worker processes (results do not change)."),
    alpha: float = typer.Option(0.05, help="Family-wise error rate (Bonferroni, Holm)."),
    batch_size: int = typer.Option(65_536, help="Hands in lock-step (part of the config)."),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Recompute saved seeds from another configuration."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no report."),
) -> None:
    """Multi-seed head-to-head evaluation: mbb/h, duplicate deals, Bonferroni and Holm.

    \b
    One matchup:      pokerirl tournament A B --hands N --seeds 0-19 --out DIR
    Several matchups: pokerirl tournament --vs dqn hairl-dqn airl-dqn --out DIR
                      (hairl-dqn vs dqn and airl-dqn vs dqn, corrected together)

    Writes DIR/report.md, report.json, per_seed.csv, per_seed.png; prints the report.

    \b
    Resumable: each seed is saved when it finishes. A rerun reuses saved seeds
    whose agents, hands, duplicate mode and batch size match, and refuses the
    others (--overwrite recomputes them). pokerirl report DIR prints it again.
    """
    from pokerirl.tournaments import parse_seeds, render_report, run_tournament

    agents = agents or []
    if vs is not None:
        if not agents:
            fail("--vs BASE needs at least one agent to play against it")
        matchups = [(agent, vs) for agent in agents]
    elif len(agents) == 2:
        matchups = [(agents[0], agents[1])]
    else:
        fail(f"give two agents (A B) or --vs BASE and agents; got {len(agents)} agent(s)")
    try:
        report = run_tournament(
            matchups,
            hands=hands,
            seeds=parse_seeds(seeds),
            out=out,
            duplicate=duplicate,
            alpha=alpha,
            jobs=jobs,
            batch_size=batch_size,
            overwrite=overwrite,
            progress=not quiet,
        )
    except ValueError as error:  # TournamentError, or an agent's illegal move
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    if not quiet:
        typer.echo(render_report(report))
        typer.echo(f"wrote {out}/report.md, report.json, per_seed.csv, per_seed.png")


@app.command()
def report(
    folder: Path = typer.Argument(..., help="A folder written by pokerirl tournament."),
    output_format: str = typer.Option("markdown", "--format", help="markdown or json."),
) -> None:
    """Print a tournament report (Markdown, or JSON for scripts)."""
    from pokerirl.tournaments import load_report, render_report

    try:
        typer.echo(render_report(load_report(folder), output_format), nl=False)
    except ValueError as error:
        fail(str(error))
