"""Double DQN on the vectorized engine, modelled on RLCard 1.2.0's ``DQNAgent``.

The whole algorithm is :func:`train_dqn`, read top to bottom: it plays ``concurrent_hands``
hands in lock-step against an opponent, makes one batched forward pass for all hands where
the learner is to act, stores finished transitions in a replay memory and does one gradient
update per ``train_every`` stored transitions (RLCard's ``train_every``; see
:class:`DQNConfig` for why ours is not 1).

Rewards, per learner decision ``(s, a)`` (``reward_fn`` is f_θ, ``w`` the payoff weight):

* sparse (``reward_fn=None``): the hand's payoff in big blinds on the last decision, else 0;
* learned: ``(1 - w) * f(s, a)`` at every decision, plus ``w * payoff`` on the last one.
  ``f`` sees the state as it was at the decision, or, with ``raise_counts="end-of-hand"``,
  with the raise counts the hand ended with (what the authors' reward read: RLCard's live
  ``raise_nums`` list after the hand); then a hand's transitions are stored when it ends.

>>> import torch; _ = torch.manual_seed(0)
>>> from pokerirl.game import make_agent
>>> config = DQNConfig(concurrent_hands=64, replay_init=32)
>>> learner = train_dqn(config, hands=256, seed=0, opponent=make_agent("random"))
>>> learner.total_t > 256, learner.train_t == (learner.total_t - 32) // 16 + 1
(True, True)
"""

from __future__ import annotations

import copy
import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn
from tqdm import tqdm

from pokerirl.agents.config import (
    POOL_SNAPSHOTS,
    POOL_STRATEGIES,
    SELF_PLAY,
    DQNConfig,
    Opponent,
)
from pokerirl.errors import ConfigError
from pokerirl.execution import unit_progress
from pokerirl.game.bots import Agent, RandomAgent, agent_actions, make_agent
from pokerirl.game.deals import DEAL_BLOCK, deal_cards
from pokerirl.game.encodings import RLCARD, Encoding, EncodingName, RawStates, get_encoding
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import agent_encoding, observe, turn_cards
from pokerirl.holdem import NUM_ACTIONS, OBS_SIZE
from pokerirl.poker.rewards import RAISE_COUNTS, ObservedDecisions, PokerReward, as_poker_reward

RewardFn = Callable[[np.ndarray, np.ndarray], np.ndarray] | PokerReward
"""A learned reward: f(obs (B, 72) uint8, actions (B,) int64) -> (B,) float rewards, or a
:class:`pokerirl.poker.rewards.PokerReward` (which may read the cards and legal actions)."""



TRAIN_STREAM = 2  # spawn-key word of the trainer's randomness (deals use 0, match agents 1)
POOL_STREAM = 1  # second word: the pool's draws of each hand's rival


class QNetwork(nn.Module):
    """RLCard's ``EstimatorNetwork``: batch norm of the input, tanh MLP, one value per action.

    The same layers as RLCard (less its no-op ``Flatten``), so its checkpoints load here.
    ``obs_size`` is the width of the encoding it reads (RLCard's 72 by default);
    ``input_norm`` False leaves out the batch norm (an identity in its place). Encodings other
    than RLCard's go without it: their features are already scaled, and batch statistics of
    their rare one-hot columns over 32 samples swing so much that a q-network fitted through
    them agrees with its own reward's argmax on 42% of states, against 95% without (issue 31).

    >>> QNetwork(hidden=(8,))(torch.zeros(3, 72)).shape
    torch.Size([3, 4])
    """

    def __init__(
        self, *, hidden: tuple[int, ...] = (64, 64), obs_size: int = OBS_SIZE,
        input_norm: bool = True,
    ) -> None:  # fmt: skip
        super().__init__()
        sizes = (obs_size, *hidden)
        self.norm: nn.Module = nn.BatchNorm1d(obs_size) if input_norm else nn.Identity()
        layers: list[nn.Module] = []
        for fan_in, fan_out in itertools.pairwise(sizes):
            layers += [nn.Linear(fan_in, fan_out), nn.Tanh()]
        layers.append(nn.Linear(sizes[-1], NUM_ACTIONS))
        self.mlp = nn.Sequential(*layers)
        for parameter in self.parameters():  # RLCard: Xavier for weights, default biases
            if parameter.dim() > 1:
                nn.init.xavier_uniform_(parameter)
        self.eval()  # as RLCard: eval mode (batch norm's running statistics) except in updates

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.mlp(self.norm(obs))


def input_norm(encoding: Encoding) -> bool:
    """Whether a q-network on ``encoding`` normalizes its input: RLCard's network does (and
    its checkpoints hold the statistics); the scaled encodings go without (see QNetwork)."""
    return encoding.name == EncodingName.RLCARD


def greedy_actions(q_values: torch.Tensor, legal_mask: torch.Tensor) -> torch.Tensor:
    """Argmax of the q-values over the legal actions only (rows with none legal give 0).

    >>> q, legal = torch.tensor([[5.0, 1.0, 2.0, 0.0]]), torch.tensor([[False, True, True, True]])
    >>> greedy_actions(q, legal)
    tensor([2])
    """
    return q_values.masked_fill(~legal_mask, -torch.inf).argmax(dim=1)


def double_dqn_targets(
    *,
    rewards: torch.Tensor,
    done: torch.Tensor,
    next_legal: torch.Tensor,
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    gamma: float,
) -> torch.Tensor:
    """Double DQN targets with illegal next actions masked out.

    ``y = r`` for a terminal transition, else ``y = r + γ Q_target(s', argmax_{legal a'}
    Q_online(s', a'))``: the online network picks among the legal actions of ``s'``, the
    target network values the pick.

    >>> double_dqn_targets(rewards=torch.tensor([1.0, 2.0]), done=torch.tensor([False, True]),
    ...     next_legal=torch.tensor([[False, True, True, True]] * 2),
    ...     q_next_online=torch.tensor([[9.0, 1.0, 3.0, 2.0]] * 2),
    ...     q_next_target=torch.tensor([[0.0, 10.0, 20.0, 30.0]] * 2), gamma=0.5)
    tensor([11.,  2.])
    """
    best = greedy_actions(q_next_online, next_legal)
    bootstrap = q_next_target.gather(1, best[:, None])[:, 0]
    return torch.where(done, rewards, rewards + gamma * bootstrap)


def epsilon_at(config: DQNConfig, step: int) -> float:
    """RLCard's schedule: linear from ``epsilon_start`` to ``epsilon_end``, then constant.

    >>> [round(epsilon_at(DQNConfig(), t), 3) for t in (0, 19_999, 50_000)]
    [1.0, 0.1, 0.1]
    """
    fraction = min(step, config.epsilon_decay_steps - 1) / max(config.epsilon_decay_steps - 1, 1)
    return config.epsilon_start + fraction * (config.epsilon_end - config.epsilon_start)


@dataclass(kw_only=True)
class ReplayMemory:
    """A ring buffer of transitions in preallocated arrays (RLCard drops the oldest, too);
    states are stored as ``encoding`` makes them (RLCard's: 72 uint8)."""

    capacity: int
    encoding: Encoding = RLCARD
    obs: np.ndarray = field(init=False, repr=False)
    actions: np.ndarray = field(init=False, repr=False)
    rewards: np.ndarray = field(init=False, repr=False)
    next_obs: np.ndarray = field(init=False, repr=False)
    next_legal: np.ndarray = field(init=False, repr=False)
    done: np.ndarray = field(init=False, repr=False)
    size: int = 0
    position: int = 0  # where the next transition goes

    def __post_init__(self) -> None:
        width, dtype = self.encoding.width, self.encoding.dtype
        self.obs = np.zeros((self.capacity, width), dtype)
        self.actions = np.zeros(self.capacity, np.int64)
        self.rewards = np.zeros(self.capacity, np.float32)
        self.next_obs = np.zeros((self.capacity, width), dtype)
        self.next_legal = np.zeros((self.capacity, NUM_ACTIONS), bool)
        self.done = np.zeros(self.capacity, bool)

    def add(
        self,
        obs: np.ndarray,
        actions: np.ndarray,
        rewards: np.ndarray,
        next_obs: np.ndarray,
        next_legal: np.ndarray,
        done: bool | np.ndarray,
    ) -> None:
        """Store n transitions (n may exceed what is left before wrapping, not the capacity)."""
        stop = self.position + len(actions)
        # A slice where the rows do not wrap (most adds): a copy, not a scatter.
        slots = (slice(self.position, stop) if stop <= self.capacity else
                 np.arange(self.position, stop) % self.capacity)  # fmt: skip
        self.obs[slots], self.actions[slots], self.rewards[slots] = obs, actions, rewards
        self.next_obs[slots], self.next_legal[slots], self.done[slots] = next_obs, next_legal, done
        self.position = int((self.position + len(actions)) % self.capacity)
        self.size = min(self.size + len(actions), self.capacity)

    def sample(self, rng: np.random.Generator, batch_size: int) -> dict[str, torch.Tensor]:
        """A uniform minibatch (with replacement; RLCard samples without, a negligible gap)."""
        index = rng.integers(0, self.size, batch_size)
        return {
            "obs": torch.from_numpy(self.obs[index]).float(),
            "actions": torch.from_numpy(self.actions[index]),
            "rewards": torch.from_numpy(self.rewards[index]),
            "next_obs": torch.from_numpy(self.next_obs[index]).float(),
            "next_legal": torch.from_numpy(self.next_legal[index]),
            "done": torch.from_numpy(self.done[index]),
        }


@dataclass(frozen=True, kw_only=True)
class GreedyQAgent:
    """The engine's agent protocol over a q-network: argmax over legal actions, batched.

    ``fingerprint`` identifies the weights (e.g. the sha256 of a saved agent's files);
    ``encoding`` names what the network reads (the engine builds its observations so).
    ``epsilon`` (default 0, greedy): with that probability a uniformly random legal action
    instead, as RLCard's epsilon-greedy ``step`` (``dataclasses.replace(agent, epsilon=e)``).
    """

    name: str
    network: QNetwork = field(repr=False)
    fingerprint: str = ""
    encoding: str = EncodingName.RLCARD
    epsilon: float = 0.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.epsilon <= 1.0:
            raise ConfigError(f"epsilon must lie in [0, 1], got {self.epsilon}")

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """(B, 4) q-values of (B, width) observations, all actions (legal or not)."""
        with torch.inference_mode():
            return self.network(torch.from_numpy(np.asarray(obs)).float()).numpy()

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        q = torch.from_numpy(self.q_values(obs))
        greedy = greedy_actions(q, torch.from_numpy(np.asarray(legal_mask, bool))).numpy()
        if self.epsilon == 0.0:  # greedy: draws nothing, so matches are as before epsilon
            return greedy
        explore = rng.random(len(greedy)) < self.epsilon
        uniform = RandomAgent().act(obs, legal_mask, rng)
        return np.where(explore, uniform, greedy)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        """(B, 4) float64: 1 on the greedy legal action (with ``epsilon``: ``1 - epsilon``
        plus ``epsilon`` spread evenly over the legal actions), 0 elsewhere."""
        legal = np.asarray(legal_mask, bool)
        q = torch.from_numpy(self.q_values(obs))
        greedy = greedy_actions(q, torch.from_numpy(legal)).numpy()
        probs = np.zeros(legal.shape)
        probs[np.arange(len(greedy)), greedy] = 1.0 - self.epsilon
        if self.epsilon:
            probs += self.epsilon * legal / legal.sum(axis=1, keepdims=True)
        return probs


@dataclass(kw_only=True)
class DQNLearner:
    """What training changes: networks, optimizer, replay memory and counters (as RLCard)."""

    config: DQNConfig
    q_net: QNetwork
    target_net: QNetwork
    optimizer: torch.optim.Optimizer
    replay: ReplayMemory
    total_t: int = 0  # transitions stored (RLCard's total_t)
    train_t: int = 0  # gradient updates done (RLCard's train_t)
    last_loss: float = float("nan")

    encoding: Encoding = RLCARD

    @classmethod
    def create(cls, config: DQNConfig, encoding: Encoding = RLCARD) -> DQNLearner:
        """Fresh networks on ``encoding``'s states (seed torch first for reproducible
        weights)."""
        q_net = QNetwork(hidden=config.hidden, obs_size=encoding.width,
                         input_norm=input_norm(encoding))  # fmt: skip
        return cls(
            config=config,
            q_net=q_net,
            target_net=copy.deepcopy(q_net),
            # Fused (CPU support since torch 2.4): one kernel for all parameters, cheaper.
            optimizer=torch.optim.Adam(
                q_net.parameters(), lr=config.learning_rate, fused=torch.__version__ >= "2.4"
            ),
            replay=ReplayMemory(capacity=config.replay_size, encoding=encoding),
            encoding=encoding,
        )

    def greedy_agent(self, name: str = "dqn") -> GreedyQAgent:
        """A frozen greedy copy of the current q-network."""
        return GreedyQAgent(name=name, network=copy.deepcopy(self.q_net).eval(),
                            encoding=self.encoding.spec)  # fmt: skip

    def update(self, rng: np.random.Generator) -> float:
        """One gradient step on a replay minibatch; copies the target network like RLCard."""
        config = self.config
        batch = self.replay.sample(rng, config.batch_size)
        with torch.no_grad():
            targets = double_dqn_targets(
                rewards=batch["rewards"],
                done=batch["done"],
                next_legal=batch["next_legal"],
                q_next_online=self.q_net(batch["next_obs"]),
                q_next_target=self.target_net(batch["next_obs"]),
                gamma=config.gamma,
            )
        self.q_net.norm.train()  # only batch norm differs between modes; the cheap switch
        q_taken = self.q_net(batch["obs"]).gather(1, batch["actions"][:, None])[:, 0]
        loss = nn.functional.mse_loss(q_taken, targets)
        self.optimizer.zero_grad()
        loss.backward()
        self.optimizer.step()
        self.q_net.norm.eval()
        # RLCard copies at train_t 0, 1000, ... (checked before counting this update).
        if self.train_t % config.target_update_every == 0:
            self.target_net.load_state_dict(self.q_net.state_dict())
        self.train_t += 1
        self.last_loss = loss.item()
        return self.last_loss

    def updates_due(self) -> int:
        """Updates owed to reach RLCard's count: one at total_t = init, init + k, init + 2k..."""
        ready = self.total_t - self.config.replay_init
        return max(0, ready // self.config.train_every + 1 - self.train_t) if ready >= 0 else 0


def train_dqn(
    config: DQNConfig,
    *,
    hands: int,
    seed: int,
    opponent: Agent | str,
    reward_fn: RewardFn | None = None,
    payoff_weight: float = 0.0,
    raise_counts: str = "decision",
    progress: bool = False,
    on_hands: Callable[[int, DQNLearner], None] | None = None,
    encoding: str | Encoding | None = None,
) -> DQNLearner:
    """Train a DQN for ``hands`` hands of the engine against ``opponent``; return the learner.

    Args:
        config: hyper-parameters.
        hands: training hands; the learner sits as small blind in even hands.
        seed: seeds torch (initial weights), the deals (``deal_cards(seed=seed)``), the
            exploration, the replay sampling and the opponent's draws.
        opponent: an engine agent; ``"self"``: a frozen greedy copy of the learner,
            refreshed every ``config.self_play_every`` updates; or ``"pool"``: each hand
            against one member of a mixture of fixed strategies and the learner's latest
            snapshots, taken every ``config.self_play_every`` updates (:class:`Rivals`).
        reward_fn: ``None`` for the sparse payoff; else f_θ, called once per lock-step on
            every learner decision of the step, with exactly the (obs, action) it took.
        payoff_weight: w in ``(1 - w) f(s, a) + w * payoff``; ignored when sparse.
        raise_counts: ``decision`` (f sees the decision's state) or ``end-of-hand`` (f sees
            the hand's final raise counts, and is called when the hand ends).
        progress: show a tqdm bar over hands on stderr.
        on_hands: called as ``on_hands(hands_done, learner)`` after every lock-step batch.
        encoding: what the q-network reads (:mod:`pokerirl.game.encodings`; default RLCard's
            72-d observation). The reward reads its own encoding, whatever this one is.
    """
    _check_training(hands=hands, payoff_weight=payoff_weight, opponent=opponent,
                    raise_counts=raise_counts)  # fmt: skip
    torch.manual_seed(seed)
    streams = np.random.SeedSequence(seed, spawn_key=(TRAIN_STREAM,)).spawn(2)
    rng, opponent_rng = (np.random.Generator(np.random.PCG64(s)) for s in streams)
    encoding = get_encoding(encoding)
    learner = DQNLearner.create(config, encoding)
    rivals = Rivals.of(opponent, learner, seed=seed)
    shaping = _Shaping.of(as_poker_reward(reward_fn), payoff_weight=payoff_weight,
                          raise_counts=raise_counts, encoding=encoding)  # fmt: skip
    deals = _Deals(seed=seed, chunk=max(config.concurrent_hands, DEAL_BLOCK))

    with tqdm(total=hands, unit="hand", unit_scale=True, disable=not progress) as bar:
        for start in range(0, hands, config.concurrent_hands):
            count = min(config.concurrent_hands, hands - start)
            game = LimitHoldemBatch(deals=deals.get(start, count))
            my_seat = ((start + np.arange(count)) % 2).astype(np.int8)
            rivals.deal(count)
            pending = _Pending(count, learner, _Staged() if shaping.at_end else None)
            while game.active().size:
                active = game.active()
                mine = game.to_act[active] == my_seat[active]
                learner_hands, rival_hands = active[mine], active[~mine]
                if learner_hands.size:
                    _learner_decides(game, learner_hands, learner=learner, shaping=shaping,
                                     pending=pending, rng=rng)  # fmt: skip
                for rival, hands_of_rival in rivals.split(rival_hands):
                    rival_obs = observe(game, hands_of_rival, agent_encoding(rival))
                    rival_legal = game.legal_mask(hands_of_rival)
                    cards_of = functools.partial(turn_cards, game, hands_of_rival)
                    game.step(
                        agent_actions(rival, rival_obs, rival_legal, opponent_rng, cards_of),
                        hands_of_rival,
                    )
                _close_ended(game, my_seat, pending, learner=learner, shaping=shaping)
                for _ in range(learner.updates_due()):
                    learner.update(rng)
                    if learner.train_t % config.self_play_every == 0:
                        rivals.snapshot(learner)
            bar.update(count)
            unit_progress(start + count, hands)  # the driver's bar, when this is a unit
            if on_hands is not None:
                on_hands(start + count, learner)
    return learner


@dataclass(frozen=True, kw_only=True)
class _Shaping:
    """What the learner's transitions are paid and what it must see: f (weighted) on each
    decision or staged to the hand's end, the payoff (scaled) when the hand ends."""

    reward: PokerReward | None  # None: the sparse payoff alone
    encoding: Encoding  # what the q-network reads
    decision_weight: float
    payoff_scale: float
    at_end: bool  # f called when the hand ends, on its final raise counts
    needs_cards: bool

    @classmethod
    def of(cls, reward: PokerReward | None, *, payoff_weight: float, raise_counts: str,
           encoding: Encoding) -> _Shaping:  # fmt: skip
        at_end = reward is not None and raise_counts == "end-of-hand"
        plain = encoding.name == EncodingName.RLCARD
        return cls(
            reward=reward,
            encoding=encoding,
            decision_weight=0.0 if reward is None else 1.0 - payoff_weight,
            payoff_scale=1.0 if reward is None else payoff_weight,
            at_end=at_end,
            needs_cards=at_end or (reward is not None and reward.needs_cards) or not plain,
        )

    @property
    def plain(self) -> bool:
        """The q-network reads RLCard's observation, the one rewards get."""
        return self.encoding.name == EncodingName.RLCARD


def _learner_decides(
    game: LimitHoldemBatch, hands: np.ndarray, *, learner: DQNLearner, shaping: _Shaping,
    pending: _Pending, rng: np.random.Generator,
) -> None:  # fmt: skip
    """The learner acts ε-greedily in ``hands``: its previous transitions there close on this
    state, the new ones open with f's share of their reward, and the engine steps."""
    encoding = shaping.encoding
    legal = game.legal_mask(hands)
    rewarded_now = shaping.reward is not None and pending.staged is None
    # RLCard's observation: what rewards get (another encoding's sparse learner needs none).
    plain_obs = game.observe(hands) if shaping.plain or rewarded_now else None
    cards = turn_cards(game, hands) if shaping.needs_cards else None
    encoded: dict[str, np.ndarray] = {}
    if shaping.plain:
        assert plain_obs is not None
        obs = plain_obs
    else:
        assert cards is not None  # a non-RLCard encoding reads the cards
        states = RawStates(cards=cards, raise_nums=game.raises[hands], legal_mask=legal)
        obs = encoded[encoding.spec] = encoding.encode(states)
    # This state closes the learner's previous transition in these hands.
    waiting = pending.waiting[hands]
    before = hands[waiting]
    pending.close(before, pending.reward[before], obs[waiting], legal[waiting], done=False)

    # Epsilon-greedy: uniform over legal actions with probability epsilon.
    epsilon = epsilon_at(learner.config, learner.total_t)
    with torch.no_grad():
        q = learner.q_net(torch.from_numpy(obs).float())
    actions = greedy_actions(q, torch.from_numpy(legal)).numpy()
    randomize = rng.random(actions.size) < epsilon
    actions[randomize] = RandomAgent().act(obs[randomize], legal[randomize], rng)

    rewards: np.ndarray = np.zeros(actions.size, np.float32)
    if pending.staged is not None:  # f comes when the hand ends
        assert cards is not None  # staging needs the cards (needs_cards)
        pending.staged.note(hands, cards, legal, actions)
    elif shaping.reward is not None:
        assert plain_obs is not None  # rewarded_now
        decisions = ObservedDecisions(obs=plain_obs, legal_mask=legal, cards=cards,
                                      encoded=encoded)  # fmt: skip
        rewards = shaping.decision_weight * shaping.reward(decisions, actions)
    pending.open(hands, obs, actions, rewards)
    game.step(actions, hands)


def _close_ended(
    game: LimitHoldemBatch, my_seat: np.ndarray, pending: _Pending, *, learner: DQNLearner,
    shaping: _Shaping,
) -> None:  # fmt: skip
    """Hands that just ended close the learner's last transition with the payoff."""
    ended = np.flatnonzero(game.done & pending.waiting)
    if not ended.size:
        return
    encoding = shaping.encoding
    payoff = game.payoffs[ended, my_seat[ended]].astype(np.float32)
    # A terminal state is never bootstrapped from: RLCard's observation of it, or zeros in
    # another encoding (not worth encoding).
    terminal = (game.observe(ended, my_seat[ended]) if shaping.plain else
                np.zeros((ended.size, encoding.width), encoding.dtype))  # fmt: skip
    pending.close(ended, pending.reward[ended] + shaping.payoff_scale * payoff, terminal,
                  np.zeros((ended.size, NUM_ACTIONS), bool), done=True)  # fmt: skip
    if pending.staged is not None:
        pending.staged.flush(ended, game.raises, shaping.reward, shaping.decision_weight,  # type: ignore[arg-type]
                             learner)  # fmt: skip


def _check_training(
    *, hands: int, payoff_weight: float, opponent: Agent | str, raise_counts: str
) -> None:
    """``train_dqn``'s arguments that no type checks, in one line each."""
    if hands < 1:
        raise ConfigError(f"hands must be at least 1, got {hands}")
    if not 0.0 <= payoff_weight <= 1.0:
        raise ConfigError(f"payoff weight must be in [0, 1], got {payoff_weight}")
    if isinstance(opponent, str) and opponent not in tuple(Opponent):
        names = " or ".join(repr(str(o)) for o in Opponent)
        raise ConfigError(f"opponent must be an agent, {names}, got {opponent!r}")
    if raise_counts not in RAISE_COUNTS:
        raise ConfigError(f"raise_counts must be one of {', '.join(RAISE_COUNTS)}")


@dataclass(kw_only=True)
class Rivals:
    """Who the learner plays in each hand of a lock-step batch.

    One agent (a fixed opponent, or ``self``: the learner's frozen greedy copy, replaced at
    each snapshot) plays every hand. ``pool``: each hand's rival is drawn when the batch is
    dealt: one of ``POOL_STRATEGIES`` uniformly, or, once the learner has snapshots, with
    probability ½ one of its ``POOL_SNAPSHOTS`` latest (uniformly). The draws come from a
    stream of their own, so a single opponent's games do not change.
    """

    fixed: tuple[Agent, ...]
    snapshots: list[Agent] = field(default_factory=list)
    replaces: bool = False  # self-play: a snapshot replaces the one rival
    pooled: bool = False
    rng: np.random.Generator | None = None
    member: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    joining: list[Agent] = field(default_factory=list)  # snapshots taken during a batch

    @classmethod
    def of(cls, opponent: Agent | str, learner: DQNLearner, *, seed: int) -> Rivals:
        if opponent == Opponent.POOL:
            stream = np.random.SeedSequence(seed, spawn_key=(TRAIN_STREAM, POOL_STREAM))
            fixed = tuple(make_agent(name) for name in POOL_STRATEGIES)
            return cls(fixed=fixed, pooled=True, rng=np.random.Generator(np.random.PCG64(stream)))
        if opponent == SELF_PLAY:
            return cls(fixed=(learner.greedy_agent("self"),), replaces=True)
        assert not isinstance(opponent, str)  # checked by _check_training
        return cls(fixed=(opponent,))

    @property
    def members(self) -> tuple[Agent, ...]:
        return (*self.fixed, *self.snapshots)

    def deal(self, count: int) -> None:
        """Draw the rival of each of a new batch's ``count`` hands."""
        if not self.pooled:
            self.member = np.zeros(count, np.int64)
            return
        assert self.rng is not None
        self.snapshots = [*self.snapshots, *self.joining][-POOL_SNAPSHOTS:]
        self.joining = []
        fixed = self.rng.integers(0, len(self.fixed), count)
        if not self.snapshots:
            self.member = fixed
            return
        snapshot = len(self.fixed) + self.rng.integers(0, len(self.snapshots), count)
        self.member = np.where(self.rng.random(count) < 0.5, snapshot, fixed)

    def split(self, hands: np.ndarray) -> list[tuple[Agent, np.ndarray]]:
        """``hands`` (indices into the batch) grouped by their rival, in member order."""
        if not hands.size:
            return []
        if len(self.members) == 1:
            return [(self.members[0], hands)]
        of_hand = self.member[hands]
        return [(agent, hands[of_hand == k]) for k, agent in enumerate(self.members)
                if (of_hand == k).any()]  # fmt: skip

    def snapshot(self, learner: DQNLearner) -> None:
        """After ``self_play_every`` updates: refresh ``self`` at once (as before pools), or
        take a snapshot for the pool, which joins it at the next batch (the oldest leaves past
        ``POOL_SNAPSHOTS``), so that the hands in play keep their rivals."""
        if self.replaces:
            self.fixed = (learner.greedy_agent("self"),)
        elif self.pooled:
            self.joining.append(learner.greedy_agent(f"snapshot-{learner.train_t}"))


@dataclass(kw_only=True)
class _Deals:
    """Deals of one seed, made ``chunk`` at a time: small lock-step batches (one hand at a
    time, as RLCard plays) then do not each pay for a block of deals."""

    seed: int
    chunk: int
    first: int = -1
    cards: np.ndarray = field(default_factory=lambda: np.zeros((0, 9), np.int8))

    def get(self, start: int, count: int) -> np.ndarray:
        if not (self.first <= start and start + count <= self.first + len(self.cards)):
            self.first = start
            self.cards = deal_cards(seed=self.seed, start=start, count=max(count, self.chunk))
        return self.cards[start - self.first : start - self.first + count]


class _Pending:
    """The learner's last decision in each hand of a batch, waiting for its next state."""

    def __init__(self, count: int, learner: DQNLearner, staged: _Staged | None) -> None:
        self.learner, self.staged = learner, staged
        self.waiting = np.zeros(count, bool)
        self.obs = np.zeros((count, learner.encoding.width), learner.encoding.dtype)
        self.action = np.zeros(count, np.int64)
        self.reward = np.zeros(count, np.float32)

    def open(self, hands: np.ndarray, obs: np.ndarray, actions: np.ndarray,
             rewards: np.ndarray) -> None:  # fmt: skip
        self.waiting[hands] = True
        self.obs[hands], self.action[hands], self.reward[hands] = obs, actions, rewards

    def close(self, hands: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray,
              next_legal: np.ndarray, *, done: bool) -> None:  # fmt: skip
        """Store the pending transitions of ``hands`` (now, or when they end)."""
        args = (self.obs[hands], self.action[hands], rewards, next_obs, next_legal)
        if self.staged is not None:
            self.staged.add(hands, *args, done=done)
        else:
            self.learner.replay.add(*args, done=done)
            self.learner.total_t += hands.size
        if done:
            self.waiting[hands] = False


class _Staged:
    """A batch's learner transitions held until their hand ends (``end-of-hand`` raise
    counts): each decision's cards, legal actions and action, and the closed transitions."""

    def __init__(self) -> None:
        self.decisions: list[tuple[np.ndarray, ...]] = []  # (hands, cards, legal, actions)
        # (hands, obs, action, reward, s', legal actions at s', done)
        self.closed: list[tuple[np.ndarray, ...]] = []

    def note(self, hands: np.ndarray, cards: np.ndarray, legal: np.ndarray,
             actions: np.ndarray) -> None:  # fmt: skip
        self.decisions.append((hands, cards, legal, actions))

    def add(self, hands: np.ndarray, obs: np.ndarray, actions: np.ndarray, rewards: np.ndarray,
            next_obs: np.ndarray, next_legal: np.ndarray, *, done: bool) -> None:  # fmt: skip
        self.closed.append((hands, obs, actions, rewards, next_obs, next_legal,
                            np.full(hands.size, done)))  # fmt: skip

    @staticmethod
    def _take(parts: list[tuple[np.ndarray, ...]], ended: np.ndarray
              ) -> tuple[list[np.ndarray], list[tuple[np.ndarray, ...]]]:  # fmt: skip
        """The rows of ``ended`` hands (by hand, then in play order), and the rest."""
        columns = [np.concatenate(column) for column in zip(*parts, strict=True)]
        hit = np.isin(columns[0], ended)
        order = np.flatnonzero(hit)[np.argsort(columns[0][hit], kind="stable")]
        rest = [tuple(c[~hit] for c in columns)] if (~hit).any() else []
        return [c[order] for c in columns], rest

    def flush(self, ended: np.ndarray, raises: np.ndarray, reward: PokerReward,
              weight: float, learner: DQNLearner) -> None:  # fmt: skip
        """Store the transitions of the ``ended`` hands, f read with their final raises."""
        (hands, cards, legal, actions), self.decisions = self._take(self.decisions, ended)
        (_, obs, taken, rewards, next_obs, next_legal, done), self.closed = self._take(
            self.closed, ended
        )
        states = RawStates(cards=cards, raise_nums=raises[hands], legal_mask=legal)
        decisions = ObservedDecisions(obs=RLCARD.encode(states), legal_mask=legal, cards=cards)
        f = reward(decisions, actions) if weight else np.zeros(len(actions), np.float32)
        learner.replay.add(obs, taken, rewards + weight * f, next_obs, next_legal, done=done)
        learner.total_t += len(taken)
