"""``pokerirl leduc``: Leduc hold'em's exact tools (docs/leduc.md): ``solve`` (CFR+),
``exploit`` (exact best response, exploitability, expected value), ``agreement``, ``synth``
(expert demonstrations) and ``study`` (IRL and RL against the CFR expert); and the exact
paths that ``match``, ``tournament``, ``exploit``, ``synth`` and ``agent train`` take with
``--game leduc`` (their agents by the specs of :mod:`pokerirl.agents.leduc_specs`)."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from pokerirl.cli.app import app
from pokerirl.cli.errors import echo
from pokerirl.cli.options import choices
from pokerirl.errors import UsageError
from pokerirl.game.leduc.rules import LeducRules, RuleSet

if TYPE_CHECKING:
    from pokerirl.game.leduc.strategy import Strategy

leduc_app = typer.Typer(
    help="Leduc hold'em: CFR+, exact best response and exploitability (docs/leduc.md).",
    no_args_is_help=True,
)
app.add_typer(leduc_app, name="leduc")

RULES_CHOICES = choices(RuleSet)
MAX_ITERATIONS = 1_000_000  # a million CFR+ iterations: hours; the curve is flat long before
MAX_HANDS = 10_000_000  # demonstrations: about 25M decisions, 2 GB of observations


@leduc_app.command()
def solve(
    rules: RuleSet = typer.Option(
        RuleSet.RLCARD, "--rules", metavar=RULES_CHOICES,
        help="The rule set: RLCard's leduc-holdem or OpenSpiel's leduc_poker.",
    ),
    iterations: int = typer.Option(
        1000, "--iterations", "-n", min=1, max=MAX_ITERATIONS, help="CFR+ iterations."
    ),
    every: int = typer.Option(
        10, "--every", min=1, max=MAX_ITERATIONS,
        help="Measure the exploitability every this many iterations (and after the last).",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Folder to write (new or empty)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace what OUT holds."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Solve Leduc hold'em with CFR+ (deterministic: the same bytes on a rerun).

    Writes OUT/strategy.json (the average strategy), curve.csv and curve.png (its exact
    exploitability, milli-chips per hand, every --every iterations) and summary.json.
    """
    from tqdm import tqdm

    from pokerirl.game.leduc.rules import get_rules
    from pokerirl.game.leduc.solve import check_out
    from pokerirl.game.leduc.solve import solve as run

    check_out(out, overwrite=overwrite)  # before the progress bar
    with tqdm(total=iterations, disable=quiet, unit="it", desc="CFR+") as bar:
        solved = run(
            get_rules(rules), iterations=iterations, out=out, every=every, overwrite=overwrite,
            progress=lambda point: bar.update(point.iteration - bar.n),
        )  # fmt: skip
    echo(solved.line())
    echo(f"wrote {out}/strategy.json, curve.csv, curve.png, summary.json")


@leduc_app.command()
def exploit(
    strategy: Path = typer.Argument(..., metavar="STRATEGY.json", help="A strategy file."),
    against: Path | None = typer.Option(
        None, "--against", metavar="STRATEGY2.json",
        help="Also the exact expected value of STRATEGY against this one.",
    ),
) -> None:
    """Exact best response to STRATEGY and its exploitability (chips and milli-chips per
    hand); with --against, the exact expected value of one against the other."""
    from pokerirl.game.leduc.exact import MILLI, best_response_values, expected_value

    rules, first = _read(strategy)
    values = best_response_values(rules, first)
    exploitability = sum(values) / 2
    echo(f"{strategy} ({rules.name} rules)")
    echo(f"  best response: {values[0]:+.6f} chips per hand in position 0, "
         f"{values[1]:+.6f} in position 1")  # fmt: skip
    echo(f"  exploitability: {exploitability:.9f} chips per hand "
         f"({exploitability * MILLI:.4f} milli-chips)")  # fmt: skip
    if against is not None:
        second = _read(against, rules=rules.name)[1]
        matchup = expected_value(rules, first, second)
        echo(f"  against {against}: {matchup.mean:+.9f} chips per hand ({matchup.first:+.9f} "
             f"in position 0, {matchup.second:+.9f} in position 1)")  # fmt: skip


@leduc_app.command()
def agreement(
    a: Path = typer.Argument(..., metavar="A.json", help="A strategy file."),
    b: Path = typer.Argument(..., metavar="B.json", help="The reference (a CFR expert)."),
) -> None:
    """The share of information sets where A's and B's most likely actions agree: each set
    counted once, and weighted by how often B reaches it playing itself."""
    from pokerirl.game.leduc.exact import agreement as agree

    rules, first = _read(a)
    found = agree(rules, first, _read(b, rules=rules.name)[1])
    echo(f"agreement of {a} with {b} ({rules.name} rules, {found.information_sets} "
         f"information sets): {found.uniform:.4f} uniform, {found.reached:.4f} "
         "weighted by B's reach")  # fmt: skip


def _read(path: Path, *, rules: str | None = None) -> tuple[LeducRules, Strategy]:
    from pokerirl.errors import InputError
    from pokerirl.game.leduc.strategy import read_strategy

    found = read_strategy(path)
    if rules is not None and found[0].name != rules:
        raise InputError(f"{path}: a strategy for the {found[0].name} rules, not {rules}")
    return found


@leduc_app.command()
def synth(
    expert: Path = typer.Option(
        ..., "--expert", metavar="DIR|STRATEGY.json",
        help="The expert: a solve folder (its strategy.json) or a strategy file.",
    ),
    hands: int = typer.Option(10_000, "--hands", "-n", min=1, max=MAX_HANDS, help="Hands."),
    seed: int = typer.Option(
        0, "--seed", min=0, max=2**32 - 1, help="Seed of the deals and the draws."
    ),
    opponent: Path | None = typer.Option(
        None, "--opponent", metavar="STRATEGY.json",
        help="Play the expert against this strategy (seats alternate) and record only the "
             "expert's decisions; default: the expert against itself, both seats recorded.",
    ),
    out: Path = typer.Option(..., "--out", "-o", metavar="FILE.npz", help="The file to write."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace FILE.npz."),
) -> None:
    """Demonstrations: HANDS hands of the expert on the batch engine, every decision as
    arrays (36-d observation, legal actions, action, next observation, done, chips won,
    hand, position, information set) in an .npz with a JSON header (no pickle). Seeded: the
    same arguments write the same bytes."""
    from pokerirl.errors import PokerIRLError, Remedy
    from pokerirl.game.leduc.demos import save, synthesize

    rules, strategy = _read(_strategy_path(expert))
    other = None if opponent is None else _read(opponent, rules=rules.name)[1]
    if out.exists() and not overwrite:
        raise PokerIRLError(f"{out} exists", remedy=Remedy.REPLACE)
    demos = synthesize(rules, strategy, hands=hands, seed=seed, opponent=other)
    save(demos, out)
    echo(f"wrote {out}: {len(demos):,} decisions of {hands:,} hands ({rules.name} rules, "
         f"expert sha256 {demos.expert_sha256[:12]})")  # fmt: skip


class StudyPreset(StrEnum):
    """The Leduc study's presets (pokerirl/studies/leduc/study.py)."""

    QUICK = "quick"
    WIDE = "wide"
    SMOKE = "smoke"


PRESET_CHOICES = choices(StudyPreset)


class LeducRL(StrEnum):
    """The Leduc RL agents: the study's ``--rl`` (pokerirl/studies/leduc/study.py's
    ``RLKind``) and ``agent train --game leduc --rl``."""

    DQN = "dqn"
    TABULAR = "tabular"


RL_CHOICES = choices(LeducRL)
RL_NAMES = {LeducRL.DQN: "DQN", LeducRL.TABULAR: "tabular Monte-Carlo learner"}


@leduc_app.command()
def study(
    out: Path = typer.Option(..., "--out", "-o", help="The study folder (resumed if present)."),
    preset: StudyPreset = typer.Option(
        StudyPreset.QUICK, "--preset", metavar=PRESET_CHOICES,
        help="quick: 10,000 expert hands, 2 IRL runs of 20 epochs per learner, 4 RL seeds; "
             "wide: the same with 5 IRL runs and 10 RL seeds; smoke: seconds, numbers "
             "meaningless.",
    ),
    rl: LeducRL = typer.Option(
        LeducRL.DQN, "--rl", metavar=RL_CHOICES,
        help="The RL agents: DQNs (100,000 hands each in the quick preset) or the tabular "
             "Monte-Carlo learner (500,000).",
    ),
    rules: RuleSet = typer.Option(
        RuleSet.RLCARD, "--rules", metavar=RULES_CHOICES, help="The rule set."
    ),
    expert: Path | None = typer.Option(
        None, "--expert", metavar="DIR|STRATEGY.json",
        help="Use this CFR expert (a solve folder or strategy file) instead of solving.",
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help="Recompute every stage."),
) -> None:
    """The Leduc study: CFR+ expert, demonstrations, AIRL, H-AIRL, GAIL and BC runs, RL
    agents (DQNs or tabular) against the expert on each learned reward and on the sparse
    reward; the exact agreement with the expert, exploitability and expected values in
    OUT/report.md and report.json (mean ± std over runs or seeds), and OUT/agreement.png.
    A rerun skips the stages whose files are present."""
    run_study(out, preset, rules=rules, rl=rl, expert=expert, overwrite=overwrite)


def run_study(
    out: Path, preset: str, *, rules: str, rl: str, expert: Path | None, overwrite: bool
) -> None:
    """``leduc study`` and ``study --game leduc``: the preset's study with these settings
    (checked by the command), into ``out``."""
    from pokerirl.studies.leduc.study import preset as get_preset
    from pokerirl.studies.leduc.study import run_leduc_study

    config = get_preset(preset, rules=rules, rl=rl)
    run_leduc_study(config, out, expert=None if expert is None else _strategy_path(expert),
                    overwrite=overwrite, echo=echo)  # fmt: skip


def _strategy_path(path: Path) -> Path:
    """A solve folder's strategy.json, or the file itself."""
    return path / "strategy.json" if path.is_dir() else path


# ------------------------------------------------- the main commands with --game leduc
# match, tournament, exploit, synth and agent train call these (pokerirl/cli/play.py,
# poker.py, exploit.py): agents by the specs of pokerirl/agents/leduc_specs.py, every
# figure exact.


def resolve(spec: str, rules: LeducRules) -> Strategy:
    """A Leduc agent spec's strategy (:func:`pokerirl.agents.leduc_specs.resolve_leduc_agent`)."""
    from pokerirl.agents.leduc_specs import resolve_leduc_agent

    return resolve_leduc_agent(spec, rules).strategy


def exact_match(a: str, b: str, rules: LeducRules, *, as_json: bool) -> None:
    """``match --game leduc``: A's exact expected value against B over every deal, both
    seats (no dealing)."""
    from pokerirl.game.leduc.exact import MILLI, expected_value

    found = expected_value(rules, resolve(a, rules), resolve(b, rules))
    if as_json:
        echo(json.dumps({
            "game": "leduc", "rules": rules.name, "chips_per_hand": found.mean,
            "milli_chips_per_hand": found.mean * MILLI, "position_0": found.first,
            "position_1": found.second,
        }))  # fmt: skip
        return
    echo(f"{a} vs {b} (Leduc, {rules.name} rules, exact over every deal and both seats): "
         f"{found.mean:+.6f} chips per hand ({found.mean * MILLI:+.3f} milli-chips); "
         f"{found.first:+.6f} in position 0, {found.second:+.6f} in position 1")  # fmt: skip


def exact_exploit(agent: str, rules: LeducRules, *, pair: str | None) -> None:
    """``exploit --game leduc``: the exact best response to AGENT (with ``pair``: to the
    profile of AGENT in position 0 and PAIR in position 1) and its exploitability."""
    from pokerirl.game.leduc.exact import MILLI, best_response_values
    from pokerirl.game.leduc.strategy import profile

    strategy = resolve(agent, rules)
    name = agent
    if pair is not None:
        strategy = profile(rules, strategy, resolve(pair, rules))
        name = f"{agent} in position 0, {pair} in position 1"
    values = best_response_values(rules, strategy)
    exploitability = sum(values) / 2
    echo(f"{name} (Leduc, {rules.name} rules, exact)")
    echo(f"  best response: {values[0]:+.6f} chips per hand in position 0, "
         f"{values[1]:+.6f} in position 1")  # fmt: skip
    echo(f"  exploitability: {exploitability:.9f} chips per hand "
         f"({exploitability * MILLI:.4f} milli-chips)")  # fmt: skip


TOURNAMENT_FILES = ("report.md", "report.json")


def exact_tournament(specs: list[str], rules: LeducRules, *, out: Path, overwrite: bool,
                     quiet: bool) -> None:  # fmt: skip
    """``tournament --game leduc``: every agent against every other, exactly; OUT/report.md
    (the table, milli-chips per hand for the row against the column, and each one's
    exploitability) and report.json."""
    from pokerirl.atomic import write_text
    from pokerirl.errors import PokerIRLError, Remedy
    from pokerirl.game.leduc.exact import MILLI, expected_value, exploitability
    from pokerirl.jsonio import read_json_object

    names = list(dict.fromkeys(specs))
    if len(names) < 2:
        raise UsageError(f"give at least two agents, got {len(names)}")
    if out.exists() and not out.is_dir():
        raise PokerIRLError(f"{out} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    if (out / "report.json").is_file() and not overwrite:
        held = read_json_object(out / "report.json")
        if held.get("game") != "leduc" or held.get("agents") != names \
                or held.get("rules") != rules.name:  # fmt: skip
            raise PokerIRLError(f"{out} holds the report of another tournament",
                                remedy=Remedy.REPLACE)  # fmt: skip
    strategies = {name: resolve(name, rules) for name in names}
    table = {a: {b: 0.0 for b in names} for a in names}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            value = expected_value(rules, strategies[a], strategies[b]).mean
            table[a][b], table[b][a] = value, 0.0 - value  # zero-sum, both seats (no -0.0)
    exploit = {name: exploitability(rules, strategies[name]) for name in names}
    mean = {a: sum(table[a].values()) / (len(names) - 1) for a in names}
    report = {
        "game": "leduc", "rules": rules.name, "agents": names, "units": "chips per hand",
        "expected_value": table, "exploitability": exploit, "mean": mean,
    }  # fmt: skip
    lines = [
        f"# Leduc round-robin ({rules.name} rules, exact)", "",
        "Milli-chips per hand won by the row against the column (every deal, both seats); "
        "mean: against the others; exploitability: what a best response wins.", "",
        "| agent | " + " | ".join(names) + " | mean | exploitability |",
        "|---" * (len(names) + 3) + "|",
    ]  # fmt: skip
    for a in names:
        cells = ["" if a == b else f"{table[a][b] * MILLI:+.1f}" for b in names]
        lines.append(f"| {a} | " + " | ".join(cells)
                     + f" | {mean[a] * MILLI:+.1f} | {exploit[a] * MILLI:.1f} |")  # fmt: skip
    text = "\n".join(lines) + "\n"
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "report.md", text)
    write_text(out / "report.json", json.dumps(report, indent=1) + "\n")
    if not quiet:
        echo(text, nl=False)
        echo(f"wrote {out}/report.md, report.json")


def exact_synth(rules: LeducRules, *, expert: str, opponent: str | None, hands: int, seed: int,
                out: Path) -> None:  # fmt: skip
    """``synth --game leduc``: what ``leduc synth`` writes, the expert and its opponent by
    agent spec."""
    from pokerirl.errors import PokerIRLError, Remedy
    from pokerirl.game.leduc.demos import save, synthesize

    if not 1 <= hands <= MAX_HANDS:
        raise UsageError(f"--hands must be at most {MAX_HANDS:,} with --game leduc, got {hands:,}")
    strategy = resolve(expert, rules)
    other = None if opponent is None else resolve(opponent, rules)
    if out.exists():
        raise PokerIRLError(f"{out} exists", remedy=Remedy.ELSEWHERE)
    demos = synthesize(rules, strategy, hands=hands, seed=seed, opponent=other)
    save(demos, out)
    echo(f"wrote {out}: {len(demos):,} decisions of {hands:,} hands ({rules.name} rules, "
         f"expert {expert}, sha256 {demos.expert_sha256[:12]})")  # fmt: skip


def exact_agent_train(rules: LeducRules, *, out: Path, rl: LeducRL, opponent: str, hands: int,
                      seed: int, reward_run: str | None, overwrite: bool) -> None:  # fmt: skip
    """``agent train --game leduc``: the Leduc DQN or the tabular learner (``rl``) against
    ``opponent`` on the sparse reward or a Leduc run's learned g (as the Leduc study trains
    them); OUT/strategy.json (its greedy strategy, an agent the specs resolve) and
    OUT/summary.json with its exact exploitability and value against the opponent."""
    import numpy as np

    from pokerirl.agents.leduc_dqn import LeducDQNConfig, train_leduc_dqn
    from pokerirl.agents.leduc_q import QConfig, train_q
    from pokerirl.agents.leduc_specs import STRATEGY_FILE, reward_table
    from pokerirl.atomic import write_text
    from pokerirl.game.leduc.exact import MILLI, expected_value, exploitability
    from pokerirl.game.leduc.infosets import info_sets
    from pokerirl.game.leduc.solve import check_out
    from pokerirl.game.leduc.strategy import sha256, to_json

    check_out(out, overwrite=overwrite)
    against = resolve(opponent, rules)
    reward = None
    if reward_run is not None:
        from pokerirl.agents.leduc_specs import run_strategy
        from pokerirl.irl.run import load_reward
        from pokerirl.poker.agent_specs import REWARD_PREFIX

        run_strategy(Path(reward_run), rules, prefix=REWARD_PREFIX)  # a Leduc run, its rules
        sets = info_sets(rules)
        table = reward_table(load_reward(reward_run).net, sets)
        reward = np.where(sets.legal, table, 0.0)  # as the study: 0 where illegal
    if rl == LeducRL.DQN:
        config = LeducDQNConfig(hands=hands, batch=min(hands, LeducDQNConfig.batch), seed=seed)
        strategy = train_leduc_dqn(rules, against, config=config, reward=reward).strategy()
    else:
        tabular = QConfig(hands=hands, batch=min(hands, QConfig.batch), seed=seed)
        strategy = train_q(rules, against, config=tabular, reward=reward).strategy()
    agent = f"leduc-{rl}"
    source = "sparse" if reward_run is None else f"learned ({reward_run})"
    text = to_json(rules, strategy, agent=agent, hands=hands, seed=seed,
                   opponent=opponent, reward=source)  # fmt: skip
    value = expected_value(rules, strategy, against).mean
    exploit = exploitability(rules, strategy)
    summary = {
        "rules": rules.name, "agent": agent, "hands": hands, "seed": seed,
        "opponent": opponent, "reward": source, "exploitability_chips": exploit,
        "value_against_opponent_chips": value, "strategy_sha256": sha256(text),
    }  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / STRATEGY_FILE, text)
    write_text(out / "summary.json", json.dumps(summary, indent=1) + "\n")
    echo(f"{out}: Leduc {RL_NAMES[rl]}, {hands:,} hands against {opponent} on the {source} reward; "
         f"exact: exploitability {exploit * MILLI:.1f} milli-chips, "
         f"{value * MILLI:+.1f} milli-chips per hand against {opponent}")  # fmt: skip
    echo(f"wrote {out}/{STRATEGY_FILE}, summary.json")
