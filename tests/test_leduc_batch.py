"""The batch of Leduc hands against the one-hand engine (itself replayed against RLCard in
tests/test_leduc_rlcard.py): the same random hands, action by action."""

from __future__ import annotations

import numpy as np
import pytest

from pokerirl.errors import ConfigError
from pokerirl.game.engine import IllegalActionError
from pokerirl.game.leduc import OPENSPIEL, RLCARD, LeducRules, deal
from pokerirl.game.leduc.batch import ACTIONS, LeducBatch


@pytest.mark.parametrize("rules", [RLCARD, OPENSPIEL], ids=["rlcard", "openspiel"])
def test_the_batch_plays_as_the_engine_hand_by_hand(rules: LeducRules) -> None:
    rng = np.random.default_rng(0)
    batch = LeducBatch.dealt(rules, 1_500, rng)
    states = [deal(rules, cards=(a, b, c)) for a, b, c in batch.cards.tolist()]
    steps = 0
    while not batch.over.all():
        legal = batch.legal()
        for hand, state in enumerate(states):
            assert legal[hand].tolist() == [a in state.legal_actions() for a in ACTIONS]
            assert batch.to_act[hand] == (-1 if state.is_over else state.to_act)
        live = ~batch.over
        observed = batch.observations(np.where(live, batch.to_act, 0))
        for hand in np.flatnonzero(live)[:200]:
            np.testing.assert_array_equal(
                observed[hand], states[hand].observation(states[hand].to_act)
            )
        actions = (rng.random(legal.shape) * legal).argmax(axis=1)
        batch.step(actions)
        states = [
            s if s.is_over else s.step(ACTIONS[a]) for s, a in zip(states, actions, strict=True)
        ]
        steps += 1
    assert steps >= 6  # some hands reach the second round's re-raise
    assert batch.payoffs().tolist() == [list(map(float, s.payoffs())) for s in states]


def test_the_batch_refuses_bad_cards_and_illegal_actions() -> None:
    with pytest.raises(ConfigError, match="different cards"):
        LeducBatch(RLCARD, cards=np.array([[0, 0, 1]]))
    batch = LeducBatch(OPENSPIEL, cards=np.array([[0, 1, 2]]))
    with pytest.raises(IllegalActionError, match="illegal"):
        batch.step(np.array([ACTIONS.index(ACTIONS[0])]))  # no fold when nothing is faced
