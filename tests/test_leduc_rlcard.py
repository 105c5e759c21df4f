"""Our Leduc engine under RLCard's rules against RLCard 1.2.0's ``leduc-holdem`` itself,
decision by decision: the observation, the legal actions and the payoffs of random hands
(:func:`~pokerirl.game.leduc.interop.replay_rlcard`). The 100,000-hand check of issue 42 is
``benchmarks/leduc.py`` (about 20 s of one core): 2,000 hands here, 20,000 in the slow test."""

from __future__ import annotations

from dataclasses import replace

import pytest

from pokerirl.game.leduc import interop
from pokerirl.game.leduc.rules import OPENSPIEL, RLCARD, SecondRound


def test_two_thousand_hands_match_rlcard_decision_by_decision() -> None:
    assert interop.replay_rlcard(2_000, seed=0) > 4_000


def test_the_replay_tells_rules_that_differ(monkeypatch: pytest.MonkeyPatch) -> None:
    # OpenSpiel's first player opens the second round; RLCard's alternates.
    wrong = replace(RLCARD, second_round=SecondRound.FIRST)
    monkeypatch.setattr(interop, "RLCARD", wrong)
    with pytest.raises(interop.Mismatch):
        interop.replay_rlcard(200, seed=0)
    monkeypatch.setattr(interop, "RLCARD", replace(RLCARD, chips_before=OPENSPIEL.chips_before))
    with pytest.raises(interop.Mismatch):
        interop.replay_rlcard(200, seed=0)


@pytest.mark.slow
def test_twenty_thousand_more_hands_match_rlcard() -> None:
    assert interop.replay_rlcard(20_000, seed=1) > 40_000
