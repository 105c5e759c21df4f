"""The batched engine against RLCard 1.2.0's own ``LimitHoldemGame``, deal by deal (no mocks).

Every deal is played in both engines with the same actions; at every step the seat to act, the
legal actions and both players' observations must agree, and at the end the payoffs.
Every run plays 14,000 deals: 2,000 in the quick test and 12,000 in the slow one.
"""

from __future__ import annotations

import numpy as np
import pytest
import rlcard
from rlcard.games.base import Card
from rlcard.games.limitholdem.game import LimitHoldemGame

from pokerirl.game.deals import deal_cards
from pokerirl.game.engine import IllegalActionError, LimitHoldemBatch
from pokerirl.holdem import ACTIONS, CALL, CHECK, FOLD, NUM_ACTIONS, RAISE, rlcard_card_str

# Action weights (call, raise, fold, check), renormalised over the legal actions.
POLICIES = {
    "uniform": (1.0, 1.0, 1.0, 1.0),
    "aggressive": (1.0, 6.0, 0.2, 1.0),  # reaches the raise cap in every round
    "passive": (4.0, 1.0, 0.0, 4.0),  # never folds: many showdowns
    "always_raise": (1.0, 1e9, 0.0, 1.0),  # scripted: raise while legal, else call
    "call_down": (1.0, 0.0, 0.0, 1.0),  # scripted: call or check to showdown
    "check_fold": (0.0, 0.0, 1.0, 1e9),  # scripted: check if free, else fold
}


def _card(index: int) -> Card:
    text = rlcard_card_str(index)
    return Card(text[0], text[1])


def _rlcard_game(deal: np.ndarray, seed: int) -> tuple[LimitHoldemGame, int]:
    """RLCard's game set up to play ``deal``; returns it and the player id in seat 0 (the SB).

    A fresh game object per deal: ``init_game`` hands out its first state before it resets
    ``history_raise_nums`` (see ``test_rlcard_first_state_has_stale_raise_counts``).
    """
    game = LimitHoldemGame()
    game.np_random = np.random.RandomState(seed)  # RLCard draws the small blind's player id
    game.init_game()
    small_blind = game.game_pointer  # the small blind acts first preflop
    game.players[small_blind].hand = [_card(c) for c in deal[0:2]]
    game.players[1 - small_blind].hand = [_card(c) for c in deal[2:4]]
    game.dealer.deck = [_card(c) for c in deal[4:9][::-1]]  # deal_card() is deck.pop()
    return game, small_blind


def _play_both(deals: np.ndarray, policies: list[str], seed: int) -> None:
    env = rlcard.make("limit-holdem")  # only for its _extract_state, RLCard's obs encoder
    rng = np.random.default_rng(seed)
    ours = LimitHoldemBatch(deals=deals)
    games = [_rlcard_game(deal, seed + i) for i, deal in enumerate(deals)]
    weights = np.array([POLICIES[p] for p in policies])
    steps = 0
    while ours.active().size:
        hands = ours.active()
        mask = ours.legal_mask(hands)
        obs = [ours.observe(hands, np.full(hands.size, s)) for s in (0, 1)]
        actions = np.empty(hands.size, dtype=np.int64)
        for row, h in enumerate(hands):
            game, small_blind = games[h]
            assert not game.is_over()
            seat_of = {small_blind: 0, 1 - small_blind: 1}
            assert seat_of[game.game_pointer] == ours.to_act[h]
            rl_legal = sorted(ACTIONS.index(a) for a in game.get_legal_actions())
            assert rl_legal == np.flatnonzero(mask[row]).tolist(), (h, steps)
            for player in (0, 1):
                state = env._extract_state(game.get_state(player))
                np.testing.assert_array_equal(state["obs"], obs[seat_of[player]][row])
            w = weights[h] * mask[row]
            actions[row] = rng.choice(NUM_ACTIONS, p=w / w.sum())
            game.step(ACTIONS[actions[row]])
        ours.step(actions, hands)
        steps += 1
    for h, (game, small_blind) in enumerate(games):
        assert game.is_over()
        payoffs = game.get_payoffs()
        np.testing.assert_array_equal(
            ours.payoffs[h], [payoffs[small_blind], payoffs[1 - small_blind]]
        )
    assert steps <= 23  # 5 preflop actions at most, 6 on each later street


def _policies(n: int, rng: np.random.Generator) -> list[str]:
    return rng.choice(list(POLICIES), size=n).tolist()


@pytest.mark.slow
def test_matches_rlcard_on_2000_deals() -> None:
    deals = deal_cards(seed=11, start=0, count=2_000)
    _play_both(deals, _policies(2_000, np.random.default_rng(0)), seed=0)


@pytest.mark.slow  # about 20 s; with the test above, 14,000 deals in all
def test_matches_rlcard_on_12000_more_deals() -> None:
    for part in range(6):
        deals = deal_cards(seed=12, start=2_000 * part, count=2_000)
        _play_both(deals, _policies(2_000, np.random.default_rng(part + 1)), seed=1_000 * part)


def test_rlcard_first_state_has_stale_raise_counts() -> None:
    """Documents an RLCard 1.2.0 fault our engine does not copy: a reused game's first state."""
    game = LimitHoldemGame()
    game.init_game()
    game.step("raise")  # the small blind raises: one raise preflop
    state, _ = game.init_game()
    assert state["raise_nums"] == [1, 0, 0, 0]  # stale: left over from the previous hand
    fresh = LimitHoldemBatch(deals=deal_cards(seed=0, start=0, count=1))
    assert fresh.observe()[0, 52:].reshape(4, 5)[:, 0].all()  # zero raises in every round


def test_illegal_actions_raise_and_change_nothing() -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=3, start=0, count=3))
    before = (game.chips.copy(), game.to_act.copy(), game.raises.copy())
    with pytest.raises(IllegalActionError, match="hand 1"):
        game.step(np.array([CALL, CHECK, RAISE]))  # the small blind cannot check preflop
    with pytest.raises(IllegalActionError):
        game.step(np.array([CALL, 7, CALL]))
    for bad in ([CALL, -1, CALL], [1.0, 1.5, 1.0]):  # out of range, not a whole number
        with pytest.raises(IllegalActionError, match="hand 1"):
            game.step(np.array(bad))
    np.testing.assert_array_equal(game.chips, before[0])
    np.testing.assert_array_equal(game.to_act, before[1])
    np.testing.assert_array_equal(game.raises, before[2])
    game.step(np.array([FOLD]), hands=np.array([0]))
    with pytest.raises(IllegalActionError, match="already over"):
        game.step(np.array([CALL]), hands=np.array([0]))


def test_raise_cap_excludes_the_big_blind() -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=4, start=0, count=1))
    for _ in range(4):
        game.step(np.array([RAISE]))
    assert not game.legal_mask()[0, RAISE]
    assert game.chips[0].tolist() == [8, 10]  # the BB made the 4th raise; the SB is to call
    game.step(np.array([CALL]))
    assert int(game.round[0]) == 1 and int(game.to_act[0]) == 1  # the SB closed: BB acts first


def test_the_legality_table_in_every_situation() -> None:
    """Behind or level, with or without a raise left: each of the four actions is refused or
    applied as the rules say (the step's table against the legal mask)."""
    for raises_first in range(5):
        game = LimitHoldemBatch(deals=deal_cards(seed=5, start=0, count=1))
        for _ in range(raises_first):
            game.step(np.array([RAISE]))
        mask = game.legal_mask()[0]
        behind = bool(mask[CALL])
        assert mask.tolist() == [behind, raises_first < 4, True, not behind]
        for action in (CALL, RAISE, FOLD, CHECK):
            trial = LimitHoldemBatch(deals=deal_cards(seed=5, start=0, count=1))
            for _ in range(raises_first):
                trial.step(np.array([RAISE]))
            if mask[action]:
                trial.step(np.array([action]))
            else:
                with pytest.raises(IllegalActionError):
                    trial.step(np.array([action]))


def test_the_step_reads_its_tables_by_arithmetic_as_the_tables_say() -> None:
    """The hot step's int8 arithmetic (legal bits and words by parts, raise sizes by a shift)
    gives each table's entry in every situation and round."""
    from pokerirl.game.engine import (
        _LEGAL_BITS,
        _LEGAL_BY_SITUATION,
        _LEGAL_WORDS,
        RAISE_SIZE_BY_ROUND,
        _by_parts,
        _raise_sizes,
    )

    situations = np.arange(4, dtype=np.int8)
    bits = _by_parts(_LEGAL_BITS, situations)
    for action in range(NUM_ACTIONS):
        legal = ((bits >> action) & 1).astype(bool)
        assert legal.tolist() == _LEGAL_BY_SITUATION[:, action].tolist()
    words = _by_parts(_LEGAL_WORDS, situations)
    assert words.view(np.bool_).reshape(4, NUM_ACTIONS).tolist() == _LEGAL_BY_SITUATION.tolist()
    assert _raise_sizes(np.arange(4, dtype=np.int8)).tolist() == RAISE_SIZE_BY_ROUND.tolist()


def test_hands_leave_play_when_they_end_whether_all_or_some_are_stepped() -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=6, start=0, count=4))
    game.step(np.array([FOLD, CALL, CALL, RAISE]))  # all of them: hand 0 ends
    assert game.active().tolist() == [1, 2, 3] and game.done.tolist() == [True, False, False, False]
    game.step(np.array([FOLD]), hands=np.array([3]))  # some: hand 3 ends, 1 and 2 wait
    assert game.active().tolist() == [1, 2]
    game.step(np.array([CHECK, CHECK]))  # the big blind checks: both see the flop
    assert game.active().tolist() == [1, 2] and game.round.tolist()[1:3] == [1, 1]
    for _ in range(3):  # check the flop, turn and river down: two showdowns
        game.step(np.array([CHECK, CHECK]))
        game.step(np.array([CHECK, CHECK]))
    assert game.active().size == 0 and game.done.all()
    assert game.payoffs[[1, 2]].sum(axis=1).tolist() == [0.0, 0.0]
    assert (np.abs(game.payoffs[[1, 2]]) <= 1.0).all()  # one big blind each, won, lost or split
