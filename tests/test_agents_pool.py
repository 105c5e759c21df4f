"""The pool opponent (``--opponent pool``): a mixture of fixed strategies and the learner's
latest snapshots, one member per hand."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pokerirl.agents.config import POOL_SNAPSHOTS, POOL_STRATEGIES, DQNConfig, Opponent
from pokerirl.agents.dqn import DQNLearner, Rivals, train_dqn
from pokerirl.errors import ConfigError


def _rivals() -> tuple[Rivals, DQNLearner]:
    torch.manual_seed(0)
    learner = DQNLearner.create(DQNConfig(concurrent_hands=64, replay_init=32))
    return Rivals.of(Opponent.POOL, learner, seed=3), learner


def test_the_pool_deals_every_fixed_strategy_then_half_the_hands_to_snapshots() -> None:
    rivals, learner = _rivals()
    assert [agent.name for agent in rivals.members] == list(POOL_STRATEGIES)
    rivals.deal(5_000)
    counts = np.bincount(rivals.member, minlength=len(POOL_STRATEGIES))
    assert counts.min() > 850 and counts.max() < 1_150  # about 1,000 each
    for _ in range(POOL_SNAPSHOTS + 2):
        rivals.snapshot(learner)
    assert len(rivals.snapshots) == 0  # snapshots join at the next batch, not mid-batch
    rivals.deal(10_000)
    assert len(rivals.snapshots) == POOL_SNAPSHOTS  # the oldest left
    on_snapshots = (rivals.member >= len(POOL_STRATEGIES)).mean()
    assert 0.47 < on_snapshots < 0.53


def test_split_groups_the_hands_by_rival_and_covers_them_once() -> None:
    rivals, learner = _rivals()
    rivals.snapshot(learner)
    rivals.deal(200)
    hands = np.arange(0, 200, 3)
    groups = rivals.split(hands)
    assert sorted(np.concatenate([h for _, h in groups]).tolist()) == hands.tolist()
    for agent, group in groups:
        assert {rivals.members[k].name for k in rivals.member[group]} == {agent.name}
    assert rivals.split(np.zeros(0, np.int64)) == []


def test_a_pool_trained_learner_differs_from_one_trained_against_random() -> None:
    from pokerirl.game import make_agent

    config = DQNConfig(concurrent_hands=64, replay_init=32, self_play_every=5)
    weights = {}
    for opponent in ("pool", make_agent("random")):
        learner = train_dqn(config, hands=512, seed=0, opponent=opponent)
        weights[str(opponent)[:4]] = torch.cat([p.flatten() for p in learner.q_net.parameters()])
    first, second = weights.values()
    assert not torch.equal(first, second)


def test_an_unknown_opponent_name_is_one_line() -> None:
    with pytest.raises(ConfigError, match="'self' or 'pool'"):
        train_dqn(DQNConfig(), hands=10, seed=0, opponent="pol")
