"""Train DQN agents into agent folders: evaluation, metrics, learning curve, many seeds.

:func:`train_agent` trains one agent (see :func:`pokerirl.agents.dqn.train_dqn`) and every
``eval_every`` hands plays its greedy policy against random and against the training opponent
(:func:`pokerirl.game.play_match`, duplicate, a fixed evaluation seed), appending a line to
``metrics.jsonl`` and redrawing ``learning_curve.png``. :func:`train_seeds` trains one agent
per seed into ``<out>/seed-<k>``.

``protocol="authors"`` trains and evaluates as the authors' ``train_rl.py`` does (see
:data:`AGENT_PRESETS`): an evaluation after hands 1, 1 + ``eval_every``, ... on ``eval_hands``
fresh games against random, seats drawn per game (RLCard's ``tournament``); the model of
every evaluation that beats 0.8 x the best payoff so far is kept (``kept.pt``), beside the
final one (``model.pt``); ``play`` says which one the folder's agent plays.

Both run through :func:`pokerirl.store.run_units`: each agent is a unit, trained with
torch on ``threads`` threads (one by default) in a private folder from its own seed, from the
bytes of its reward run and opponent; the driver writes the folder. So the weights do not
depend on the backend, the job count or the machine's cores. A folder is written beside its
target and swapped in at the end, with ``unit.json`` (the fingerprint of everything that
determines the agent, the reward run's and the opponent's fingerprints as its inputs, and the
sha256 of each file) and ``timings.json`` (wall-clock figures, kept out of ``config.json`` so
that fingerprints never cover them). A rerun reuses an agent whose fingerprint matches (a
folder of an older pokerirl too), retrains one whose files are corrupt, and refuses one
trained with other settings unless ``overwrite``.

>>> import tempfile
>>> from pokerirl.agents.config import DQNConfig
>>> out = Path(tempfile.mkdtemp()) / "dqn"
>>> config = TrainConfig(hands=512, seed=0, eval_every=512, eval_hands=200,
...                      dqn=DQNConfig(concurrent_hands=128))
>>> summary = train_agent(out, config)
>>> sorted(p.name for p in out.iterdir())
['config.json', 'learning_curve.png', 'metrics.jsonl', 'model.pt', 'timings.json', 'unit.json']
>>> train_agent(out, config) is None  # finished with these settings: reused
True
"""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from pokerirl import __version__
from pokerirl.agents import ShippedAgent, land_agent, ship_agent
from pokerirl.agents.checkpoint import CURVE_FILE, METRICS_FILE, save_agent
from pokerirl.agents.config import (
    AgentOverrides,  # noqa: F401 - re-exported from its old home
    Opponent,
    RewardMode,
    TrainConfig,
    TrainingProtocol,
    agent_preset,  # noqa: F401 - re-exported from its old home
    load_agent_config,  # noqa: F401 - re-exported from its old home
)
from pokerirl.agents.dqn import (
    DQNLearner,
    RewardFn,
    epsilon_at,
    train_dqn,
)
from pokerirl.agents.names import CONFIG_FILE, KEPT_FILE, MODEL_FILE
from pokerirl.agents.registry import agent_fingerprint, resolve_agent
from pokerirl.atomic import atomic_path
from pokerirl.errors import ConfigError, InputError
from pokerirl.execution import Backend, read_files
from pokerirl.game import DecisionLog, make_agent, play_match
from pokerirl.game.bots import Agent
from pokerirl.game.encodings import get_encoding
from pokerirl.irl.run import REWARD_RUN_FILES  # noqa: F401 - re-exported: pokerirl.agents.train.REWARD_RUN_FILES
from pokerirl.jsonio import read_json_lines
from pokerirl.poker.reward_sources import RewardSource
from pokerirl.poker.rewards import (
    ObservedDecisions,
    PokerReward,
    TransformedReward,
    as_poker_reward,
    follow_share,
)
from pokerirl.serial import Omit, Serializable, meta
from pokerirl.store import Unit, UnitOutput, run_units

TIMINGS_FILE = "timings.json"
AGENT_OUTPUTS = (MODEL_FILE, CONFIG_FILE, METRICS_FILE, CURVE_FILE)
KEEP_RATIO = 0.8  # the authors' rule: keep a model whose payoff beats 0.8 x the best so far


_OURS = TrainConfig(hands=1, seed=0)
@dataclass(frozen=True, kw_only=True)
class Score(Serializable):
    """The greedy policy's result against one opponent."""

    mbb_per_hand: float
    std_error: float


@dataclass(frozen=True, kw_only=True)
class MetricsLine(Serializable):
    """One evaluation during training: a line of ``metrics.jsonl``, and the ``final`` and
    ``kept`` of an agent's ``config.json``. ``eval`` maps each opponent's label (``random``
    first) to its score; ``keep_rule`` (the authors' protocol only, written only when set)
    says whether the line was offered to their keep rule; ``follows_reward`` (learned rewards
    only) is the share of the greedy policy's decisions against random where it takes the
    reward's best legal action."""

    hands: int
    transitions: int
    updates: int
    epsilon: float
    loss: float | None  # None before the first update (JSON has no NaN)
    eval: Mapping[str, Score]
    keep_rule: bool | None = field(default=None, metadata=meta(omit=Omit.NONE))
    # A learned-reward agent's share of its decisions against random (the evaluation's) where
    # it takes f's best legal action: whether the DQN follows its reward (written when set).
    follows_reward: float | None = field(default=None, metadata=meta(omit=Omit.NONE))


def read_metrics(folder: str | os.PathLike[str]) -> list[MetricsLine]:
    """An agent folder's evaluations during training (its ``metrics.jsonl``), typed: what a
    study reads of the agents it trained, instead of the file's keys."""
    path = Path(folder) / METRICS_FILE
    lines = read_json_lines(path)
    return [MetricsLine.from_json(line, f"{path}:{i + 1}") for i, line in enumerate(lines)]


@dataclass(frozen=True, kw_only=True)
class Evaluation(Serializable):
    """The seconds since the start of training at an evaluation."""

    hands: int
    seconds: float


@dataclass(frozen=True, kw_only=True)
class Timings(Serializable):
    """An agent's ``timings.json`` (never fingerprinted): the whole run, and the seconds
    since the start at each evaluation."""

    seconds: float
    hands_per_second: float | None
    evaluations: tuple[Evaluation, ...]


def reward_run_fingerprint(run_dir: str | os.PathLike[str]) -> str:
    """``sha256:<hex>`` of a reward source: a run's ``reward.pt`` and ``config.json``, or an
    ``authors:FILE`` (:class:`pokerirl.poker.reward_sources.RewardSource`)."""
    return RewardSource.read(run_dir).fingerprint


def _evaluate(
    learner: DQNLearner, opponents: Mapping[str, Agent], config: TrainConfig, index: int,
    reward: PokerReward | None = None,
) -> tuple[dict[str, Score], float | None]:  # fmt: skip
    """The greedy policy against each opponent: duplicate hands of the fixed evaluation seed,
    or, for the authors' protocol, fresh games (seed ``eval_seed + index``) with seats drawn
    per game, as RLCard's ``tournament``; and, given its ``reward``, the share of its
    decisions against random (the first opponent) that follow it."""
    greedy = learner.greedy_agent()
    authors = config.protocol == TrainingProtocol.AUTHORS
    results: dict[str, Score] = {}
    log: list[DecisionLog] = []
    for label, opponent in opponents.items():
        result = play_match(
            greedy,
            opponent,
            hands=config.eval_hands,
            seed=config.eval_seed + index if authors else config.eval_seed,
            duplicate=not authors,
            seating="random" if authors else "alternate",
            log=log if reward is not None and not results else None,
        )
        results[label] = Score(mbb_per_hand=result.mbb_per_hand, std_error=result.std_error)
    return results, None if reward is None else followed(reward, log)


def followed(reward: PokerReward, log: Sequence[DecisionLog]) -> float:
    """The share of logged decisions (:class:`~pokerirl.game.DecisionLog`) that take
    ``reward``'s best legal action (:func:`pokerirl.poker.rewards.follow_share`)."""
    seen = DecisionLog.concatenate(list(log))
    decisions = ObservedDecisions(obs=seen.obs, legal_mask=seen.legal_mask, cards=seen.cards)
    return round(follow_share(reward, decisions, seen.actions), 6)


def evaluation_points(config: TrainConfig) -> list[int]:
    """Training hands after which the agent is evaluated (the last one: the final model).

    Ours: every ``eval_every`` hands and at the end (at the first lock-step boundary on or
    after each). The authors': after hands 1, 1 + ``eval_every``, ... (their episode 0, 100,
    ...), then ours adds the end, which their rule never sees.

    >>> evaluation_points(TrainConfig(hands=250, seed=0, eval_every=100, protocol="authors"))
    [1, 101, 201, 250]
    """
    if config.protocol == TrainingProtocol.AUTHORS:
        points = list(range(1, config.hands + 1, config.eval_every))
    else:
        points = list(range(config.eval_every, config.hands, config.eval_every))
    return points if points and points[-1] == config.hands else [*points, config.hands]


def plot_learning_curve(metrics: Sequence[MetricsLine], path: Path) -> None:
    """mbb/h (± one standard error) of every evaluation against training hands, as a PNG."""
    import matplotlib

    from pokerirl.figures import finish

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 4))
    for label in metrics[0].eval:
        hands = [m.hands for m in metrics]
        mbb = np.array([m.eval[label].mbb_per_hand for m in metrics])
        error = np.array([m.eval[label].std_error for m in metrics])
        axes.plot(hands, mbb, marker="o", label=f"vs {label}")
        axes.fill_between(hands, mbb - error, mbb + error, alpha=0.25)
    axes.axhline(0.0, color="grey", linewidth=0.8)
    finish(axes, title="Evaluations during training", xlabel="training hands",
           ylabel="mbb/hand (greedy, duplicate deals)",
           spread="bands: ± 1 standard error of each evaluation")  # fmt: skip
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", dpi=100)
    plt.close(figure)


def train_agent(
    out: str | os.PathLike[str],
    config: TrainConfig,
    *,
    reward_fn: RewardFn | None = None,
    progress: bool = False,
    overwrite: bool = False,
    backend: Backend | None = None,
) -> MetricsLine | None:
    """Train one agent into the folder ``out``; return its last evaluation, or None when
    ``out`` already holds this agent (same fingerprint).

    In learned mode, ``reward_fn`` is f_θ (then the agent trains in this process); without
    it, f_θ is loaded from ``config.reward_run``. ``out`` is replaced only at the end, whole;
    a finished agent of other settings is refused unless ``overwrite``. ``backend``: where
    it trains and on how many torch threads (default: here, on one).
    """
    return _train_many(
        {config.seed: (Path(out), config)},
        backend=backend or Backend(),
        reward_fn=reward_fn,
        overwrite=overwrite,
        progress=progress,
    )[config.seed]


def train_seeds(
    out: str | os.PathLike[str],
    config: TrainConfig,
    seeds: list[int],
    *,
    jobs: int = 1,
    progress: bool = False,
    overwrite: bool = False,
    backend: Backend | None = None,
) -> dict[int, MetricsLine | None]:
    """Train one agent per seed into ``<out>/seed-<k>``, as units on ``backend`` (default:
    ``jobs`` local processes).

    Seeds already finished with the same settings are reused (their value is ``None``); the
    others map to their last evaluation. One progress bar counts seeds.
    """
    if jobs < 1:
        raise ConfigError(f"jobs must be at least 1, got {jobs}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out} exists and is not a folder")
    units = {s: (out / f"seed-{s}", dataclasses.replace(config, seed=s)) for s in seeds}
    return _train_many(
        units,
        backend=backend or Backend(jobs=jobs),
        reward_fn=None,
        overwrite=overwrite,
        progress=progress,
    )


@dataclass(frozen=True, kw_only=True)
class _TrainUnit:
    """What a worker needs to train one agent: settings and the bytes of its inputs."""

    config: TrainConfig
    reward_source: RewardSource | None  # None: sparse, or a reward_fn given in this process
    reward_fingerprint: str | None
    opponent: ShippedAgent | Opponent  # an agent's files, or self-play or the pool
    threads: int
    progress: bool


def agent_unit_config(
    config: TrainConfig, *, reward_fingerprint: str | None, opponent: str, threads: int
) -> dict[str, object]:
    """Everything that determines an agent's bytes, fingerprinted in its ``unit.json``.

    Inputs count by content (the reward run's and the opponent's fingerprints), not by path.
    Settings added since the first format appear only when they differ from their default,
    so agents trained before them keep their fingerprints.
    """
    found = {
        "kind": "pokerirl-dqn-agent",
        "seed": config.seed,
        "hands": config.hands,
        "reward": config.reward,
        "reward_run": reward_fingerprint,
        "payoff_weight": config.payoff_weight,
        "opponent": opponent,
        "evaluation": [config.eval_every, config.eval_hands, config.eval_seed],
        "dqn": dataclasses.asdict(config.dqn),
        "threads": threads,
    }
    for name in ("reward_transform", "raise_counts", "protocol", "play", "encoding"):
        if getattr(config, name) != getattr(_OURS, name):
            found[name] = getattr(config, name)
    return found


def _train_many(
    units: dict[int, tuple[Path, TrainConfig]],
    *,
    backend: Backend,
    reward_fn: RewardFn | None,
    overwrite: bool,
    progress: bool,
) -> dict[int, MetricsLine | None]:
    """Train the agents not already finished, each into its folder; reused ones map to None."""
    if not units:
        return {}
    first = next(iter(units.values()))[1]  # every unit shares these settings but the seed
    # Bad input fails here, in one line, before any worker starts; the reward is resolved
    # once (read, checked, hashed) and its bytes travel in the units.
    source: RewardSource | None = None
    reward_print = None
    if first.reward == RewardMode.LEARNED:
        if first.reward_run is None:
            raise ConfigError("reward 'learned' needs a reward_run (a run folder, or authors:FILE)")
        # A reward given in this process is used as it is: its run is only named and hashed.
        read = RewardSource.read if reward_fn is not None else RewardSource.resolve
        source = read(first.reward_run)
        reward_print = source.fingerprint
    opponent: ShippedAgent | Opponent
    opponent_print: str
    if first.opponent in tuple(Opponent):
        opponent = opponent_print = Opponent(first.opponent)
    else:
        opponent_print = agent_fingerprint(resolve_agent(first.opponent))
        opponent = ship_agent(first.opponent)
    if reward_fn is not None:
        backend = dataclasses.replace(backend, kind="local", address=None, jobs=1)

    inputs = {"reward_run": reward_print, "opponent": opponent_print}
    agents = []
    for folder, config in units.values():
        unit_config = agent_unit_config(
            config, reward_fingerprint=reward_print, opponent=opponent_print,
            threads=backend.threads,
        )  # fmt: skip
        unit = _TrainUnit(
            config=config,
            reward_source=None if reward_fn is not None else source,
            reward_fingerprint=reward_print,
            opponent=opponent,
            threads=backend.threads,
            progress=progress and len(units) == 1 and backend.kind == "local",
        )
        agents.append(
            Unit(
                key=str(folder),
                target=folder,
                config={k: v for k, v in unit_config.items() if k not in inputs},
                inputs=inputs,
                fn=_train_unit,
                args=(unit, reward_fn),
            )
        )
    done = run_units(
        agents, backend, overwrite=overwrite, progress=progress and len(units) > 1,
        desc=_set_name(folder for folder, _ in units.values()),
    ).done  # fmt: skip
    return {key: agent.extra for key, agent in zip(units, done, strict=True)}


def _set_name(folders: Iterable[Path]) -> str:
    """A set's bar label: its folder, ``agents hairl-dqn`` (a study trains four sets)."""
    parents = {Path(folder).parent.name for folder in folders}
    return f"agents {parents.pop()}" if len(parents) == 1 else "agents"


def _train_unit(unit: _TrainUnit, reward_fn: RewardFn | None = None) -> UnitOutput[MetricsLine]:
    """Train one agent in a private folder and return its files, its timings (never
    fingerprinted) and its last metrics line (runs in a worker)."""
    config = unit.config
    reward: PokerReward | None = None
    with tempfile.TemporaryDirectory(prefix="pokerirl-agent-") as private:
        if config.reward == RewardMode.LEARNED:
            if reward_fn is None:
                assert unit.reward_source is not None  # resolved by the driver
                reward = unit.reward_source.load()
            else:
                reward = as_poker_reward(reward_fn)
            reward = TransformedReward(reward, config.reward_transform)  # type: ignore[arg-type]
        opponent = (
            unit.opponent
            if isinstance(unit.opponent, Opponent)
            else land_agent(unit.opponent, Path(private, "opponent"))
        )
        out = Path(private, "agent")
        summary, timings = _train_into(
            out,
            config,
            reward=reward,
            reward_fingerprint=unit.reward_fingerprint,
            opponent=opponent,
            threads=unit.threads,
            progress=unit.progress,
        )
        kept = (KEPT_FILE,) if (out / KEPT_FILE).is_file() else ()
        files = read_files(out, (*AGENT_OUTPUTS, *kept))
    timed = {TIMINGS_FILE: (json.dumps(timings.to_json(), indent=2) + "\n").encode()}
    return UnitOutput(files=files, unhashed=timed, extra=summary)


@dataclass(kw_only=True)
class _Keeper:
    """The authors' checkpoint rule: after an evaluation whose payoff against random beats
    0.8 x the best so far, keep that model (``train_rl.py``: ``if payoff > 0.8 *
    best_payoff: torch.save(agent)``; the best starts at minus infinity)."""

    best: float = float("-inf")
    state: dict[str, torch.Tensor] | None = None
    line: MetricsLine | None = None

    def offer(self, learner: DQNLearner, line: MetricsLine) -> None:
        payoff = line.eval["random"].mbb_per_hand
        if payoff > KEEP_RATIO * self.best:
            self.state = {k: v.detach().clone() for k, v in learner.q_net.state_dict().items()}
            self.line = line
            self.best = max(self.best, payoff)


def _train_into(
    out: Path,
    config: TrainConfig,
    *,
    reward: PokerReward | None,
    reward_fingerprint: str | None,
    opponent: Agent | str,
    threads: int,
    progress: bool,
) -> tuple[MetricsLine, Timings]:
    """Train into the new folder ``out``; return the last metrics line and the timings."""
    # The frozen self-play copy and the pool change all the time: against random only then.
    opponents: dict[str, Agent] = {"random": make_agent("random")}
    if not isinstance(opponent, str) and config.opponent != "random":
        opponents[config.opponent] = opponent

    out.mkdir(parents=True)
    metrics_path = out / METRICS_FILE
    metrics_path.write_text("")
    metrics: list[MetricsLine] = []
    seconds: list[float] = []
    started = time.perf_counter()
    points = evaluation_points(config)
    keeper = _Keeper() if config.protocol == TrainingProtocol.AUTHORS else None

    def evaluate(hands_done: int, learner: DQNLearner) -> None:
        due = [p for p in points if p <= hands_done]
        if not due:
            return
        del points[: len(due)]
        seconds.append(round(time.perf_counter() - started, 3))  # timings.json, not here
        keep_rule = None
        scores, follows = _evaluate(learner, opponents, config, len(metrics), reward)
        if keeper is not None:
            # The authors never evaluate their last hands' model: the end is not offered.
            is_final = hands_done == config.hands and (config.hands - 1) % config.eval_every
            keep_rule = not is_final
        line = MetricsLine(
            hands=hands_done,
            transitions=learner.total_t,
            updates=learner.train_t,
            epsilon=epsilon_at(config.dqn, learner.total_t),
            loss=None if np.isnan(learner.last_loss) else learner.last_loss,
            eval=scores,
            keep_rule=keep_rule,
            follows_reward=follows,
        )
        if keeper is not None and keep_rule:
            keeper.offer(learner, line)
        metrics.append(line)
        with metrics_path.open("a") as stream:
            stream.write(json.dumps(line.to_json()) + "\n")
        plot_learning_curve(metrics, out / CURVE_FILE)

    learner = train_dqn(
        config.dqn,
        hands=config.hands,
        seed=config.seed,
        opponent=opponent,
        reward_fn=reward,
        payoff_weight=config.payoff_weight,
        raise_counts=config.raise_counts,
        progress=progress,
        on_hands=evaluate,
        encoding=config.encoding,
    )
    record = {
        "hidden": list(config.dqn.hidden),
        "encoding": get_encoding(config.encoding).spec,
        "source": {"kind": "pokerirl-dqn", "version": __version__, "torch": torch.__version__},
        "reward": {
            "mode": config.reward,
            "run": config.reward_run,
            "fingerprint": reward_fingerprint,
            "payoff_weight": config.payoff_weight,
            "transform": config.reward_transform,
            "raise_counts": config.raise_counts,
        },
        "opponent": {
            "spec": config.opponent,
            "fingerprint": opponent if isinstance(opponent, str) else agent_fingerprint(opponent),
        },
        "seed": config.seed,
        "hands": config.hands,
        "threads": threads,
        "evaluation": {
            "every": config.eval_every,
            "hands": config.eval_hands,
            "seed": config.eval_seed,
            "protocol": config.protocol,
        },
        "dqn": dataclasses.asdict(config.dqn),
        "final": metrics[-1].to_json(),
        "plays": config.play,
        "kept": None if keeper is None or keeper.line is None else keeper.line.to_json(),
    }
    save_agent(out, learner.q_net, record, kept=None if keeper is None else keeper.state)
    total = time.perf_counter() - started
    timings = Timings(
        seconds=round(total, 3),
        hands_per_second=round(config.hands / total, 1) if total > 0 else None,
        evaluations=tuple(
            Evaluation(hands=m.hands, seconds=t) for m, t in zip(metrics, seconds, strict=True)
        ),
    )
    return metrics[-1], timings
