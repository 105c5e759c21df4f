"""A DQN for Leduc hold'em against a fixed opponent strategy, on the batch engine: what the
Leduc study's RL stage trains (the tabular :mod:`pokerirl.agents.leduc_q` stays beside it).

The Q-network is the poker DQN's :class:`~pokerirl.agents.dqn.QNetwork` (a tanh MLP, no input
norm) over :func:`features`: RLCard's 36-d observation of the information set (private and
public card ranks, both positions' chips) followed by a one-hot of the public betting node.
The observation alone aliases the 288 sets of RLCard's rules into 84 (it holds the chips, not
the order of the bets); with the node every set has its own vector (under OpenSpiel's rules
the suits of a key are not observed, as in the study's IRL). Hands are played ``batch`` at a
time (:func:`~pokerirl.agents.leduc_q.play_batch`: one forward pass per decision step over
the hands where the agent acts), ε-greedy with ε falling linearly over the hands; each
finished hand's transitions go to a replay memory (a ring buffer of information-set rows);
after each batch, ``updates`` Adam steps on minibatches with the Huber loss on double-DQN
targets (γ = 1: a hand is short), the target network copied every ``target_every`` steps.

Rewards, as :func:`~pokerirl.agents.leduc_q.train_q`: ``sparse`` (the chips won, on the
agent's last decision of the hand) or a table ``r[row, action]`` paid on every decision.
Seeded: numpy draws the deals, the exploration and the minibatches, torch (one thread) the
initial weights: the same seed gives the same bytes.

>>> from pokerirl.game.leduc.rules import RLCARD
>>> from pokerirl.game.leduc.strategy import uniform_strategy
>>> config = LeducDQNConfig(hands=1000, batch=500, updates=2, seed=0)
>>> agent = train_leduc_dqn(RLCARD, uniform_strategy(RLCARD), config=config)
>>> len(agent.strategy()) == 288, agent.q.shape
(True, (288, 4))
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pokerirl.agents.leduc_q import MAX_HANDS, opponent_table, play_batch, reward_sets
from pokerirl.errors import ConfigError
from pokerirl.game.leduc.batch import node_arrays
from pokerirl.game.leduc.infosets import InfoSets, info_sets
from pokerirl.game.leduc.rules import LeducRules
from pokerirl.game.leduc.strategy import Strategy

TURNS = 4  # a position's decisions in a hand at most: two a round (a bet, then a call or raise)


@dataclass(frozen=True, kw_only=True)
class LeducDQNConfig:
    """Training length (``hands``, played ``batch`` at a time), ``updates`` gradient steps of
    ``minibatch`` transitions after each batch, the replay ``memory``, the network, Adam's
    ``lr``, the target network's period."""

    hands: int = 100_000
    batch: int = 1_000
    updates: int = 25
    minibatch: int = 512
    memory: int = 100_000
    hidden: tuple[int, ...] = (64, 64)
    lr: float = 1e-3
    target_every: int = 50
    epsilon_start: float = 0.5
    epsilon_end: float = 0.05
    seed: int = 0

    def __post_init__(self) -> None:
        epsilons = 0 <= self.epsilon_end <= self.epsilon_start <= 1
        counts = min(self.batch, self.updates, self.minibatch, self.memory, self.target_every)
        if not (1 <= self.hands <= MAX_HANDS and counts >= 1 and epsilons and self.lr > 0
                and self.seed >= 0 and self.hidden and min(self.hidden) >= 1):  # fmt: skip
            raise ConfigError(
                f"invalid Leduc DQN settings: need 1 <= hands <= {MAX_HANDS:,}, batch, updates, "
                "minibatch, memory, target_every and hidden widths >= 1, lr > 0, "
                "0 <= epsilon_end <= epsilon_start <= 1, seed >= 0"
            )


@dataclass(frozen=True, kw_only=True, eq=False)
class DQNAgent:
    """A trained DQN, as the table of its final network's values: ``q`` (rows x 4,
    :class:`InfoSets` rows; -inf where illegal), and how often each pair was played."""

    sets: InfoSets
    q: np.ndarray
    visits: np.ndarray

    def strategy(self) -> dict[str, dict[str, float]]:
        """The greedy strategy over every information set."""
        return self.sets.greedy(self.q)


def features(rules: LeducRules) -> np.ndarray:
    """rows x (36 + decision nodes): each information set's observation and betting node."""
    sets = info_sets(rules)
    actor = node_arrays(rules).actor
    decisions = np.flatnonzero(actor >= 0)
    node = np.zeros(len(sets.keys), dtype=np.int64)
    for column, i in enumerate(decisions):
        node[np.unique(sets.node_rows[i])] = column  # a set's rows all sit at one node
    return np.concatenate([sets.observations, np.eye(len(decisions))[node]], axis=1)


def train_leduc_dqn(
    rules: LeducRules,
    opponent: Strategy,
    *,
    config: LeducDQNConfig,
    reward: np.ndarray | None = None,
) -> DQNAgent:
    """Train against ``opponent`` (the agent sits in position ``hand % 2``) on the sparse
    reward (``reward`` None) or on ``reward[row, action]`` per decision."""
    import torch

    from pokerirl.agents.dqn import QNetwork, double_dqn_targets
    from pokerirl.execution import pinned_threads

    sets = reward_sets(rules, reward)
    # Returns within [-1, 1], where the Huber loss is the squared error: fitted to the mean
    # return, not (as |error| far out would) to the median of chips that swing by ±13.
    if reward is None:
        scale = float(node_arrays(rules).chips.max())
    else:
        scale = float(np.abs(reward[sets.legal]).max() * TURNS) or 1.0
    cumulative = opponent_table(rules, opponent)
    rng = np.random.default_rng(config.seed)
    inputs = torch.as_tensor(features(rules), dtype=torch.float32)
    legal = torch.as_tensor(sets.legal)
    with pinned_threads(1), torch.random.fork_rng(devices=[]):
        torch.manual_seed(config.seed)
        network = QNetwork(hidden=config.hidden, obs_size=inputs.shape[1], input_norm=False)
        target = QNetwork(hidden=config.hidden, obs_size=inputs.shape[1], input_norm=False)
        target.load_state_dict(network.state_dict())
        optimizer = torch.optim.Adam(network.parameters(), lr=config.lr)
        memory = _Memory(config.memory)
        visits = np.zeros(sets.legal.shape, dtype=np.int64)

        def values(rows: np.ndarray) -> np.ndarray:
            with torch.no_grad():
                return network(inputs[rows]).double().numpy()

        played = steps = 0
        while played < config.hands:
            hands = min(config.batch, config.hands - played)
            share = played / max(config.hands - 1, 1)
            epsilon = config.epsilon_start + (config.epsilon_end - config.epsilon_start) * share
            seat = (np.arange(hands) + played) % 2
            batch, hand, row, action = play_batch(
                rules, cumulative, seat=seat, rng=rng, epsilon=epsilon, values=values
            )
            np.add.at(visits, (row, action), 1)
            order = np.argsort(hand, kind="stable")  # each hand's decisions in play order
            hand, row, action = hand[order], row[order], action[order]
            last = np.append(hand[1:] != hand[:-1], True)
            if reward is None:
                paid = np.where(last, batch.payoffs()[hand, seat[hand]], 0.0) / scale
            else:
                paid = reward[row, action] / scale
            memory.add(row, action, paid, np.where(last, -1, np.roll(row, -1)))
            for _ in range(config.updates):
                s, a, r, s2 = (torch.as_tensor(x) for x in memory.sample(config.minibatch, rng))
                done = s2 < 0
                nxt = inputs[s2.clamp(min=0)]
                with torch.no_grad():
                    y = double_dqn_targets(
                        rewards=r.float(), done=done, next_legal=legal[s2.clamp(min=0)],
                        q_next_online=network(nxt), q_next_target=target(nxt), gamma=1.0,
                    )  # fmt: skip
                q = network(inputs[s]).gather(1, a[:, None])[:, 0]
                loss = torch.nn.functional.smooth_l1_loss(q, y)
                optimizer.zero_grad()
                loss.backward()
                optimizer.step()
                steps += 1
                if steps % config.target_every == 0:
                    target.load_state_dict(network.state_dict())
            played += hands
        with torch.no_grad():
            table = network(inputs).double().numpy()
    return DQNAgent(sets=sets, q=np.where(sets.legal, table, -np.inf), visits=visits)


class _Memory:
    """A ring buffer of transitions (row, action, reward, next row or -1 at a hand's end)."""

    def __init__(self, size: int) -> None:
        self.row = np.zeros(size, dtype=np.int64)
        self.action = np.zeros(size, dtype=np.int64)
        self.reward = np.zeros(size)
        self.next = np.zeros(size, dtype=np.int64)
        self.size, self.filled, self.at = size, 0, 0

    def add(self, row: np.ndarray, action: np.ndarray, reward: np.ndarray,
            nxt: np.ndarray) -> None:  # fmt: skip
        row, action, reward, nxt = (x[-self.size:] for x in (row, action, reward, nxt))
        where = (self.at + np.arange(len(row))) % self.size
        self.row[where], self.action[where] = row, action
        self.reward[where], self.next[where] = reward, nxt
        self.at = int((self.at + len(row)) % self.size)
        self.filled = min(self.filled + len(row), self.size)

    def sample(self, n: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        pick = rng.integers(0, self.filled, size=n)
        return self.row[pick], self.action[pick], self.reward[pick], self.next[pick]
