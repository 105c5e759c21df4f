"""The Leduc DQN (pokerirl/agents/leduc_dqn.py): the same seed gives the same bytes, it learns
what its reward asks against a fixed strategy, and the study's ``rl`` setting is checked."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from pokerirl.agents.leduc_dqn import LeducDQNConfig, features, train_leduc_dqn
from pokerirl.cli import app
from pokerirl.errors import ConfigError
from pokerirl.game.leduc import RLCARD, expected_value
from pokerirl.game.leduc.batch import ACTIONS
from pokerirl.game.leduc.infosets import info_sets, pure
from pokerirl.game.leduc.rules import Action
from pokerirl.game.leduc.strategy import uniform_strategy
from pokerirl.studies.leduc.study import RLKind, preset

SMALL = LeducDQNConfig(hands=1_000, batch=500, updates=4, minibatch=64, seed=3)
CALLER = pure(RLCARD, {Action.CALL: 2, Action.CHECK: 1})  # calls, checks when nothing is faced


def test_every_information_set_has_its_own_features() -> None:
    # The 36-d observation alone maps the 288 sets to 84 vectors (it holds chips, not bets).
    found = features(RLCARD)
    assert found.shape[0] == 288 and len(np.unique(found, axis=0)) == 288


def test_the_same_seed_gives_the_same_bytes() -> None:
    first, again = (train_leduc_dqn(RLCARD, CALLER, config=SMALL) for _ in range(2))
    assert first.q.tobytes() == again.q.tobytes()
    other = train_leduc_dqn(RLCARD, CALLER, config=LeducDQNConfig(**{**vars(SMALL), "seed": 4}))
    assert other.q.tobytes() != first.q.tobytes()


def test_the_sparse_reward_beats_a_calling_station() -> None:
    # A best response to always-call wins 1.47 chips per hand, the uniform strategy loses 1.17
    # and always-call itself breaks even (all exact); with the payoff's sign or seat wrong the
    # DQN learns to lose. 15,000 hands get 0.8 to 1.1 (seeds 0 to 2).
    config = LeducDQNConfig(hands=15_000, batch=500, updates=20, minibatch=128, seed=0)
    agent = train_leduc_dqn(RLCARD, CALLER, config=config)
    uniform = expected_value(RLCARD, uniform_strategy(RLCARD), CALLER).mean
    assert uniform < -1 and expected_value(RLCARD, agent.strategy(), CALLER).mean > 0.5


def test_a_per_decision_reward_is_followed() -> None:
    # A reward that pays for raising and nothing else: the greedy DQN raises wherever it may
    # at the sets it played (ε explores beyond its own raises; at sets it never reached, its
    # values are the network's guesses: 80% raise there).
    sets = info_sets(RLCARD)
    reward = np.zeros(sets.legal.shape)
    reward[:, ACTIONS.index(Action.RAISE)] = 1.0
    config = LeducDQNConfig(hands=5_000, batch=500, updates=20, minibatch=128, seed=1)
    agent = train_leduc_dqn(RLCARD, CALLER, config=config, reward=reward)
    played = agent.visits.sum(axis=1) > 0
    can_raise = played & sets.legal[:, ACTIONS.index(Action.RAISE)]
    assert can_raise.sum() >= 20
    assert (agent.q.argmax(axis=1)[can_raise] == ACTIONS.index(Action.RAISE)).all()
    with pytest.raises(ConfigError, match="reward table"):
        train_leduc_dqn(RLCARD, CALLER, config=SMALL, reward=reward[:10])


def test_the_study_rl_setting_is_checked() -> None:
    assert preset("quick").rl == RLKind.DQN and preset("quick").rl_hands == 100_000
    assert preset("quick", rl="tabular").rl_hands == 500_000  # the tabular figures' setting
    with pytest.raises(ConfigError, match="unknown RL agent 'nope'"):
        preset("quick", rl="nope")
    result = CliRunner().invoke(app, ["leduc", "study", "--out", "x", "--rl", "nope"])
    errors = result.stderr.splitlines()
    assert result.exit_code == 2 and len(errors) == 1 and errors[0].startswith("error: "), errors
