"""The commands that play agents against each other: match and tournament (hold'em, sampled;
with ``--game leduc``, exact over every deal: :mod:`pokerirl.cli.leduc`)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import typer

from pokerirl.cli.app import app
from pokerirl.cli.errors import INTERRUPTED, echo, on_error, settings_from_options
from pokerirl.cli.fanout import command_backend
from pokerirl.cli.options import (
    ENCODING_CHOICES,
    GAME_OPTION,
    RULES_OPTION,
    choices,
    holdem_only,
    leduc_rules,
    parse_encoding,
)
from pokerirl.cli.seeds import SEED_OPTION, seed_list
from pokerirl.errors import InputError, UsageError
from pokerirl.game.leduc.rules import RuleSet
from pokerirl.game.spec import GameName

AGENTS_ENCODING_HELP = (
    "Check that every agent reads this encoding (rlcard or strength; the built-ins read what "
    "they need): one line names an agent that does not. Agents of different encodings can "
    "meet without it: the engine builds each one's own observations."
)


@app.command()
def match(
    ctx: typer.Context,
    agent_a: str = typer.Argument(
        ...,
        metavar="AGENT_A",
        help="Agent A (reported): a built-in (random, raise, call, fold, tightbot, "
        "loosebot), an agent folder, reward:RUN (a learned reward's argmax), policy:RUN (an "
        "IRL policy, greedy) or rlcard:CKPT (an RLCard checkpoint: it is unpickled, which "
        "runs any code it holds; trusted files only).",
    ),
    agent_b: str = typer.Argument(..., metavar="AGENT_B", help="Agent B: as agent A."),
    hands: int = typer.Option(100_000, min=1, help="Hands to play (even with --duplicate)."),
    seed: int = typer.Option(
        0, **SEED_OPTION, help="Seed of the deals and of the agents' random draws."
    ),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats."
    ),
    output_format: str = typer.Option(
        "text",
        "--format",
        metavar=choices(("text", "json")),
        help="text or json.",
    ),
    encoding: str | None = typer.Option(
        None,
        "--encoding",
        metavar=ENCODING_CHOICES,
        help=AGENTS_ENCODING_HELP,
    ),
    game: GameName = GAME_OPTION,
    rules: RuleSet | None = RULES_OPTION,
) -> None:
    """Play A against B and print A's result in milli-big-blinds per hand.

    Beside the raw result, the AIVAT-corrected one: chance corrections at the flop, turn and
    river give an unbiased estimate of the same payoff, usually with a smaller error.

    With --game leduc nothing is dealt: A's exact expected value against B over every deal,
    from both seats, in chips and milli-chips per hand (agents: docs/leduc.md).
    """
    from pokerirl.agents import resolve_agent
    from pokerirl.game import check_match_size
    from pokerirl.tournaments.aivat import play_corrected_match

    if output_format not in ("text", "json"):
        raise UsageError(f"unknown --format {output_format!r} (text or json)")
    leduc = leduc_rules(game, rules)
    if leduc is not None:
        from pokerirl.cli.leduc import exact_match

        holdem_only(ctx, "a Leduc match is exact: every deal, both seats", hands=hands,
                    seed=seed, duplicate=duplicate, encoding=encoding)  # fmt: skip
        exact_match(agent_a, agent_b, leduc, as_json=output_format == "json")
        return
    refuse_leduc_agents([agent_a, agent_b])
    settings_from_options(check_match_size, hands, duplicate=duplicate)
    players = resolve_agent(agent_a), resolve_agent(agent_b)
    if encoding is not None:
        _check_agents_encoding(dict(zip((agent_a, agent_b), players, strict=True)),
                               parse_encoding(encoding).name)  # fmt: skip
    found = play_corrected_match(
        *players,
        hands=hands,
        seed=seed,
        duplicate=duplicate,
        progress=True,
    )
    result = found.match
    if output_format == "json":
        summary = {
            "mbb_per_hand": result.mbb_per_hand,
            "std_error": result.std_error,
            "hands": result.hands,
            "hands_per_second": result.hands_per_second,
            "aivat_seconds": result.on_batch_seconds,
        }
        echo(json.dumps(summary))
    else:
        echo(
            f"{result.agent_a} vs {result.agent_b}: {result.mbb_per_hand:+.1f} "
            f"+- {result.std_error:.1f} mbb/h over {result.hands:,} hands "
            f"({result.hands_per_second:,.0f} hands/s of play, "
            f"{result.on_batch_seconds:.1f} s of AIVAT); AIVAT-corrected "
            f"{found.corrected_mbb_per_hand:+.1f} +- {found.corrected_std_error:.1f} mbb/h"
        )


@app.command()
@on_error(interrupted=INTERRUPTED)
def tournament(
    ctx: typer.Context,
    agents: list[str] = typer.Argument(
        None,
        help="A B (one matchup, A's payoff), or with --vs the agents to play against BASE. "
        "Each: a built-in (random, raise, call), an agent folder, an agent set (a folder "
        "of seed-<k> agent folders: seed k plays seed-k), or several agent folders joined "
        "by commas (agents trained with different seeds: every one meets every agent of the "
        "other side, and the test is across training seeds). An rlcard:CKPT agent is "
        "unpickled, which runs any code it holds (trusted files only).",
        show_default=False,
    ),
    vs: str | None = typer.Option(
        None, "--vs", metavar="BASE", help="Play every AGENT against BASE (several matchups)."
    ),
    cross: bool = typer.Option(
        False,
        "--cross",
        help="An agent set is all its seed-<k> agents: every one meets every agent of the "
        "other side on the same deals of every seed (instead of seed k against seed k).",
    ),
    hands: int = typer.Option(1_000_000, "--hands", "-n", min=2, help="Hands per seed."),
    seeds: str = typer.Option(
        "0-19", "--seeds", callback=seed_list, metavar="SEEDS", help="Seeds, e.g. 0-19 or 0-4,10."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Report folder (resumes what it holds)."),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats, paired."
    ),
    jobs: int = typer.Option(
        2, "--jobs", "-j", min=1, help="Local worker processes (results do not change)."
    ),
    ray: str | None = typer.Option(
        None,
        "--ray",
        metavar="ADDRESS",
        help="Play the seeds on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), "
        "or 'local' for a private single-machine Ray. Results do not change.",
    ),
    alpha: float = typer.Option(0.05, help="Family-wise error rate (Bonferroni, Holm)."),
    batch_size: int = typer.Option(65_536, min=2, help="Hands in lock-step (part of the config)."),
    overwrite: bool = typer.Option(
        False,
        "--overwrite",
        help="Recompute saved seeds from another configuration; replace the report of a "
        "tournament of other matchups in --out (else refused).",
    ),
    encoding: str | None = typer.Option(
        None,
        "--encoding",
        metavar=ENCODING_CHOICES,
        help=AGENTS_ENCODING_HELP,
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no report."),
    game: GameName = GAME_OPTION,
    rules: RuleSet | None = RULES_OPTION,
) -> None:
    """Multi-seed head-to-head evaluation: mbb/h, duplicate deals, Bonferroni and Holm.

    \b
    One matchup:      pokerirl tournament A B --hands N --seeds 0-19 --out DIR
    Several matchups: pokerirl tournament --vs dqn hairl-dqn airl-dqn --out DIR
                      (hairl-dqn vs dqn and airl-dqn vs dqn, corrected together)
    Training seeds:   pokerirl tournament --cross --vs agents/dqn agents/hairl
                        --out DIR (sets of `agent train --seeds 0-2`: 3 x 3 pairs)

    With one agent per side the p-value is about these two agents only (the seeds
    re-deal the cards); several agents per side, trained with different seeds, make
    it a test across training seeds: a claim about the training. The report's first
    lines say which.

    Writes DIR/report.md, report.json, per_seed.csv, per_seed.png (and timings.json:
    the wall-clock figures, kept apart so the rest is the same bytes for the same seeds);
    prints the report.

    Resumable: each seed is saved when it finishes. A rerun reuses saved seeds
    whose agents, hands, duplicate mode and batch size match, and refuses the
    others (--overwrite recomputes them); a corrupt saved seed is recomputed.
    A DIR that holds a tournament of other matchups is refused (--overwrite
    replaces its report; its saved seeds stay).
    pokerirl report DIR prints it again.

    With --game leduc: AGENTS (two or more) in a round-robin of exact expected values
    (every deal, both seats) and each one's exploitability; DIR/report.md and report.json.
    """
    leduc = leduc_rules(game, rules)
    if leduc is not None:
        from pokerirl.cli.leduc import exact_tournament

        holdem_only(ctx, "a Leduc tournament is an exact round-robin", vs=vs, cross=cross,
                    hands=hands, seeds=seeds, duplicate=duplicate, jobs=jobs, ray=ray,
                    alpha=alpha, batch_size=batch_size, encoding=encoding)  # fmt: skip
        exact_tournament(agents or [], leduc, out=out, overwrite=overwrite, quiet=quiet)
        return
    from pokerirl.game import check_match_size
    from pokerirl.seeds import parse_seeds
    from pokerirl.tournaments import render_report, run_tournament
    from pokerirl.tournaments.lineup import Side, parse_side

    agents = agents or []
    matchups: list[tuple[Side, Side]]
    if vs is not None:
        if not agents:
            raise UsageError("--vs BASE needs at least one agent to play against it")
        base = parse_side(vs, cross=cross)
        matchups = [(parse_side(agent, cross=cross), base) for agent in agents]
    elif len(agents) == 2:
        matchups = [(parse_side(agents[0], cross=cross), parse_side(agents[1], cross=cross))]
    else:
        raise UsageError(
            f"give two agents (A B) or --vs BASE and agents; got {len(agents)} agent(s)"
        )
    if not 0 < alpha < 1:
        raise UsageError(f"--alpha must be between 0 and 1, got {alpha}")
    if duplicate and hands < 4:
        raise UsageError(
            f"--hands must be at least 4 with duplicate deals (two pairs), got {hands}"
        )
    settings_from_options(check_match_size, hands, duplicate=duplicate, batch_size=batch_size)
    refuse_leduc_agents([spec for pair in matchups for side in pair
                          for spec in ([side] if isinstance(side, str) else side)])  # fmt: skip
    if encoding is not None:
        specs = [spec for pair in matchups for side in pair
                 for spec in ([side] if isinstance(side, str) else side)]  # fmt: skip
        _check_agents_encoding(_resolve_lineup(specs), parse_encoding(encoding).name)
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
        backend=command_backend(jobs, ray),
    )
    if not quiet:
        echo(render_report(report))
        echo(f"wrote {out}/report.md, report.json, per_seed.csv, per_seed.png, timings.json")


def _check_agents_encoding(agents: Mapping[str, object], expected: str) -> None:
    """Refuse, in one line naming it, an agent (spec -> agent) that reads another encoding
    than ``expected``; the built-ins read what they need and pass."""
    from pokerirl.game import BUILT_IN_AGENTS
    from pokerirl.game.match import agent_encoding

    for spec, agent in agents.items():
        found = agent_encoding(agent).name  # type: ignore[arg-type]
        if spec not in BUILT_IN_AGENTS and found != expected:
            raise InputError(f"{spec}: an agent on the {found} encoding, not {expected}")


def _resolve_lineup(specs: Sequence[str]) -> dict[str, object]:
    """Every agent a lineup names (an agent set's ``seed-<k>`` folders one by one)."""
    from pokerirl.agents import resolve_agent
    from pokerirl.game import BUILT_IN_AGENTS

    found: dict[str, object] = {}
    for spec in dict.fromkeys(specs):
        seeds = [] if spec in BUILT_IN_AGENTS else sorted(Path(spec).glob("seed-*"))
        for member in [str(folder) for folder in seeds] or [spec]:
            found[member] = resolve_agent(member)
    return found


def refuse_leduc_agents(specs: Sequence[str]) -> None:
    """Refuse, in one line naming it, a Leduc agent given to hold'em."""
    from pokerirl.agents.leduc_specs import leduc_spec_reason

    for spec in specs:
        reason = leduc_spec_reason(spec)
        if reason is not None:
            raise InputError(f"{spec}: {reason}, not a hold'em agent (give --game leduc)")
