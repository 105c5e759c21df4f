"""``action_probs`` on every agent (pokerirl/game/bots.py, pokerirl/agents/dqn.py): a
distribution over the legal actions, and the very one ``act`` draws from."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.errors import ConfigError
from pokerirl.game.bots import BUILT_IN_AGENTS, PolicyAgent, agent_action_probs, make_agent
from pokerirl.game.deals import deal_cards
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import play_match, turn_cards
from pokerirl.holdem import CALL, CHECK, FOLD


def _states(count: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Observations, legal masks and cards of decisions on every street (random play)."""
    game = LimitHoldemBatch(deals=deal_cards(seed=9, start=0, count=count))
    rng, random = np.random.default_rng(0), make_agent("random")
    obs, legal, cards = [], [], []
    while game.active().size:
        hands = game.active()
        obs.append(game.observe(hands))
        legal.append(game.legal_mask(hands))
        cards.append(turn_cards(game, hands))
        game.step(random.act(obs[-1], legal[-1], rng), hands)
    return np.concatenate(obs), np.concatenate(legal), np.concatenate(cards)


def _q_agent(epsilon: float = 0.0) -> GreedyQAgent:
    torch.manual_seed(1)
    return GreedyQAgent(name="q", network=QNetwork(hidden=(8,)).eval(), epsilon=epsilon)


AGENTS = {**{name: make_agent(name) for name in BUILT_IN_AGENTS}, "dqn": _q_agent(),
          "dqn-epsilon": _q_agent(0.3)}  # fmt: skip


@pytest.mark.parametrize("name", sorted(AGENTS))
def test_action_probs_is_a_distribution_over_the_legal_actions(name: str) -> None:
    agent = AGENTS[name]
    assert isinstance(agent, PolicyAgent)
    obs, legal, cards = _states()
    probs = agent_action_probs(agent, obs, legal, cards)
    assert probs.shape == (len(obs), 4) and probs.dtype == np.float64
    assert (probs[~legal] == 0).all() and (probs >= 0).all()
    np.testing.assert_allclose(probs.sum(axis=1), 1.0, rtol=1e-12)


@pytest.mark.parametrize("name", sorted(AGENTS))
def test_act_draws_from_action_probs(name: str) -> None:
    agent = AGENTS[name]
    obs, legal, cards = _states(60)
    probs = agent_action_probs(agent, obs, legal, cards)
    repeats = 3000
    tiled = [np.repeat(a, repeats, axis=0) for a in (obs, legal, cards)]
    rng = np.random.default_rng(4)
    if getattr(agent, "sees_cards", False):
        actions = agent.act(tiled[0], tiled[1], rng, cards=tiled[2])
    else:
        actions = agent.act(tiled[0], tiled[1], rng)
    counts = np.zeros((len(obs), 4))
    np.add.at(counts, (np.repeat(np.arange(len(obs)), repeats), actions), 1)
    frequency = counts / repeats
    # Five standard errors of a frequency at most; 0 and 1 exactly for what cannot happen.
    error = np.sqrt(probs * (1 - probs) / repeats)
    assert (np.abs(frequency - probs) <= 5 * error + 1e-12).all()


def test_the_fold_agent_folds_even_when_checking_is_free() -> None:
    mask = np.array([[False, True, True, True], [True, True, True, False]])
    fold = make_agent("fold")
    assert fold.act(np.zeros((2, 72), np.uint8), mask, np.random.default_rng(0)).tolist() == [
        FOLD,
        FOLD,
    ]
    # It gives up its blind in every hand: 1 chip as small blind, 2 as big blind.
    result = play_match(make_agent("call"), fold, hands=1000, seed=0)
    assert result.mbb_per_hand == 750.0 and result.std_error == 0.0


def test_greedy_draws_nothing_and_epsilon_is_checked() -> None:
    agent, obs, legal = _q_agent(), *_states(50)[:2]
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state
    agent.act(obs, legal, rng)
    assert rng.bit_generator.state == before  # a greedy match plays as before epsilon existed
    probs = agent.action_probs(obs, legal)
    assert set(np.unique(probs)) == {0.0, 1.0}
    assert (probs.argmax(axis=1) == agent.act(obs, legal, rng)).all()
    with pytest.raises(ConfigError, match="epsilon must lie in"):
        dataclasses.replace(agent, epsilon=1.5)


def test_an_agent_without_action_probs_is_refused_in_one_line() -> None:
    class Blind:
        name = "blind"

        def act(self, obs, legal_mask, rng):
            return np.where(legal_mask[:, CALL], CALL, CHECK)

    with pytest.raises(ConfigError, match="'blind' has no action_probs"):
        agent_action_probs(Blind(), np.zeros((1, 72)), np.ones((1, 4), bool))
