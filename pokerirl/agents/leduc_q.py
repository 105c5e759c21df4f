"""A tabular agent for Leduc hold'em: every-visit Monte-Carlo control over information sets,
against a fixed opponent strategy, on the batch engine. Numpy only, seeded.

Against a fixed opponent the agent faces a single-agent problem whose states are its
information sets (perfect recall: the key holds its own past actions), so sample-average
returns under a decaying ε-greedy policy move its greedy strategy towards a best response to
that opponent under the reward it is given. The reward is either ``sparse`` (the chips won at
the end of the hand, on every decision of the hand) or a table of per-decision rewards
``r[row, action]`` (a learned f(s, a): the return of a decision is the sum of r over the
agent's decisions from it on). Self-play is not offered: a tabular learner against a moving
copy of itself need not converge, and the study asks what each reward makes of the same
opponent.

>>> from pokerirl.game.leduc.rules import RLCARD
>>> from pokerirl.game.leduc.strategy import uniform_strategy
>>> agent = train_q(RLCARD, uniform_strategy(RLCARD), config=QConfig(hands=2000, seed=0))
>>> len(agent.strategy()) == 288, agent.q.shape
(True, (288, 4))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.leduc.batch import LeducBatch
from pokerirl.game.leduc.infosets import InfoSets, info_sets
from pokerirl.game.leduc.rules import LeducRules
from pokerirl.game.leduc.strategy import Strategy

MAX_HANDS = 100_000_000


@dataclass(frozen=True, kw_only=True)
class QConfig:
    """Training length and exploration: ε falls linearly from ``epsilon_start`` to
    ``epsilon_end`` over the hands; hands are played ``batch`` at a time."""

    hands: int = 200_000
    batch: int = 2_000
    epsilon_start: float = 0.5
    epsilon_end: float = 0.02
    seed: int = 0

    def __post_init__(self) -> None:
        epsilons = 0 <= self.epsilon_end <= self.epsilon_start <= 1
        if not (1 <= self.hands <= MAX_HANDS and self.batch >= 1 and epsilons and self.seed >= 0):
            raise ConfigError(
                f"invalid Q-learning settings: need 1 <= hands <= {MAX_HANDS:,}, batch >= 1, "
                "0 <= epsilon_end <= epsilon_start <= 1, seed >= 0"
            )


@dataclass(frozen=True, kw_only=True, eq=False)
class TabularAgent:
    """A trained table: ``q`` (rows x 4, :class:`InfoSets` rows; -inf where illegal) and how
    often each pair was visited."""

    sets: InfoSets
    q: np.ndarray
    visits: np.ndarray

    def strategy(self) -> dict[str, dict[str, float]]:
        """The greedy strategy (unvisited actions count 0)."""
        return self.sets.greedy(np.where(self.visits > 0, self.q, 0.0))


def train_q(
    rules: LeducRules,
    opponent: Strategy,
    *,
    config: QConfig,
    reward: np.ndarray | None = None,
) -> TabularAgent:
    """Train against ``opponent`` (the agent sits in position ``hand % 2``) on the sparse
    reward (``reward`` None) or on ``reward[row, action]`` per decision."""
    sets = reward_sets(rules, reward)
    cumulative = opponent_table(rules, opponent)
    rng = np.random.default_rng(config.seed)
    q = np.zeros(sets.legal.shape)
    visits = np.zeros(sets.legal.shape, dtype=np.int64)
    def values(rows: np.ndarray) -> np.ndarray:
        return np.where(visits[rows] > 0, q[rows], 0.0)  # unvisited actions count 0

    played = 0
    while played < config.hands:
        hands = min(config.batch, config.hands - played)
        share = played / max(config.hands - 1, 1)
        epsilon = config.epsilon_start + (config.epsilon_end - config.epsilon_start) * share

        seat = (np.arange(hands) + played) % 2
        batch, hand, row, action = play_batch(
            rules, cumulative, seat=seat, rng=rng, epsilon=epsilon, values=values
        )
        if reward is None:
            returns = batch.payoffs()[hand, seat[hand]]
        else:  # the reward from this decision on: its hand's total minus what came before
            step = reward[row, action]
            total = np.bincount(hand, step, minlength=hands)
            before = np.zeros(len(step))
            order = np.argsort(hand, kind="stable")  # play order kept within a hand
            cum = np.cumsum(step[order])
            start = np.concatenate(([0.0], np.cumsum(np.bincount(hand, step, minlength=hands))))
            before[order] = cum - step[order] - start[hand[order]]
            returns = total[hand] - before
        np.add.at(visits, (row, action), 1)
        sums = np.zeros(q.shape)
        counts = np.zeros(q.shape)
        np.add.at(sums, (row, action), returns)
        np.add.at(counts, (row, action), 1)
        seen = counts > 0
        q[seen] += (sums[seen] - counts[seen] * q[seen]) / visits[seen]  # running means
        played += hands
    return TabularAgent(sets=sets, q=np.where(sets.legal, q, -np.inf), visits=visits)


def reward_sets(rules: LeducRules, reward: np.ndarray | None) -> InfoSets:
    """The information sets of ``rules``; a ``ConfigError`` if ``reward`` (a per-decision
    table, or None for the sparse reward) is not one value per set and action."""
    sets = info_sets(rules)
    if reward is not None and reward.shape != sets.legal.shape:
        raise ConfigError(f"a reward table must be {sets.legal.shape}, got {reward.shape}")
    return sets


def opponent_table(rules: LeducRules, opponent: Strategy) -> np.ndarray:
    """rows x 4: ``opponent``'s cumulative probabilities, what :func:`play_batch` samples."""
    return np.cumsum(info_sets(rules).probabilities(opponent), axis=1)


def play_batch(
    rules: LeducRules, cumulative: np.ndarray, *, seat: np.ndarray, rng: np.random.Generator,
    epsilon: float, values: Callable[[np.ndarray], np.ndarray],
) -> tuple[LeducBatch, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Deal ``len(seat)`` hands and play them to the end: the agent, in ``seat[hand]``, is
    ε-greedy on ``values(rows)`` (rows x 4 at its information sets' rows; ties to the first
    legal action), the opponent samples ``cumulative`` (:func:`opponent_table`). Returns the
    finished batch and the agent's decisions in play order: hand, row, action."""
    sets = info_sets(rules)
    batch = LeducBatch.dealt(rules, len(seat), rng)
    taken: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # hand, row, action
    while not batch.over.all():
        live = np.flatnonzero(~batch.over)
        rows = sets.rows_of(batch.node[live], batch.cards[live])
        mine = batch.to_act[live] == seat[live]
        legal = sets.legal[rows]
        draw = rng.random(len(live))  # the agent's exploring and the opponent's sampling
        explore = rng.random((len(live), legal.shape[1])) * legal
        greedy = np.full(legal.shape, -np.inf)
        greedy[mine] = np.where(legal[mine], values(rows[mine]), -np.inf)
        agent = np.where(draw[:, None] < epsilon, explore, greedy).argmax(axis=1)
        table = cumulative[rows]
        sampled = np.minimum((table <= draw[:, None] * table[:, -1:]).sum(axis=1), 3)
        choice = np.where(mine, agent, sampled)
        taken.append((live[mine], rows[mine], choice[mine]))
        actions = np.zeros(len(seat), dtype=np.int64)
        actions[live] = choice
        batch.step(actions)
    hand, row, action = (np.concatenate(c) for c in zip(*taken, strict=True))
    return batch, hand, row, action
