"""The study commands: demo, study (poker: hold'em, or with ``--game leduc`` the Leduc study),
transfer and report (any study or tournament folder)."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import typer

from pokerirl.cli.app import app
from pokerirl.cli.data import MONTHS_HELP, months
from pokerirl.cli.errors import INTERRUPTED, echo, on_error, settings_from_options
from pokerirl.cli.fanout import RAY_HELP, command_backend
from pokerirl.cli.leduc import LeducRL
from pokerirl.cli.leduc import StudyPreset as LeducPreset
from pokerirl.cli.leduc import run_study as run_leduc_study
from pokerirl.cli.options import (
    ENCODING_CHOICES,
    LOG_DIR,
    POKER_GENERATOR_STEPS,
    POKER_ROUNDS,
    Default,
    choices,
    online_mode,
    write_logs,
)
from pokerirl.cli.seeds import MAX_SEEDS, SEED_OPTION, seed_list
from pokerirl.errors import MissingExtra, UsageError
from pokerirl.game.leduc.rules import RuleSet
from pokerirl.game.spec import GameName
from pokerirl.irl.config import IRLMode  # torch-free
from pokerirl.jsonio import read_json
from pokerirl.studies.poker.config import (
    AGENT_PRESETS,
    FOLDS,
    IRL_ALGOS,
    STAGE_BOUNDS,
    TRANSFORMS,
)
from pokerirl.studies.poker.config import PRESETS as STUDY_PRESETS

DEMO_CONFIG = "pokerirl.studies.demo:DemoConfig"
TRANSFER_CONFIG = "pokerirl.studies.poker.transfer:TransferConfig"


@app.command()
@on_error(interrupted=INTERRUPTED)
def demo(
    out: Path = typer.Option(Path("demo-output"), "--out", "-o", help="Where the demo writes."),
    seed: int = typer.Option(
        Default(DEMO_CONFIG, "seed"), "--seed", **SEED_OPTION, help="Seed of the synthetic data."
    ),
    jobs: int = typer.Option(
        Default(DEMO_CONFIG, "jobs"), "--jobs", min=1, help="Processes for agent training and play."
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help="Recompute changed units."),
    gym: bool = typer.Option(
        True, "--gym/--no-gym", help="Also run the Gymnasium study's demo preset on MountainCar."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """Run the poker study (pokerirl study --preset demo) on built-in synthetic data and print
    its report, then the Gymnasium study (pokerirl gym study MountainCar-v0 --preset demo) on
    the shipped expert. Sized for about 5 minutes on 2 idle cores, the poker report first
    (docs/cli.md has the timings).

    synth -> ingest -> IRL (airl, hairl) -> agents (dqn, airl_dqn, hairl_dqn) -> Table 1
    tournament -> panel -> report.md, report.json and figures; then OUT/gym: expert data ->
    AIRL and H-AIRL -> DQN on each reward and on the env reward -> OUT/gym/report.md. A rerun
    skips finished work.
    """
    from pokerirl.studies.demo import DemoConfig, closing_lines, run_demo, run_gym_demo

    config = settings_from_options(DemoConfig, seed=seed, jobs=jobs)
    result = run_demo(out, config, say=echo, progress=not quiet, overwrite=overwrite)
    echo("")
    echo(result.markdown)
    echo(f"report: {out / 'report.md'} (pokerirl report {out})")
    if gym:
        from pokerirl.gym.envs import require_gym

        try:
            require_gym()
        except MissingExtra as error:  # not an error here: the poker demo is done
            warnings.warn(f"the Gymnasium demo is skipped: {error}", stacklevel=1)
            gym = False
    if gym:
        echo("")
        tasks = ", ".join(config.gym.tasks)
        echo(f"gym: the {config.gym.name} study on {tasks} -> {out / 'gym'}")
        gym_result = run_gym_demo(out, config, say=echo, progress=not quiet, overwrite=overwrite)
        echo("")
        echo(gym_result.markdown)
        echo(f"report: {out / 'gym' / 'report.md'}")
    echo("")
    for line in closing_lines(result, out, gym=gym):
        echo(line)


def _sources(sources: list[Path] | None) -> list[Path]:
    """The SOURCE arguments (none: the Leduc study's case, checked by the command)."""
    return months(sources) if sources else []


@app.command()
@on_error(interrupted=INTERRUPTED)
def study(
    sources: list[Path] | None = typer.Argument(
        None, callback=_sources, help=MONTHS_HELP + " Hold'em only."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The study folder."),
    game: str = typer.Option(
        GameName.HOLDEM, "--game", metavar=choices(GameName),
        help="holdem: the paper's study on IRC months; leduc: the Leduc study (as pokerirl "
        "leduc study: CFR+ expert, IRL, RL against it; --rules, --rl).",
    ),
    preset_name: str = typer.Option(
        "quick",
        "--preset",
        metavar=choices(STUDY_PRESETS),
        help="smoke (seconds; checks the pipeline, its numbers mean nothing), demo (what "
        "pokerirl demo runs), quick, paper "
        "(ours), authors (their IRL and DQN settings and their tournament protocol, beside "
        "our duplicate-deal Table 1) or real (what pokerirl sweep chose on real hands; "
        "docs/sweep.md). Leduc: quick, wide or smoke.",
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, max=MAX_SEEDS, help="IRL runs per algorithm."
    ),
    seeds: str | None = typer.Option(
        None, "--seeds", callback=seed_list, metavar="SEEDS", help="Agent seeds, e.g. 0-19."
    ),
    hands: int | None = typer.Option(
        None, "--hands", min=2, max=STAGE_BOUNDS["hands"], help="Tournament hands per seed."
    ),
    lbr_hands: int | None = typer.Option(
        None, "--lbr-hands", min=0, max=STAGE_BOUNDS["lbr_hands"],
        help="LBR's hands per seed against each panel agent (even; 0: no LBR); default: the "
        "preset's (quick 500, paper 10,000).",
    ),
    algos: str | None = typer.Option(
        None,
        "--algos",
        metavar="ALGO[,ALGO...]",
        help=f"The IRL algorithms trained, each with its DQN agents, among "
        f"{', '.join(IRL_ALGOS)}; default: the paper's airl,hairl (gail: GAIL beside them).",
    ),
    reward_run: list[str] = typer.Option(
        [],
        "--reward-run",
        metavar="[ALGO=]SPEC",
        help="Replace an algorithm's IRL runs by a reward, e.g. authors:FILE (hairl, the "
        "default) or airl=authors:FILE2; repeatable.",
    ),
    reward_transform: str | None = typer.Option(
        None,
        "--reward-transform",
        metavar=choices(TRANSFORMS),
        help="raw, centered, log_softmax or advantage: the learned-reward DQNs' (docs/rewards.md).",
    ),
    encoding: str | None = typer.Option(
        None,
        "--encoding",
        metavar=ENCODING_CHOICES,
        help="What rewards, policies and DQNs read: rlcard (the paper's 72-d, the default) or "
        "strength (hole and board apart, with hand features).",
    ),
    folds: str | None = typer.Option(
        None,
        "--folds",
        metavar=choices(FOLDS),
        help="drop (default: the hands that end in a fold hide the cards and are left out) "
        "or impute (kept, the hidden cards drawn from a posterior; docs/folds.md).",
    ),
    opponent: str | None = typer.Option(
        None, "--opponent", metavar="random|self|pool",
        help="Every DQN's training opponent (default random; pool: fixed strategies and the "
        "learner's own snapshots).",
    ),
    payoff_weight: float | None = typer.Option(
        None, "--payoff-weight", help="w in w * payoff + (1 - w) * f for the learned-reward DQNs."
    ),
    reward_decay: float | None = typer.Option(
        None, "--reward-decay", help="The reward net's weight decay (default: the IRL core's)."
    ),
    experts: str | None = typer.Option(
        None, "--experts", metavar="all|winners",
        help="Whose decisions are the expert's: all players (default) or the period's winners.",
    ),
    period: str | None = typer.Option(
        None, "--period", metavar="START:END",
        help="The part of each month read, as fractions of its hands by time (0:0.6, 0.6:1).",
    ),
    jobs: int | None = typer.Option(
        None, "--jobs", min=1, max=STAGE_BOUNDS["jobs"],
        help="Processes for training and play (default 2).",
    ),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    mode: str | None = typer.Option(
        None, "--mode", metavar=choices(IRLMode),
        help="The IRL runs: offline (the default; the paper's: the policy acts at the expert's "
        "states) or online (as train --mode online: the policy plays hands on the engine).",
    ),
    rounds: int | None = POKER_ROUNDS,
    generator_steps: int | None = POKER_GENERATOR_STEPS,
    generator_opponent: str | None = typer.Option(
        None, "--generator-opponent", metavar="random|call|raise|tight|loose",
        help="Online: the fixed opponent the IRL policy plays (default random; --opponent is "
        "the DQNs').",
    ),
    rules: str | None = typer.Option(
        None, "--rules", metavar=choices(RuleSet), help="Leduc: the rule set (default rlcard)."
    ),
    rl: str | None = typer.Option(
        None, "--rl", metavar=choices(LeducRL),
        help="Leduc: the RL agents, dqn (the default) or tabular.",
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Recompute changed units, and the units that read them."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
    log_dir: Path | None = LOG_DIR,
) -> None:
    """The paper's poker study in one command: ingest, IRL (AIRL and H-AIRL, several runs),
    DQN agents (sparse, AIRL and H-AIRL rewards), Table 1, the panel, and a report beside the
    paper's numbers (report.md, report.json, panel.csv, figures/), with the reward cards.
    --preset authors adds the authors' tournament protocol. Resumable: finished units are kept.

    --mode online trains the IRL runs online (everything after them as offline; the report
    says so; a folder made in the other mode is refused unless --overwrite). --game leduc
    runs the Leduc study (pokerirl leduc study) instead."""
    from pokerirl.seeds import seeds_as_written
    from pokerirl.studies.poker import preset, run_study

    if game not in tuple(GameName):
        raise UsageError(f"--game must be one of {', '.join(GameName)}, got {game!r}")
    holdem_only = {
        "SOURCE": bool(sources), "--runs": runs, "--seeds": seeds, "--hands": hands,
        "--lbr-hands": lbr_hands, "--algos": algos, "--reward-run": reward_run or None,
        "--reward-transform": reward_transform, "--encoding": encoding, "--folds": folds,
        "--opponent": opponent, "--payoff-weight": payoff_weight,
        "--reward-decay": reward_decay, "--experts": experts, "--period": period,
        "--jobs": jobs, "--ray": ray, "--mode": mode, "--rounds": rounds,
        "--generator-steps": generator_steps, "--generator-opponent": generator_opponent,
    }  # fmt: skip
    if game == GameName.LEDUC:
        refused = [name for name, value in holdem_only.items() if value not in (None, False)]
        if refused:
            raise UsageError(f"{refused[0]} applies to --game holdem only")
        _leduc_study(out, preset_name, rules=rules, rl=rl, overwrite=overwrite)
        write_logs(out, log_dir)
        return
    leduc_only = {"--rules": rules, "--rl": rl}
    refused = [name for name, value in leduc_only.items() if value is not None]
    if refused:
        raise UsageError(f"{refused[0]} applies to --game leduc only")
    if not sources:
        raise UsageError("give at least one SOURCE (an IRC month folder or archive, or a "
                         "dataset name), or --game leduc")  # fmt: skip
    online = _study_mode(mode, rounds, generator_steps, generator_opponent)

    sources_given = []
    for item in reward_run:
        algo, _, spec = item.partition("=") if "=" in item.split(":", 1)[0] else ("", "", item)
        sources_given.append((algo or "hairl", spec))
    config = settings_from_options(
        preset,
        preset_name,
        runs=runs,
        # As written: the first seeds the agents, and a repeat is refused, not dropped.
        seeds=None if seeds is None else seeds_as_written(seeds),
        hands=hands,
        lbr_hands=lbr_hands,
        jobs=jobs,
        reward_sources=tuple(sources_given) or None,
        algos=None if algos is None else tuple(a.strip() for a in algos.split(",")),
        reward_transform=reward_transform,
        encoding=encoding,
        folds=folds,
        opponent=opponent,
        payoff_weight=payoff_weight,
        reward_decay=reward_decay,
        experts=experts,
        period=None if period is None else _period(period),
        **online,
    )
    result = run_study(
        sources,
        out,
        config,
        overwrite=overwrite,
        progress=not quiet,
        say=echo,
        backend=command_backend(config.jobs, ray),
    )
    echo("")
    echo(result.markdown)
    echo(f"report: {out / 'report.md'} (pokerirl report {out})")
    write_logs(out, log_dir)


def _study_mode(
    mode: str | None, rounds: int | None, steps: int | None, opponent: str | None
) -> dict[str, object]:
    """``study --mode`` and its online options as the study config's overrides (a usage
    error for an online option offline, or an unknown mode)."""
    if not online_mode(mode, {"--rounds": rounds, "--generator-steps": steps,
                              "--generator-opponent": opponent}):  # fmt: skip
        return {}
    return {"irl_mode": mode, "online_rounds": rounds, "online_generator_steps": steps,
            "online_opponent": opponent}  # fmt: skip


def _leduc_study(
    out: Path, preset_name: str, *, rules: str | None, rl: str | None, overwrite: bool
) -> None:
    """``study --game leduc``: the Leduc study, as ``pokerirl leduc study`` runs it."""
    for option, value, allowed in (("--preset", preset_name, LeducPreset),
                                   ("--rules", rules, RuleSet), ("--rl", rl, LeducRL)):  # fmt: skip
        if value is not None and value not in tuple(allowed):
            raise UsageError(f"--game leduc: {option} must be one of {', '.join(allowed)}, "
                             f"got {value!r}")  # fmt: skip
    run_leduc_study(out, preset_name, rules=rules or RuleSet.RLCARD, rl=rl or LeducRL.DQN,
                    expert=None, overwrite=overwrite)  # fmt: skip


def _period(text: str) -> tuple[float, float]:
    """``--period START:END`` as a pair, checked (a usage error in one line)."""
    from pokerirl.datasets.players import Period

    found = settings_from_options(Period.parse, text)
    return (found.start, found.end)


@app.command()
@on_error(interrupted=INTERRUPTED)
def transfer(
    reward_run: str = typer.Argument(
        ...,
        metavar="REWARD",
        help="An IRL run folder, or authors:FILE.",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Folder for the agents and the table."),
    transforms: str = typer.Option(
        Default(TRANSFER_CONFIG, "transforms"), "--transforms",
        metavar="T[,T...]", help="Reward transforms to train on.",
    ),
    payoff_weights: str = typer.Option(
        Default(TRANSFER_CONFIG, "payoff_weights"),
        "--payoff-weights",
        metavar="W[,W...]",
        help="e.g. 0,0.5.",
    ),
    seeds: str = typer.Option(
        Default(TRANSFER_CONFIG, "seeds"),
        "--seeds",
        callback=seed_list,
        metavar="SEEDS",
        help="DQN seeds.",
    ),
    hands: int = typer.Option(
        Default(TRANSFER_CONFIG, "hands"), "--hands", "-n", min=1, help="DQN training hands."
    ),
    agent_preset: str = typer.Option(
        Default(TRANSFER_CONFIG, "agent_preset"),
        "--preset",
        metavar=choices(AGENT_PRESETS),
        help="DQN preset: default, authors.",
    ),
    eval_hands: int = typer.Option(
        Default(TRANSFER_CONFIG, "eval_hands"), "--eval-hands", min=2,
        help="Duplicate hands vs random.",
    ),
    experts: str = typer.Option(
        Default(TRANSFER_CONFIG, "experts"),
        "--experts",
        metavar="RULE[,RULE...]",
        help="Rules to compare the agents' actions with (tightbot, loosebot, legal_majority), "
        "or none.",
    ),
    encoding: str | None = typer.Option(
        None,
        "--encoding",
        metavar=ENCODING_CHOICES,
        help="What the DQNs read: rlcard or strength; default: the reward run's encoding.",
    ),
    jobs: int = typer.Option(2, "--jobs", min=1, help="Processes training seeds at once."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    game: str = typer.Option(
        GameName.HOLDEM, "--game", metavar=GameName.HOLDEM,
        help="holdem, the only game transfer plays (the Leduc study trains its own agents).",
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """Does a learned reward teach the expert's play? DQNs on each reward transform (and
    payoff weight), and f's argmax and the IRL policy (no RL), each judged against random,
    head to head against each expert bot, against the expert rules on the states it visits
    and by its action shares, beside the expert bots, always-call and a sparse DQN.
    Writes OUT/transfer.json and transfer.md; a rerun reuses the trained agents."""
    from pokerirl.seeds import seeds_as_written
    from pokerirl.studies.poker.transfer import TransferConfig, parse_list, run_transfer

    if game != GameName.HOLDEM:
        raise UsageError(
            f"--game {game}: transfer plays hold'em only (the Leduc study trains its own RL "
            "agents on its rewards: pokerirl study --game leduc)"
        )

    config = settings_from_options(
        TransferConfig,
        transforms=settings_from_options(parse_list, transforms),
        payoff_weights=settings_from_options(parse_list, payoff_weights, float),
        seeds=seeds_as_written(seeds),  # as written: a repeat is refused, as study does
        hands=hands,
        agent_preset=agent_preset,
        eval_hands=eval_hands,
        experts=settings_from_options(parse_list, experts),
        encoding=encoding,
    )
    result = run_transfer(
        reward_run, out, config, backend=command_backend(jobs, ray), progress=not quiet, say=echo
    )
    echo(result.markdown())
    echo(f"wrote {out / 'transfer.json'} and transfer.md")


@app.command()
def report(
    folder: Path = typer.Argument(
        ..., help="A folder written by pokerirl study, gym study or tournament."
    ),
    output_format: str = typer.Option(
        "markdown",
        "--format",
        metavar=choices(("markdown", "json")),
        help="markdown or json.",
    ),
) -> None:
    """Print a study or tournament report (Markdown, or JSON for scripts)."""
    from pokerirl.studies.gym.report import is_gym_study, load_gym_study
    from pokerirl.studies.poker import is_study_report, load_study_report, render_markdown
    from pokerirl.tournaments import load_report, render_report

    if output_format not in ("markdown", "text", "json"):
        raise UsageError(f"unknown --format {output_format!r}; choose markdown or json")
    from pokerirl.studies.common import REPORT_JSON, SUMMARY_JSON

    for name in (SUMMARY_JSON, REPORT_JSON):
        _refuse_corrupt(folder / name)
    if is_gym_study(folder):
        summary, markdown = load_gym_study(folder)
        found = summary.to_json()
    elif is_study_report(folder):
        loaded = load_study_report(folder)
        found, markdown = loaded.to_json(), render_markdown(loaded)
    else:
        echo(render_report(load_report(folder), output_format), nl=False)
        return
    if output_format == "json":
        echo(json.dumps(found, indent=2))
    else:
        echo(markdown, nl=False)


def _refuse_corrupt(path: Path) -> None:
    """Fail on a report's file (gym study's summary.json, a study's or tournament's
    report.json) that is there but cannot be read as JSON: truncated or damaged."""
    if path.exists() or path.is_symlink():
        read_json(path, what="corrupt: ")
