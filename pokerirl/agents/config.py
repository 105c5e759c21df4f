"""The settings of a DQN agent's training, torch-free: :class:`TrainConfig` (what an agent
learns from, against whom, how it is evaluated), :class:`DQNConfig` (the learner), the
presets (:data:`AGENT_PRESETS`) and their TOML overrides (:func:`load_agent_config`). The
command line builds ``agent train``'s options from these fields without loading torch;
:mod:`pokerirl.agents.train` and :mod:`pokerirl.agents.dqn` use them.
"""

from __future__ import annotations

import dataclasses
import os
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

from pokerirl.errors import ConfigError
from pokerirl.game.encodings import EncodingName
from pokerirl.poker.rewards import RaiseCounts, Transform
from pokerirl.settings import (
    MAX_BATCH,
    MAX_LAYERS,
    MAX_REPLAY,
    MAX_STEPS,
    MAX_WIDTH,
    check_bounds,
    enum_value,
    setting,
    with_overrides,
)


class Plays(StrEnum):
    """Which checkpoint an agent plays: the final model, or the authors' kept one."""

    FINAL = "final"
    KEPT = "kept"


PLAYS: tuple[str, ...] = tuple(Plays)


class Opponent(StrEnum):
    """Opponent specs that name no agent."""

    SELF = "self"  # a frozen greedy copy of the learner
    # Each hand against one member of a mixture: the fixed strategies of POOL_STRATEGIES and,
    # once there are some, the latest POOL_SNAPSHOTS greedy snapshots of the learner (half of
    # the hands): an agent cannot win by exploiting random alone.
    POOL = "pool"


SELF_PLAY = Opponent.SELF
POOL_STRATEGIES = ("random", "call", "raise", "tightbot", "loosebot")
POOL_SNAPSHOTS = 4


class RewardMode(StrEnum):
    """What an agent learns from: the payoff at the end of a hand, or a learned reward."""

    SPARSE = "sparse"
    LEARNED = "learned"


class TrainingProtocol(StrEnum):
    """How an agent is evaluated and kept: ours (duplicate deals), or the authors'."""

    POKERIRL = "pokerirl"
    AUTHORS = "authors"



@dataclass(frozen=True, kw_only=True)
class DQNConfig:
    """Hyper-parameters; RLCard's ``DQNAgent`` defaults except where noted.

    ``train_every`` (RLCard: 1) is the number of stored transitions per gradient update. A
    32-sample update (~0.8 ms on a CPU core) costs a hundred times more than playing a
    decision on the engine, so with RLCard's one update per transition, training would run
    at RLCard's speed. 16 still replays each transition twice on average (batch 32 / 16),
    and 50,000 sparse-reward hands against random reach about +2,700 mbb/h, more than twice
    always-call's +1,170 (the sweep over 1, 8, 16, 32, 128 is in ``docs/agents.md``).

    ``concurrent_hands`` hands are played in lock-step: all decisions of one step are taken by
    one forward pass with the same network and epsilon.
    """

    hidden: tuple[int, ...] = setting(
        (64, 64), help="Q-network widths, e.g. 64,64.", min=1, max=MAX_WIDTH, max_len=MAX_LAYERS
    )
    replay_size: int = setting(20_000, help="Replay memory size.", max=MAX_REPLAY)
    replay_init: int = setting(
        100, help="Transitions before the first update.", max=MAX_REPLAY
    )
    batch_size: int = setting(32, help="Update minibatch size.", max=MAX_BATCH)
    learning_rate: float = setting(5e-5, help="Adam lr.", flags=("--lr", "--learning-rate"))
    gamma: float = setting(0.99, help="Discount.")
    epsilon_start: float = setting(1.0, help="Exploration at the start.")
    epsilon_end: float = setting(0.1, help="Exploration after the decay.")
    # in stored transitions, as RLCard's total_t
    epsilon_decay_steps: int = setting(
        20_000, help="Transitions of the linear decay.", max=MAX_STEPS
    )
    target_update_every: int = setting(
        1_000, help="Updates between target copies.", max=MAX_STEPS
    )
    train_every: int = setting(
        16, help="Stored transitions per gradient update.", max=MAX_STEPS
    )
    concurrent_hands: int = setting(
        1024, help="Hands played in lock-step.", max=MAX_BATCH
    )
    # refreshes of the frozen copy with opponent "self", snapshots with "pool"
    self_play_every: int = setting(
        1_000, help="Updates between refreshes of 'self' (snapshots of 'pool').", max=MAX_STEPS
    )

    def __post_init__(self) -> None:
        check_bounds(self)  # before anything is built: a width of 10^9, a replay of 10^12
        positive = (
            "replay_size", "replay_init", "batch_size", "epsilon_decay_steps",
            "target_update_every", "train_every", "concurrent_hands", "self_play_every",
        )  # fmt: skip
        for name in positive:
            if getattr(self, name) < 1:
                raise ConfigError(f"{name} must be at least 1, got {getattr(self, name)}")
        if max(self.batch_size, self.replay_init, self.concurrent_hands) > self.replay_size:
            raise ConfigError(
                "batch_size, replay_init and concurrent_hands must not exceed replay_size"
            )
        if not self.learning_rate > 0 or not 0 <= self.gamma <= 1:
            raise ConfigError("learning_rate must be positive and gamma in [0, 1]")
        if not (0 <= self.epsilon_start <= 1 and 0 <= self.epsilon_end <= 1):
            raise ConfigError(
                f"epsilon_start and epsilon_end must lie in [0, 1], got {self.epsilon_start} "
                f"and {self.epsilon_end}"
            )
        if not self.hidden or min(self.hidden) < 1:
            raise ConfigError(f"hidden must be positive layer sizes, got {self.hidden}")


@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    """One training run: what to learn from, against whom, for how long, how to evaluate.

    ``reward``: ``sparse`` (the payoff at the end of a hand) or ``learned`` (f_θ of
    ``reward_run``, a run folder or ``authors:FILE``, after ``reward_transform`` over the
    legal actions, mixed with the payoff by ``payoff_weight``; ``raise_counts`` says which
    raise counts f reads). ``opponent``: an agent spec
    (:func:`pokerirl.agents.resolve_agent`) or ``self``. The evaluation plays ``eval_hands``
    duplicate hands of seed ``eval_seed`` every ``eval_every`` training hands and at the end;
    ``protocol="authors"`` evaluates and keeps a checkpoint as the authors do (see the module
    docstring), and ``play`` says which checkpoint the agent plays.
    """

    hands: int = setting(help="Training hands.", flags=("--hands", "-n"), max=MAX_STEPS)
    seed: int
    # A member after __post_init__; `| str`: callers may name it (the studies do).
    reward: RewardMode | str = setting(
        RewardMode.SPARSE, help="sparse (the payoff) or learned (--reward-run's f).",
        show_default=True,
    )  # fmt: skip
    reward_run: str | None = setting(
        None, help="AIRL / H-AIRL run folder, or authors:FILE (one of the authors' rewards).",
        metavar="REWARD",
    )  # fmt: skip
    payoff_weight: float = setting(
        0.0, help="w in r = w * payoff + (1 - w) * f(s, a); 0: the learned reward alone."
    )
    opponent: str = setting(
        "random", metavar="AGENT|self|pool",
        help="random (default), raise, call, tightbot, loosebot, an agent folder, rlcard:CKPT "
        "(unpickled: runs any code it holds; trusted files only), self, or pool (each hand "
        "against one of random, call, raise, tightbot, loosebot or, for half of the hands once "
        "there are some, one of the learner's 4 latest snapshots).",
    )  # fmt: skip
    eval_every: int = setting(
        10_000, help="Evaluate every N training hands.", max=MAX_STEPS
    )
    eval_hands: int = setting(
        20_000, help="Hands per evaluation (even, duplicate).", max=MAX_STEPS
    )
    eval_seed: int = setting(1_000_003, help="Deal seed of every evaluation.")
    dqn: DQNConfig = field(default_factory=DQNConfig)
    reward_transform: Transform | str = setting(  # as reward
        Transform.RAW, show_default=True,
        help="raw (f), centered (f minus its mean over legal actions), log_softmax (f minus "
        "its logsumexp over legal actions) or advantage (f minus its max over legal actions, "
        "floored at -10; docs/rewards.md).",
    )  # fmt: skip
    raise_counts: RaiseCounts = setting(
        RaiseCounts.DECISION, show_default=True,
        help="decision (f reads the raise counts of the decision) or end-of-hand (those the "
        "hand ended with, as the authors' agent read RLCard's live list).",
    )  # fmt: skip
    protocol: TrainingProtocol = setting(
        TrainingProtocol.POKERIRL,
        help="pokerirl (duplicate evaluations) or authors (their evaluation and kept model).",
    )
    play: Plays = setting(
        Plays.FINAL,
        help="final or kept (the authors' > 0.8 x best checkpoint; needs --protocol authors).",
    )
    encoding: EncodingName = setting(  # what the q-network reads (pokerirl.game.encodings)
        EncodingName.RLCARD, show_default=True,
        help="What the q-network reads: rlcard (RLCard's 72-d observation) or strength (hole "
        "and board apart, with hand features). The reward reads its own run's encoding.",
    )  # fmt: skip

    def __post_init__(self) -> None:
        for name, kind in _ENUM_FIELDS.items():  # a file's or a flag's string, as its member
            object.__setattr__(self, name, enum_value(name, kind, getattr(self, name)))
        check_bounds(self)
        if self.reward == RewardMode.SPARSE and self.reward_run is not None:
            raise ConfigError("reward_run needs reward 'learned'")
        if self.reward == RewardMode.SPARSE and self.payoff_weight != 0.0:
            raise ConfigError("payoff_weight needs reward 'learned'")
        if not 0.0 <= self.payoff_weight <= 1.0:
            raise ConfigError(f"payoff weight must be in [0, 1], got {self.payoff_weight}")
        if self.hands < 1 or self.eval_every < 1:
            raise ConfigError("hands and eval_every must be at least 1")
        if self.seed < 0 or self.eval_seed < 0:
            raise ConfigError("seeds must be non-negative")
        duplicate = self.protocol == TrainingProtocol.POKERIRL
        if self.eval_hands < 2 or (duplicate and self.eval_hands % 2):
            raise ConfigError(f"eval_hands must be even and at least 2, got {self.eval_hands}")
        if self.reward == RewardMode.SPARSE and (
            self.reward_transform != Transform.RAW or self.raise_counts != RaiseCounts.DECISION
        ):
            raise ConfigError("reward_transform and raise_counts need reward 'learned'")
        if self.play == Plays.KEPT and self.protocol != TrainingProtocol.AUTHORS:
            raise ConfigError("play 'kept' needs protocol 'authors' (its kept checkpoint)")


_ENUM_FIELDS: dict[str, type[StrEnum]] = {
    name: kind
    for name, hint in typing.get_type_hints(TrainConfig).items()
    for kind in typing.get_args(hint) or (hint,)
    if isinstance(kind, type) and issubclass(kind, StrEnum)
}
AUTHORS_DQN = DQNConfig(
    learning_rate=5e-4,
    train_every=1,
    epsilon_end=0.0,
    epsilon_decay_steps=5_000,
    concurrent_hands=1,  # one hand at a time, as RLCard plays (evaluation points fall on it)
)
AGENT_PRESETS: dict[str, TrainConfig] = {
    # Ours: 50,000 hands, RLCard's constructor defaults but train_every 16 (docs/agents.md).
    "default": TrainConfig(hands=50_000, seed=0),
    # The authors' train_rl.py (silue-dev/hairl) with their DQNAgent subclass's settings:
    # lr 5e-4, train_every 1, epsilon 1 -> 0 over 5,000 steps; batch 32, replay 20,000,
    # target every 1,000 updates and MLP [64, 64] are RLCard's constructor defaults, as ours.
    "authors": TrainConfig(
        hands=5_000,
        seed=0,
        eval_every=100,
        eval_hands=1_000,
        protocol=TrainingProtocol.AUTHORS,
        play=Plays.KEPT,
        dqn=AUTHORS_DQN,
    ),
}


def agent_preset(name: str, **overrides: Any) -> TrainConfig:
    """The preset ``name`` (:data:`AGENT_PRESETS`), then ``overrides`` (None values ignored);
    ``dqn`` overrides may be a dict of fields (over the preset's)."""
    dqn = overrides.pop("dqn", None)
    if isinstance(dqn, Mapping):
        base = with_overrides(AGENT_PRESETS, name, what="agent preset").dqn
        dqn = dataclasses.replace(base, **dqn)
    return with_overrides(AGENT_PRESETS, name, what="agent preset", dqn=dqn, **overrides)


_TRAIN_KEYS = {f.name: f.type for f in dataclasses.fields(TrainConfig) if f.name != "dqn"}
_DQN_KEYS = {f.name: f.type for f in dataclasses.fields(DQNConfig)}


def _typed(key: str, hint: str, value: Any) -> Any:
    """``value`` if it fits the field's annotation (as a string: ``from __future__``)."""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if hint == "int" and isinstance(value, int) and not isinstance(value, bool):
        return value
    if hint == "float" and number:
        return float(value)
    if hint.startswith("str") and (isinstance(value, str) or (value is None and "None" in hint)):
        return value
    if key in _ENUM_FIELDS and isinstance(value, str):  # TrainConfig checks the name
        return value
    if hint.startswith("tuple") and isinstance(value, list) and value:
        if all(isinstance(w, int) and not isinstance(w, bool) for w in value):
            return tuple(value)
    kind = {"int": "an integer", "float": "a number", "tuple[int, ...]": "a list of integers"}
    raise ConfigError(f"{key} must be {kind.get(hint, 'a string')}")


@dataclass(frozen=True, kw_only=True)
class AgentOverrides:
    """Training settings over an agent preset: fields of :class:`TrainConfig` (``train``) and of
    :class:`~pokerirl.agents.dqn.DQNConfig` (``dqn``).

    >>> file = AgentOverrides(train={"hands": 500}, dqn={"train_every": 2})
    >>> config = file.with_flags(train={"hands": None}, dqn={"train_every": 4}).config("default")
    >>> config.hands, config.dqn.train_every
    (500, 4)
    """

    train: Mapping[str, Any] = field(default_factory=dict)
    dqn: Mapping[str, Any] = field(default_factory=dict)

    def with_flags(self, *, train: Mapping[str, Any], dqn: Mapping[str, Any]) -> AgentOverrides:
        """These settings under ``train`` and ``dqn`` (command-line flags: None values unset)."""
        return AgentOverrides(
            train={**self.train, **{k: v for k, v in train.items() if v is not None}},
            dqn={**self.dqn, **{k: v for k, v in dqn.items() if v is not None}},
        )

    def config(self, preset: str, *, seed: int | None = None) -> TrainConfig:
        """:func:`agent_preset` ``preset`` with these settings."""
        return agent_preset(preset, seed=seed, dqn=dict(self.dqn), **self.train)


def load_agent_config(path: str | os.PathLike[str]) -> AgentOverrides:
    """A TOML file of training settings as :func:`agent_preset` overrides: flat keys, any
    field of :class:`TrainConfig` (``hands``, ``eval_every``, ...) or of
    :class:`~pokerirl.agents.dqn.DQNConfig` (``learning_rate``, ``train_every``, ...).

    Raises :class:`~pokerirl.errors.ConfigError` of one line naming the file and the key.
    """
    import tomllib

    path = Path(path)
    try:
        settings = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"config file not found: {path}") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise ConfigError(f"cannot read {path} as TOML: {error}") from None
    train: dict[str, object] = {}
    dqn: dict[str, object] = {}
    for key, value in settings.items():
        hint = _TRAIN_KEYS.get(key) or _DQN_KEYS.get(key)
        if hint is None or key == "seed":
            known = sorted({*_TRAIN_KEYS, *_DQN_KEYS} - {"seed"})
            raise ConfigError(f"{path}: unknown setting {key!r} (known: {', '.join(known)})")
        try:
            checked = _typed(key, str(hint), value)
        except ValueError as error:
            raise ConfigError(f"{path}: {error}, got {value!r}") from None
        (dqn if key in _DQN_KEYS else train)[key] = checked
    return AgentOverrides(train=train, dqn=dqn)


