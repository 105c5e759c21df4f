"""Replaying IRC action strings into RLCard-style decisions."""

from __future__ import annotations

import pytest

from pokerirl.holdem import CALL, CHECK, FOLD, RAISE
from pokerirl.parsers.replay import ReplayError, replay_actions


def actions(strings: tuple[str, ...]) -> list[tuple[int, int, int]]:
    """(position, street, action id) of each decision."""
    return [(d.position, d.street, d.action_id) for d in replay_actions(strings).decisions]


@pytest.mark.parametrize("quit_code", ["Q", "K", "f"])
def test_quit_and_kicked_are_folds(quit_code: str) -> None:
    replay = replay_actions(("Bc", "Bk", "b", quit_code, "-", "-", "-", "-"))
    assert actions(("Bc", "Bk", "b", quit_code, "-", "-", "-", "-"))[-1] == (2, 1, FOLD)
    assert not replay.showdown and replay.last_street == 1


def test_all_in_not_facing_a_bet_is_a_raise() -> None:
    replay = replay_actions(("Bc", "Bk", "A", "c", "-", "-", "-", "-"))
    assert actions(("Bc", "Bk", "A", "c", "-", "-", "-", "-"))[2:] == [(1, 1, RAISE), (2, 1, CALL)]
    assert replay.all_in and replay.showdown


def test_trailing_all_in_marks_a_call_that_went_all_in() -> None:
    replay = replay_actions(("Brrr", "BrrcA", "-", "-", "-", "-", "-", "-"))
    assert replay.all_in and replay.showdown
    assert [d.action_id for d in replay.decisions] == [RAISE, RAISE, RAISE, RAISE, RAISE, CALL]


def test_call_with_nothing_to_call_is_a_check() -> None:
    assert actions(("Bc", "Bc", "k", "k", "k", "k", "k", "k"))[1] == (2, 0, CHECK)


def test_trailing_quits_after_the_hand_ended_are_ignored() -> None:
    replay = replay_actions(("Bc", "Bk", "bQ", "Q", "-", "-", "-", "-"))
    assert [d.action_id for d in replay.decisions][-2:] == [RAISE, FOLD]


def test_legal_mask_and_raise_counts_follow_rlcard() -> None:
    replay = replay_actions(("Bc", "Bk", "brrr", "rrrc", "k", "k", "k", "k"))
    flop = [d for d in replay.decisions if d.street == 1]
    # b r r r r r r c: seven raises, then the call.
    assert [d.raise_nums[1] for d in flop] == [0, 1, 2, 3, 4, 4, 4, 4]
    # The fifth raise is past RLCard's cap: the mask still shows it, because it was taken.
    assert flop[4].action_id == RAISE and flop[4].legal_mask[RAISE]
    assert flop[-1].raise_nums[1] == 4 and not flop[-1].legal_mask[RAISE]
    assert flop[-1].raises_uncapped == 7
    assert replay.max_raises == 7


@pytest.mark.parametrize(
    ("strings", "message"),
    [
        (("Bc", "Bk", "b", "k", "-", "-", "-", "-"), "check facing a bet"),
        (("Bc", "Bk", "b", "-", "-", "-", "-", "-"), "ends before the round is closed"),
        (("Bc", "Bkk", "k", "k", "k", "k", "k", "k"), "extra actions"),
        (("Bf", "B", "k", "k", "-", "-", "-", "-"), "action after the hand ended"),
        (("Bc", "Bk", "kB", "k", "k", "k", "k", "k"), "blind after preflop"),
        (("Bx", "Bk", "k", "k", "k", "k", "k", "k"), "unknown action code"),
    ],
)
def test_unplayable_strings_raise(strings: tuple[str, ...], message: str) -> None:
    with pytest.raises(ReplayError, match=message):
        replay_actions(strings)
