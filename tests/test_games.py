"""The Game protocol (pokerirl.game.games): hold'em and Leduc play through it by the rules each
engine already checks against RLCard, their payoffs match what the evaluator and the exact
Leduc values say, and Leduc's information-set keys are the tree's sets."""

from __future__ import annotations

import numpy as np
import pytest

from pokerirl.game.engine import IllegalActionError
from pokerirl.game.evaluator import seven_card_strengths
from pokerirl.game.games import (
    HOLDEM,
    Choose,
    Game,
    Hands,
    LeducGame,
    play_out,
    uniform_legal,
)
from pokerirl.game.leduc.exact import expected_value
from pokerirl.game.leduc.infosets import info_sets
from pokerirl.game.leduc.rules import OPENSPIEL, RLCARD
from pokerirl.game.leduc.strategy import uniform_strategy
from pokerirl.game.spec import GameName

GAMES: dict[str, Game] = {
    "holdem": HOLDEM,
    "leduc-rlcard": LeducGame(RLCARD),
    "leduc-openspiel": LeducGame(OPENSPIEL),
}


@pytest.mark.parametrize("name", sorted(GAMES))
def test_each_game_plays_legal_zero_sum_seeded_hands(name: str) -> None:
    game = GAMES[name]
    assert isinstance(game, Game)
    def checked(chosen: Choose) -> Choose:
        def choose(h: Hands, live: np.ndarray) -> np.ndarray:
            legal = h.legal_mask(live)
            assert legal.shape == (live.size, len(game.actions)) and legal.any(axis=1).all()
            assert set(h.actors(live).tolist()) <= {0, 1}
            assert h.observe(live).shape == (live.size, game.table_spec().width)
            return chosen(h, live)

        return choose

    runs = []
    for _ in range(2):
        hands = game.deal(hands=500, seed=3)
        assert isinstance(hands, Hands) and hands.size == 500
        runs.append(play_out(hands, checked(uniform_legal(np.random.default_rng(1)))))
    payoffs = runs[0]
    assert np.array_equal(runs[0], runs[1])  # same seed, same bytes
    assert np.all(payoffs.sum(axis=1) == 0) and np.any(payoffs != 0)
    assert hands.active().size == 0


@pytest.mark.parametrize("name", sorted(GAMES))
def test_an_illegal_action_is_refused_and_nothing_is_played(name: str) -> None:
    hands = GAMES[name].deal(hands=4, seed=0)
    live = hands.active()
    legal = hands.legal_mask(live)
    illegal = np.argmin(legal, axis=1)  # hold'em and Leduc both forbid check facing a bet
    assert not legal[np.arange(4), illegal].any()
    before = hands.infoset_keys(live)
    with pytest.raises(IllegalActionError):
        hands.step(illegal, live)
    assert np.array_equal(hands.infoset_keys(live), before)


def test_holdem_all_call_hands_are_won_by_the_better_seven_cards() -> None:
    hands = HOLDEM.deal(hands=2_000, seed=5)
    call, check = HOLDEM.actions.index("call"), HOLDEM.actions.index("check")

    def passive(h: Hands, live: np.ndarray) -> np.ndarray:
        return np.where(h.legal_mask(live)[:, check], check, call)

    payoffs = play_out(hands, passive)
    cards = hands.batch.cards.astype(np.int64)  # type: ignore[attr-defined]
    first = seven_card_strengths(np.concatenate([cards[:, 0:2], cards[:, 4:]], axis=1))
    second = seven_card_strengths(np.concatenate([cards[:, 2:4], cards[:, 4:]], axis=1))
    # The small blind calls, then both check to the showdown: a pot of one big blind each.
    assert np.array_equal(payoffs[:, 0], np.sign(first - second).astype(np.float64))


@pytest.mark.parametrize("rules", [RLCARD, OPENSPIEL], ids=["rlcard", "openspiel"])
def test_leduc_random_play_averages_to_the_exact_value(rules) -> None:  # type: ignore[no-untyped-def]
    payoffs = play_out(LeducGame(rules).deal(hands=200_000, seed=2),
                       uniform_legal(np.random.default_rng(4)))  # fmt: skip
    exact = expected_value(rules, uniform_strategy(rules), uniform_strategy(rules)).first
    se = payoffs[:, 0].std(ddof=1) / np.sqrt(len(payoffs))
    assert abs(payoffs[:, 0].mean() - exact) < 4 * se, (payoffs[:, 0].mean(), exact, se)


def test_leduc_keys_are_every_information_set_and_fix_what_the_actor_sees() -> None:
    game = LeducGame(RLCARD)
    hands = game.deal(hands=100_000, seed=0)
    choose = uniform_legal(np.random.default_rng(0))
    seen: dict[str, tuple[bytes, bytes]] = {}
    while (live := hands.active()).size:
        keys = hands.infoset_keys(live)
        views = hands.observe(live)
        legal = hands.legal_mask(live)
        for key, view, mask in zip(keys.tolist(), views, legal, strict=True):
            found = (view.tobytes(), mask.tobytes())
            assert seen.setdefault(key, found) == found, key
        hands.step(choose(hands, live), live)
    assert set(seen) == set(info_sets(RLCARD).keys)
    assert game.name is GameName.LEDUC and game.table_spec().game is GameName.LEDUC


def test_holdem_keys_are_what_rlcard_observes() -> None:
    hands = HOLDEM.deal(hands=50, seed=1)
    live = hands.active()
    keys = hands.infoset_keys(live)
    views = hands.observe(live)
    same = keys[:, None] == keys[None, :]
    assert np.array_equal(same, (views[:, None, :] == views[None, :, :]).all(axis=2))
    assert HOLDEM.unit == "big blinds" and HOLDEM.table_spec().width == 72
