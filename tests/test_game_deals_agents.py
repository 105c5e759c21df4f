"""Replayable deals and the built-in agents."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from pokerirl.game import Agent, deal_cards, make_agent
from pokerirl.game.deals import DEAL_BLOCK
from pokerirl.holdem import CALL, CHECK, FOLD, RAISE


def test_deal_depends_only_on_seed_and_index() -> None:
    whole = deal_cards(seed=5, start=0, count=3 * DEAL_BLOCK)
    for start, count in [
        (0, 1),
        (DEAL_BLOCK - 3, 7),
        (2 * DEAL_BLOCK + 11, 100),
        (17, 2 * DEAL_BLOCK),
    ]:
        np.testing.assert_array_equal(
            deal_cards(seed=5, start=start, count=count), whole[start : start + count]
        )
    np.testing.assert_array_equal(deal_cards(seed=5, start=0, count=50), whole[:50])
    assert (deal_cards(seed=6, start=0, count=50) != whole[:50]).any()


def test_deals_are_nine_distinct_uniform_cards() -> None:
    deals = deal_cards(seed=1, start=0, count=40_000).astype(np.int64)
    assert deals.min() >= 0 and deals.max() <= 51
    assert (np.sort(deals, axis=1)[:, 1:] != np.sort(deals, axis=1)[:, :-1]).all()
    for position in range(9):  # every position is uniform over the 52 cards
        counts = np.bincount(deals[:, position], minlength=52)
        assert stats.chisquare(counts).pvalue > 1e-4
    # Hole cards of the two seats are exchangeable: seat 0 is not dealt better cards.
    high = deals % 13 == 0  # aces
    assert abs(high[:, :2].mean() - high[:, 2:4].mean()) < 0.01


def test_deal_arguments_are_checked() -> None:
    with pytest.raises(ValueError):
        deal_cards(seed=-1, start=0, count=1)
    assert deal_cards(seed=1, start=0, count=0).shape == (0, 9)


MASKS = np.array(
    [
        [True, True, True, False],  # facing a bet
        [False, True, True, True],  # level
        [True, False, True, False],  # facing a bet at the raise cap
        [False, False, True, True],  # level at the raise cap
    ]
)


def test_built_in_agents_follow_their_rules() -> None:
    rng = np.random.default_rng(0)
    obs = np.zeros((4, 72), dtype=np.uint8)
    assert make_agent("raise").act(obs, MASKS, rng).tolist() == [RAISE, RAISE, CALL, CHECK]
    assert make_agent("call").act(obs, MASKS, rng).tolist() == [CALL, CHECK, CALL, CHECK]
    for name in ("random", "raise", "call"):
        agent = make_agent(name)
        assert isinstance(agent, Agent) and agent.name == name
        actions = agent.act(obs, MASKS, rng)
        assert actions.dtype == np.int64 and MASKS[np.arange(4), actions].all()


def test_random_agent_is_uniform_over_legal_actions_and_seeded() -> None:
    agent = make_agent("random")
    masks = np.repeat(MASKS, 20_000, axis=0)
    actions = agent.act(None, masks, np.random.default_rng(1)).reshape(4, -1)
    for row, mask in enumerate(MASKS):
        counts = np.bincount(actions[row], minlength=4)
        assert (counts[~mask] == 0).all()
        assert stats.chisquare(counts[mask]).pvalue > 1e-4
    again = agent.act(None, masks, np.random.default_rng(1)).reshape(4, -1)
    np.testing.assert_array_equal(actions, again)
    assert FOLD in actions[0]


def test_unknown_agent_is_a_value_error() -> None:
    known = "call, fold, loosebot, raise, random, tightbot"
    with pytest.raises(ValueError, match=f"unknown agent .dqn. .built-in agents: {known}"):
        make_agent("dqn")
