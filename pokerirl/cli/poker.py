"""The poker commands: ingest, synth, train, reward-card, agent train (match and tournament:
:mod:`pokerirl.cli.play`).

synth and agent train also take ``--game leduc`` (the exact Leduc paths of
:mod:`pokerirl.cli.leduc`); heads-up limit hold'em stays the default, its outputs unchanged."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from pokerirl import execution
from pokerirl.agents.config import AGENT_PRESETS, DQNConfig, Plays, TrainConfig  # torch-free
from pokerirl.cli.app import app
from pokerirl.cli.data import MONTHS_HELP, months
from pokerirl.cli.errors import INTERRUPTED, RUN_ADVICE, echo, on_error, settings_from_options
from pokerirl.cli.fanout import RAY_HELP, command_backend
from pokerirl.cli.leduc import LeducRL
from pokerirl.cli.options import (
    ENCODING_CHOICES,
    GAME_OPTION,
    LOG_DIR,
    NO_SETTINGS,
    POKER_GENERATOR_STEPS,
    POKER_ROUNDS,
    RULES_OPTION,
    Default,
    Settings,
    choices,
    given,
    holdem_only,
    leduc_rules,
    online_mode,
    parse_encoding,
    settings_options,
    widths,
    write_logs,
)
from pokerirl.cli.seeds import MAX_SEEDS, SEED_OPTION, seed_list
from pokerirl.errors import InputError, UsageError
from pokerirl.game.leduc.rules import RuleSet
from pokerirl.game.spec import GameName
from pokerirl.irl.config import AIRLConfig, Algo, IRLMode  # torch-free
from pokerirl.jsonio import read_json
from pokerirl.poker.folds import FoldsMode
from pokerirl.poker.rewards import Transform

if TYPE_CHECKING:
    from pokerirl.agents.train import MetricsLine
    from pokerirl.game.encodings import Encoding
    from pokerirl.irl.records import EpochMetrics
    from pokerirl.irl.run import RunSummary

ENCODING_HELP = (
    "What the reward and policy read: rlcard (RLCard's 72-d observation, the paper's) or "
    "strength (hole and board apart, with hand features: docs/encodings.md)."
)


IMPUTE_CONFIG = "pokerirl.poker.folds:ImputeConfig"
GAME_CHOICES = choices(GameName)
LEDUC_RL_CHOICES = choices(LeducRL)
GAME_WORDS = {GameName.HOLDEM: "a hold'em decision table", GameName.LEDUC: "Leduc demonstrations"}


@app.command()
def ingest(
    ctx: typer.Context,
    sources: list[Path] = typer.Argument(..., callback=months, help=MONTHS_HELP),
    out: Path = typer.Option(..., "--out", "-o", help="The Parquet table to write."),
    strict: bool = typer.Option(False, "--strict", help="Stop at the first malformed line."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no summary."),
    folds: str = typer.Option(
        "drop",
        "--folds",
        metavar=choices(FoldsMode),
        help="drop: leave out the hands that end in a fold with the cards hidden (the table "
        "of before, byte for byte); impute: keep them, each hidden player's cards drawn from "
        "a posterior over the 1,326 pairs under a behaviour model (docs/folds.md).",
    ),
    imputations: int = typer.Option(
        Default(IMPUTE_CONFIG, "imputations"), "--imputations", min=1,
        help="With --folds impute: posterior draws K per hidden player (equal draws merge "
        "into one row set of weight count/K).",
    ),
    behaviour: Path | None = typer.Option(
        None, "--behaviour", metavar="RUN",
        help="With --folds impute: a pokerirl train run whose policy is the behaviour model "
        "(in its own encoding); default: behaviour cloning on this table's shown hands, "
        "then EM rounds.",
    ),
    behaviour_encoding: str = typer.Option(
        Default(IMPUTE_CONFIG, "behaviour_encoding"), "--behaviour-encoding",
        metavar=ENCODING_CHOICES,
        help="With --folds impute and no --behaviour: what the fitted behaviour model reads "
        "(rlcard or strength).",
    ),
    behaviour_rounds: int = typer.Option(
        Default(IMPUTE_CONFIG, "behaviour_rounds"), "--behaviour-rounds", min=0,
        help="With --folds impute and no --behaviour: EM rounds after the first fit.",
    ),
    seed: int = typer.Option(
        Default(IMPUTE_CONFIG, "seed"), "--seed", **SEED_OPTION,
        help="With --folds impute: seeds the behaviour model's fit and the draws.",
    ),
    period: str | None = typer.Option(
        None, "--period", metavar="START:END",
        help="Keep the hands from fraction START to END of each month's hands in time order "
        "(0:0.6 the earlier 60%, 0.6:1 the rest: disjoint, together the month). The players' "
        "statistics for --min-hands and --min-bb-per-100 come from this period alone.",
    ),
    players: list[str] | None = typer.Option(
        None, "--player", metavar="NAME",
        help="Keep this player's decisions (repeat for several); with the filters below, "
        "only those of the named players that pass them.",
    ),
    min_hands: int | None = typer.Option(
        None, "--min-hands", min=1, metavar="N",
        help="Keep the decisions of the players who played at least N heads-up hands in the "
        "period (every hand their pdb lines record, folds included).",
    ),
    min_bb_per_100: float | None = typer.Option(
        None, "--min-bb-per-100", metavar="X",
        help="With --min-hands: keep those of them who won at least X big blinds per 100 "
        "hands (chips won minus chips put in, over their heads-up hands in the period).",
    ),
) -> None:
    """Turn IRC Poker Database hand histories into a Parquet state-action table.

    Writes TABLE and TABLE.summary.json (where every hand went) and prints the summary.
    With --folds impute the table gains the columns imputed, weight, imputation and
    posterior_entropy, and the summary a folds section. --period, --player, --min-hands
    and --min-bb-per-100 select the expert's decisions; the summary's selection section
    says what each kept.
    """
    from pokerirl.datasets.players import Period, Selection
    from pokerirl.poker.folds import FoldsMode, ImputeConfig

    if folds not in tuple(FoldsMode):
        raise UsageError(f"unknown --folds {folds!r} ({', '.join(FoldsMode)})")
    if min_bb_per_100 is not None and min_hands is None:
        raise UsageError("--min-bb-per-100 needs --min-hands (the hands the winnings are over)")
    selection = None
    if period is not None or players or min_hands is not None:
        selection = settings_from_options(
            Selection, period=Period() if period is None else settings_from_options(
                Period.parse, period),
            players=tuple(players or ()), min_hands=min_hands, min_bb_per_100=min_bb_per_100,
        )  # fmt: skip
    imputing = given(ctx, imputations=imputations, behaviour=behaviour,
                     behaviour_encoding=behaviour_encoding, behaviour_rounds=behaviour_rounds,
                     seed=seed)  # fmt: skip
    if folds == FoldsMode.DROP:
        if imputing:
            flags = ", ".join("--" + name.replace("_", "-") for name in imputing)
            raise UsageError(f"{flags} apply only with --folds impute")
        from pokerirl.datasets.ingest import ingest_table

        summary = ingest_table(sources, out, strict=strict, progress=not quiet,
                               selection=selection)  # fmt: skip
    else:
        fitted_only = [n for n in ("behaviour_encoding", "behaviour_rounds") if n in imputing]
        if behaviour is not None and fitted_only:  # ignored without a word before
            flags = ", ".join("--" + name.replace("_", "-") for name in fitted_only)
            raise UsageError(f"{flags} apply only without --behaviour (to the fitted model)")
        config = settings_from_options(
            ImputeConfig, imputations=imputations,
            behaviour=None if behaviour is None else str(behaviour),
            behaviour_encoding=behaviour_encoding, behaviour_rounds=behaviour_rounds, seed=seed,
        )  # fmt: skip
        from pokerirl.poker.impute import ingest_imputed

        summary = ingest_imputed(sources, out, config, strict=strict, progress=not quiet,
                                 selection=selection)  # fmt: skip
    if not quiet:
        echo(json.dumps(summary.to_json(), indent=2))


@app.command()
def synth(
    ctx: typer.Context,
    out: Path = typer.Option(
        ..., "--out", "-o",
        help="Folder to write <out>/holdem/<YYYYMM>/ in; with --game leduc the .npz to write.",
    ),
    hands: int = typer.Option(10_000, "--hands", "-n", min=1, help="Number of hands."),
    seed: int = typer.Option(
        0, "--seed", **SEED_OPTION, help="Random seed: the same seed, the same files."
    ),
    reveal_all: bool = typer.Option(
        False,
        "--reveal-all",
        help="Show every player's hole cards, folds included (the truth to score rewards "
        "on); the deals and actions are the same as without it.",
    ),
    game: GameName = GAME_OPTION,
    rules: RuleSet | None = RULES_OPTION,
    expert: str = typer.Option(
        "cfr", "--expert", metavar="AGENT",
        help="With --game leduc: the expert, a Leduc agent (default cfr: CFR+ solved here).",
    ),
    opponent: str | None = typer.Option(
        None, "--opponent", metavar="AGENT",
        help="With --game leduc: play the expert against this Leduc agent (seats alternate) and "
        "record only the expert's decisions; default: the expert against itself.",
    ),
) -> None:
    """Write a synthetic IRC-format month of heads-up 10-20 limit hold'em between two bots.

    With --game leduc: Leduc demonstrations of --expert, as `pokerirl leduc synth` writes
    them (an .npz that `pokerirl train` reads).
    """
    from pokerirl.game.synth import MAX_HANDS, write_synthetic_month

    leduc = leduc_rules(game, rules)
    if leduc is not None:
        from pokerirl.cli.leduc import exact_synth

        holdem_only(ctx, "Leduc's demonstrations are arrays, not hand histories",
                    reveal_all=reveal_all)  # fmt: skip
        exact_synth(leduc, expert=expert, opponent=opponent, hands=hands, seed=seed, out=out)
        return
    if given(ctx, expert=expert, opponent=opponent):
        raise UsageError("--expert and --opponent apply to --game leduc only")

    if hands > MAX_HANDS:
        raise UsageError(f"--hands must be at most {MAX_HANDS:,} (one month), got {hands:,}")
    folder = write_synthetic_month(out, hands=hands, seed=seed, reveal_all=reveal_all)
    echo(f"wrote {hands} hands to {folder}")


@app.command()
@on_error(interrupted=INTERRUPTED, advice=RUN_ADVICE)
@settings_options(irl=AIRLConfig)
def train(
    ctx: typer.Context,
    table: str = typer.Argument(
        ..., metavar="TABLE",
        help="Parquet decision table written by `pokerirl ingest`, or Leduc demonstrations "
        "(the .npz of `pokerirl leduc synth`).",
    ),
    out: str = typer.Option(
        ..., "--out", metavar="DIR", help="Run folder (with --runs > 1: a folder of runs)."
    ),
    algo: str = typer.Option(
        Algo.HAIRL, "--algo", metavar=choices(Algo),
        help="hairl, airl or gail (picks the defaults; gail also GAIL's discriminator).",
    ),
    runs: int = typer.Option(
        1, "--runs", min=1, max=MAX_SEEDS, help="Runs with seeds seed..seed+runs-1, in OUT/run-<k>."
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace a finished run (with --runs: runs of other settings)."
    ),
    jobs: int = typer.Option(1, "--jobs", "-j", min=1, help="Processes running --runs at once."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    device: str = typer.Option("cpu", "--device", metavar="DEVICE", help="cpu or cuda."),
    config: str | None = typer.Option(
        None, "--config", metavar="FILE", help="TOML file of hyperparameters."
    ),
    hidden: str | None = typer.Option(
        None, "--hidden", metavar="WIDTHS", help="Widths for both nets, e.g. 64,64."
    ),
    irl: Settings = NO_SETTINGS,  # AIRLConfig's options: --epochs, --seed, --alpha, ...
    encoding: str | None = typer.Option(
        None, "--encoding", metavar=ENCODING_CHOICES,
        help=ENCODING_HELP + " Default: rlcard; Leduc demonstrations have their one encoding.",
    ),
    threads: int = typer.Option(
        1, "--threads", min=1, help="CPU threads; small nets train best on 1."
    ),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
    em_rounds: int = typer.Option(
        0, "--em-rounds", min=0,
        help="On a table of ingest --folds impute: after the first run, re-impute the hidden "
        "cards N times with the last run's policy as the behaviour model and train again "
        "(OUT/round-<r>, OUT/table-<r>.parquet, OUT/em.json); one run only.",
    ),
    log_dir: Path | None = LOG_DIR,
    mode: str = typer.Option(
        IRLMode.OFFLINE, "--mode", metavar=choices(IRLMode),
        help="offline: the policy acts at the expert's states (the paper's); online: it plays "
        "hands on the engine against --opponent on the current learned reward.",
    ),
    rounds: int | None = POKER_ROUNDS,
    generator_steps: int | None = POKER_GENERATOR_STEPS,
    opponent: str | None = typer.Option(
        None, "--opponent", metavar="random|call|raise|tight|loose",
        help="Online: the fixed opponent the policy plays (default random; tight, loose: the "
        "synthetic months' TightBot, LooseBot).",
    ),
    game: GameName | None = typer.Option(
        None, "--game", metavar=GAME_CHOICES,
        help="Check that TABLE holds this game's decisions (the game is read from the data: "
        "holdem for a Parquet table, leduc for demonstrations).",
    ),
) -> None:
    """Learn a reward function with AIRL, Hybrid-AIRL or GAIL from an expert decision table.

    Writes OUT/reward.pt, policy.pt, config.json, timings.json, metrics.jsonl,
    baselines.json, split.json and plots; with --runs N, OUT/run-<k> and OUT/summary.json.
    A finished OUT is replaced only with --overwrite, and only once the new run is complete.
    With --mode online the same folder, its config.json saying data.mode = online.
    """
    from pokerirl.datasets.decisions import data_game
    from pokerirl.irl import load_config
    from pokerirl.irl.adversarial import resolve_device
    from pokerirl.poker.train import train_em, train_runs

    if game is not None and Path(table).is_file() and data_game(table) is not game:
        raise InputError(f"{table}: {GAME_WORDS[data_game(table)]}, not {GAME_WORDS[game]} "
                         "(the game is read from the data)")  # fmt: skip

    both = () if hidden is None else ("reward_hidden", "policy_hidden")
    nets = dict.fromkeys(both, widths(hidden or ""))
    # the algorithm's defaults, then the --config file's, then the flags given
    flags = {**irl, **nets}
    settings = settings_from_options(load_config, algo, config_file=config, overrides=flags)
    offline_only = {"--em-rounds": em_rounds > 0, "--device": device != "cpu",
                    "--jobs": jobs > 1, "--ray": ray is not None}  # fmt: skip
    online = _online_settings(mode, rounds, generator_steps, opponent, offline_only)
    settings_from_options(resolve_device, device)
    chosen = None if encoding is None else parse_encoding(encoding)
    if em_rounds and runs > 1:
        raise UsageError("--em-rounds re-imputes with one run's policy: give --runs 1")
    execution.pin_threads(threads)
    common: dict[str, Any] = dict(
        algo=algo, config=settings, device=device, progress=not quiet, overwrite=overwrite,
        encoding=chosen,
    )
    if em_rounds:
        _echo_em(train_em(table, out, rounds=em_rounds, **common), out, em_rounds)
    elif online is not None:
        _echo_runs(algo, _train_online(table, out, runs=runs, online=online, **common))
    else:
        backend = command_backend(jobs, ray)
        _echo_runs(algo, train_runs(table, out, runs=runs, backend=backend, **common))
    write_logs(Path(out), log_dir)


def _online_settings(
    mode: str, rounds: int | None, steps: int | None, opponent: str | None,
    offline_only: Mapping[str, bool],
) -> Any:
    """``train --mode``: None offline, else the online settings (a usage error for an
    online-only option offline, or an offline-only one given online: ``offline_only``)."""
    if not online_mode(mode, {"--rounds": rounds, "--generator-steps": steps,
                              "--opponent": opponent}):  # fmt: skip
        return None
    refused = [name for name, given_online in offline_only.items() if given_online]
    if refused:  # online runs train one after another, on the CPU, without EM
        raise UsageError(f"{refused[0]} applies to --mode offline only")
    from pokerirl.poker.online import Opponent, PokerOnlineSettings

    if opponent is not None and opponent not in tuple(Opponent):
        raise UsageError(f"--opponent must be one of {', '.join(Opponent)}, got {opponent!r}")
    return PokerOnlineSettings.given(rounds=rounds, generator_steps=steps, opponent=opponent)


def _train_online(table: str, out: str, *, online: Any, **kwargs: Any) -> RunSummary:
    """``train --mode online``: :func:`pokerirl.poker.online.train_poker_online`, a line a
    round."""
    from pokerirl.irl.metrics import Metric
    from pokerirl.poker.online import train_poker_online

    kwargs.pop("device")  # the engine and the generator run on the CPU

    def line(run: int, metrics: EpochMetrics) -> None:
        echo(
            f"run {run} round {metrics.epoch}/{online.rounds}: reward alignment "
            f"{Metric.VAL_REWARD_ALIGNMENT.of(metrics):.3f}, "
            f"disc loss {Metric.DISC_LOSS.of(metrics):.3f}, "
            f"generator {metrics['generator_bb_per_hand']:+.2f} bb/hand vs {online.opponent}"
        )

    return train_poker_online(table, out, settings=online, on_round=line, **kwargs)


def _echo_em(report: Mapping[str, Any], out: str, rounds: int) -> None:
    """``train --em-rounds``: each round's agreement, as the command prints it."""
    for found in report["rounds"]:
        change = found.get("policy_agree_imputed_change")
        echo(f"round {found['round']}: policy argmax = imputed actions "
             f"{found['policy_agree_imputed']:.1%}"
             + ("" if change is None else f" ({change:+.1%} from the round before)")
             + f", = observed actions {found['policy_agree_observed']:.1%}; reward "
             f"argmax = imputed {found['reward_agree_imputed']:.1%}")  # fmt: skip
    echo(f"wrote {out}/round-0..{rounds} and {out}/em.json")


def _echo_runs(algo: str, summary: RunSummary) -> None:
    """``train``: each run's last epoch (one run, or every run of --runs), then the speed."""
    if summary.results:  # several runs: each one, named by its folder
        for run in summary.results:
            _echo_run(f"{algo} {Path(run.out).name}", Path(run.out), run.metrics,
                      run.baselines, (run.train_rows, run.val_rows))  # fmt: skip
    else:
        _echo_run(algo, summary.out_dir, summary.metrics, summary.baselines,
                  (summary.train_rows, summary.val_rows))  # fmt: skip
    echo(f"{summary.samples_per_second:,.0f} samples/s; wrote {summary.out_dir}")


def _echo_run(
    name: str,
    folder: Path,
    metrics: Sequence[EpochMetrics],
    baselines: Mapping[str, float],
    rows: tuple[int, int],
) -> None:
    """One IRL run's last epoch, its baselines and its reward card, as ``pokerirl train``
    prints them."""
    from pokerirl.irl.metrics import Metric
    from pokerirl.poker.reward_card import read_card

    last = metrics[-1]
    echo(
        f"{name}: {len(metrics)} epochs on {rows[0]} rows; validation "
        f"alignment {Metric.VAL_ALIGNMENT.of(last):.3f}, reward alignment "
        f"{Metric.VAL_REWARD_ALIGNMENT.of(last):.3f}; baselines "
        + ", ".join(f"{k} {v:.3f}" for k, v in baselines.items())
        + f" on {rows[1]} rows"
    )
    card = read_card(folder)
    if card is not None:
        shares = ", ".join(f"{a} {v:.0%}" for a, v in card.argmax_share.items())
        echo(
            f"  reward card: {card.prediction}. argmax over legal actions: {shares}; "
            f"= expert {card.agree_expert:.1%}, = legal majority "
            f"{card.agree_legal_majority:.1%} (reward_card.json)"
        )


@app.command("reward-card")
def reward_card_command(
    reward: str = typer.Argument(
        ...,
        metavar="REWARD",
        help="An AIRL / H-AIRL run folder, or authors:FILE (one of the authors' rewards).",
    ),
    table: Path | None = typer.Option(
        None,
        "--table",
        help="Decision table (pokerirl ingest) of states; default: the run's own table. On a "
        "table of synth --reveal-all (every hand, folds too), the card scores the reward "
        "against the expert's true actions on all states.",
    ),
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Folder for reward_card.json and .png; default: the run."
    ),
    validation: bool = typer.Option(
        False, "--validation", help="Only the run's validation hands (its split.json)."
    ),
    transform: str = typer.Option(
        "raw",
        "--transform",
        metavar=choices(Transform),
        help="raw, centered, log_softmax or advantage (docs/rewards.md).",
    ),
    encoding: str | None = typer.Option(
        None,
        "--encoding",
        metavar=ENCODING_CHOICES,
        help="The encoding the run must read (rlcard or strength); default: the run's own. "
        "A run of another encoding is refused.",
    ),
) -> None:
    """What a reward prefers: f per action, the per-decision bonus, the argmax over legal
    actions by street and equity, its agreement with the expert and the legal-majority rule,
    and what a DQN is predicted to learn. Writes OUT/reward_card.json and reward_card.png.
    """
    from pokerirl.agents.leduc_specs import leduc_spec_reason
    from pokerirl.poker.reward_card import CardStates, reward_card, write_card
    from pokerirl.poker.reward_sources import RewardSource
    from pokerirl.poker.rewards import TRANSFORMS, TransformedReward

    if transform not in TRANSFORMS:
        raise UsageError(f"unknown --transform {transform!r} ({', '.join(TRANSFORMS)})")
    if leduc_spec_reason("reward:" + reward) is not None:
        raise InputError(  # the words of run_encoding's refusal, and what to use instead
            f"{reward}: a reward learned on the game 'leduc', not on heads-up limit hold'em "
            f"(on Leduc: pokerirl exploit reward:{reward} --game leduc, match --game leduc, "
            "leduc agreement)"
        )
    resolved = RewardSource.resolve(reward)
    if encoding is not None:
        _check_encoding(resolved, parse_encoding(encoding))
    table = table if table is not None else _run_table(resolved)
    out = out if out is not None else _run_folder(resolved, "--out")
    source = resolved.load()
    groups = None
    if validation:
        from pokerirl.irl.run import SPLIT_FILE, read_split

        if not (Path(reward) / SPLIT_FILE).is_file():
            raise InputError(f"--validation needs a run folder with split.json; {reward} has none")
        groups = read_split(reward)
    states = CardStates.from_table(table, groups=groups, progress=True)
    card = reward_card(TransformedReward(source, transform), states)
    if not resolved.is_authors and transform == "raw":  # the run's own numbers, to flag below-BC
        from pokerirl.irl.run import load_run_config
        from pokerirl.poker.reward_card import with_run_alignments

        card = with_run_alignments(card, load_run_config(reward))
    write_card(card, out)
    echo(card.render())
    echo(f"wrote {out / 'reward_card.json'} and reward_card.png")


agent_app = typer.Typer(help="Train DQN agents.", no_args_is_help=True)
app.add_typer(agent_app, name="agent")


@agent_app.command("train")
@on_error(interrupted=INTERRUPTED)
@settings_options(train=TrainConfig, dqn=DQNConfig)
def agent_train(
    ctx: typer.Context,
    out: Path = typer.Option(..., "--out", "-o", help="Agent folder (with --seeds: its parent)."),
    preset: str = typer.Option(
        "default", "--preset", metavar=choices(AGENT_PRESETS),
        help="default (ours: 50,000 hands, train_every 16) or authors (their train_rl.py: "
        "5,000 hands, lr 5e-4, train_every 1, epsilon 1 -> 0 over 5,000 steps, evaluation "
        "every 100 hands on 1,000 games, the > 0.8 x best checkpoint plays). Flags and "
        "--config override it.",
    ),
    config_file: Path | None = typer.Option(
        None, "--config", help="TOML file of settings (any TrainConfig or DQNConfig field)."
    ),
    seed: int = typer.Option(0, **SEED_OPTION, help="Seed of one agent."),
    seeds: str | None = typer.Option(
        None, callback=seed_list, metavar="SEEDS",
        help="e.g. 0-19: one agent per seed, in OUT/seed-<k>.",
    ),
    jobs: int = typer.Option(
        1, "--jobs", "-j", min=1, help="Local processes training seeds at once."
    ),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    threads: int = typer.Option(
        1, "--threads", min=1,
        help="torch threads per agent (part of the result: the weights change).",
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Retrain finished agents of other settings (else refused)."
    ),
    train: Settings = NO_SETTINGS,  # TrainConfig's options: --hands, --reward, --opponent, ...
    dqn: Settings = NO_SETTINGS,  # DQNConfig's options: --hidden, --lr, --train-every, ...
    log_dir: Path | None = LOG_DIR,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
    game: GameName = GAME_OPTION,
    rules: RuleSet | None = RULES_OPTION,
    rl: LeducRL | None = typer.Option(
        None, "--rl", metavar=LEDUC_RL_CHOICES,
        help="With --game leduc: dqn (the Leduc DQN, the default) or tabular (the tabular "
        "Monte-Carlo learner), as the Leduc study's --rl.",
    ),
) -> None:
    """Train a DQN agent (or one per seed) on the sparse payoff or a learned reward.

    A finished agent folder is never changed: a rerun with the same settings reuses it,
    one with other settings is refused (--overwrite retrains it). New folders are
    written beside the old and swapped in at the end, so a killed run loses nothing.
    With --seeds, seeds run as units (--jobs or --ray); a rerun resumes the set.
    Every setting: --preset, then --config FILE, then the flags (docs/agents.md).

    With --game leduc: the Leduc DQN (or --rl tabular: the tabular learner) against
    --opponent (a Leduc agent, default random) for --hands (default 100,000) on the sparse reward or
    --reward learned --reward-run RUN (a Leduc run's g); OUT/strategy.json (its greedy
    strategy, a Leduc agent) and summary.json with its exact exploitability and value.
    """
    leduc = leduc_rules(game, rules)
    if leduc is not None:
        _leduc_agent_train(ctx, leduc, out, train, dqn, rl=rl or LeducRL.DQN, seed=seed,
                           overwrite=overwrite)  # fmt: skip
        return
    if rl is not None:
        raise UsageError("--rl applies to --game leduc only (hold'em's agents are DQNs)")
    from pokerirl.agents.config import AgentOverrides, load_agent_config
    from pokerirl.agents.train import train_agent, train_seeds
    from pokerirl.seeds import parse_seeds

    backend = command_backend(jobs, ray, threads)
    from_file = AgentOverrides()
    if config_file is not None:
        from_file = settings_from_options(load_agent_config, config_file)
    config = settings_from_options(
        from_file.with_flags(train=train, dqn=dqn).config, preset, seed=seed
    )
    common: dict[str, Any] = dict(progress=not quiet, overwrite=overwrite, backend=backend)
    if seeds is None:
        lines = {seed: train_agent(out, config, **common)}
    else:
        lines = train_seeds(out, config, list(parse_seeds(seeds)), jobs=jobs, **common)
    for agent_seed, line in lines.items():
        _echo_agent(out if seeds is None else out / f"seed-{agent_seed}", line, config.play)
    write_logs(out, log_dir)


LEDUC_TRAIN = ("hands", "opponent", "reward", "reward_run")  # the settings a Leduc DQN takes
LEDUC_HANDS = 100_000  # the Leduc study's quick preset


def _leduc_agent_train(ctx: typer.Context, rules: Any, out: Path, train: Settings, dqn: Settings,
                       *, rl: LeducRL, seed: int, overwrite: bool) -> None:  # fmt: skip
    """``agent train --game leduc``: one line for a hold'em setting, then
    :func:`pokerirl.cli.leduc.exact_agent_train`."""
    from pokerirl.cli.leduc import exact_agent_train

    why = "a Leduc agent takes --rl, --hands, --opponent, --reward, --reward-run, --seed"
    holdem_only(ctx, why, **{k: v for k, v in {**train, **dqn}.items() if k not in LEDUC_TRAIN})
    holdem_only(ctx, why, preset=ctx.params.get("preset"), config_file=ctx.params.get(
        "config_file"), seeds=ctx.params.get("seeds"), jobs=ctx.params.get("jobs"),
        ray=ctx.params.get("ray"), threads=ctx.params.get("threads"),
        log_dir=ctx.params.get("log_dir"))  # fmt: skip
    learned = str(train.get("reward", "sparse")) == "learned"
    run = train.get("reward_run")
    if learned != (run is not None):
        raise UsageError("--reward learned and --reward-run RUN go together")
    exact_agent_train(
        rules, out=out, rl=rl, opponent=str(train.get("opponent", "random")),
        hands=int(train.get("hands", LEDUC_HANDS)), seed=seed,
        reward_run=None if run is None else str(run), overwrite=overwrite,
    )  # fmt: skip


def _echo_agent(folder: Path, line: MetricsLine | None, play: str) -> None:
    """``agent train``: an agent's last evaluation (and the checkpoint it plays)."""
    from pokerirl.agents.names import CONFIG_FILE, KEPT_FILE, MODEL_FILE
    from pokerirl.agents.train import MetricsLine

    if line is None:
        echo(f"{folder}: already finished with these settings, reused")
        return
    scores = ", ".join(
        f"vs {n} {e.mbb_per_hand:+.0f} +- {e.std_error:.0f} mbb/h" for n, e in line.eval.items()
    )
    follows = (
        "" if line.follows_reward is None
        else f"; follows its reward on {line.follows_reward:.0%} of its decisions vs random"
    )  # fmt: skip
    echo(f"{folder}: {line.hands:,} hands, {scores}{follows}")
    if play == Plays.KEPT:
        kept = MetricsLine.from_json(read_json(folder / CONFIG_FILE)["kept"])
        echo(
            f"{folder}: plays {KEPT_FILE} (after {kept.hands:,} hands, vs random "
            f"{kept.eval['random'].mbb_per_hand:+.0f} mbb/h in its evaluation); "
            f"{MODEL_FILE} is the final model"
        )


def _check_encoding(source: object, expected: Encoding) -> None:
    """Refuse, in one line naming the run, a reward run of another encoding."""
    from pokerirl.game.encodings import get_encoding

    found = getattr(source, "encoding", None)  # its spec: strength-v1 is still strength
    if found is not None and get_encoding(found).name != expected.name:
        raise InputError(
            f"{getattr(source, 'spec', source)}: a reward on the {found} encoding, not "
            f"{expected.name} (its config.json's data.encoding)"
        )


def _run_folder(source: object, option: str) -> Path:
    """A reward run's folder, as the default of ``option`` (an authors' file has none)."""
    spec = str(getattr(source, "spec", source))
    if getattr(source, "is_authors", False):
        raise UsageError(f"{option} is needed for {spec} (an authors' file, not a run folder)")
    return Path(spec)


def _run_table(source: object) -> Path:
    """The decision table a reward run was trained on (its ``config.json``'s data.path)."""
    from pokerirl.irl.run import load_run_config

    folder = _run_folder(source, "--table")
    path = (load_run_config(folder).get("data") or {}).get("path")
    if not isinstance(path, str) or not Path(path).is_file():
        raise UsageError(
            f"--table is needed: {folder} records no table that still exists ({path!r})"
        )
    return Path(path)

