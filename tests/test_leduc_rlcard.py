"""Our Leduc engine under RLCard's rules against RLCard 1.2.0's ``leduc-holdem`` itself,
decision by decision: the observation, the legal actions and the payoffs of random hands.

RLCard deals, seats the small blind at random and steps; we read its deal (the two hands, the
card its dealer pops next for the board, the small blind's seat) and replay the same actions.
The 100,000-hand check of issue 42 is the slow test (and ``benchmarks/leduc.py`` times it)."""

from __future__ import annotations

import numpy as np
import pytest

from pokerirl.game.leduc import RLCARD, Action, deal

# RLCard's action ids (LeducholdemEnv.actions) and card ids (its deck's order: SJ HJ SQ HQ ...)
RLCARD_ACTIONS = (Action.CALL, Action.RAISE, Action.FOLD, Action.CHECK)
RLCARD_CARDS = {"SJ": 0, "HJ": 1, "SQ": 2, "HQ": 3, "SK": 4, "HK": 5}


def replay(hands: int, seed: int) -> int:
    """Play ``hands`` random hands through RLCard and ours; return the decisions compared."""
    import rlcard  # the environments only (rlcard.agents would run pip freeze)

    env = rlcard.make("leduc-holdem", config={"seed": seed})
    rng = np.random.default_rng(seed)
    decisions = 0
    for _ in range(hands):
        state, player = env.reset()
        game = env.game
        small = player  # the small blind acts first
        seats = (small, 1 - small)  # position -> RLCard's player id
        cards = tuple(RLCARD_CARDS[c.get_index()] for c in (
            game.players[seats[0]].hand, game.players[seats[1]].hand, game.dealer.deck[-1],
        ))  # fmt: skip
        ours = deal(RLCARD, cards=(cards[0], cards[1], cards[2]))
        while not env.is_over():
            position = seats.index(player)
            assert ours.to_act == position
            np.testing.assert_array_equal(ours.observation(position), state["obs"])
            legal = [RLCARD_ACTIONS.index(a) for a in ours.legal_actions()]
            assert sorted(legal) == sorted(state["legal_actions"])
            move = int(rng.choice(legal))
            state, player = env.step(move)
            ours = ours.step(RLCARD_ACTIONS[move])
            decisions += 1
        assert ours.is_over
        payoffs = env.get_payoffs()
        for position, seat in enumerate(seats):
            assert payoffs[seat] * RLCARD.env_chips_per_unit == ours.payoffs()[position]
    return decisions


def test_two_thousand_hands_match_rlcard_decision_by_decision() -> None:
    assert replay(2_000, seed=0) > 4_000


@pytest.mark.slow
def test_a_hundred_thousand_hands_match_rlcard() -> None:
    assert replay(100_000, seed=1) > 200_000
