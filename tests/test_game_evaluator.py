"""Seven-card hand strength against RLCard 1.2.0's own ``compare_hands`` (no mocks)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from rlcard.games.limitholdem.utils import compare_hands

from pokerirl.game.evaluator import HAND_CATEGORIES, category, hand_strength
from pokerirl.holdem import parse_card, rlcard_card_str


def _cards(text: str) -> list[int]:
    return [parse_card(c) for c in text.split()]


def _pairs_sharing_a_board(rng: np.random.Generator, n: int, deck: np.ndarray) -> tuple:
    """n heads-up showdowns dealt from ``deck``: two hole cards each and a shared board."""
    order = np.argsort(rng.random((n, deck.size)), axis=1)[:, :9]
    dealt = deck[order]
    board = dealt[:, 4:]
    return np.hstack([dealt[:, :2], board]), np.hstack([dealt[:, 2:4], board])


def _assert_agrees_with_rlcard(a: np.ndarray, b: np.ndarray) -> int:
    """Compare every pair with RLCard; return how many were split pots."""
    sa, sb = hand_strength(a), hand_strength(b)
    for i in range(a.shape[0]):
        expected = compare_hands(
            [[rlcard_card_str(c) for c in a[i]], [rlcard_card_str(c) for c in b[i]]]
        )
        ours = [int(sa[i] >= sb[i]), int(sb[i] >= sa[i])]
        assert ours == expected, (a[i].tolist(), b[i].tolist(), hex(sa[i]), hex(sb[i]))
    return int((sa == sb).sum())


def _restricted_decks() -> list[np.ndarray]:
    """Decks that make rare categories and ties common: few ranks, or few suits."""
    all_cards = np.arange(52)
    rank = all_cards % 13
    suit = all_cards // 13
    return [
        all_cards[np.isin(rank, [0, 1, 2, 3, 4, 9])],  # A-5 and T: quads, boats, wheels
        all_cards[np.isin(rank, [8, 9, 10, 11, 12, 0])],  # 9-A: broadway straights, boats
        all_cards[suit < 2],  # two suits: flushes and straight flushes
        all_cards[(suit == 0) | np.isin(rank, [5, 6, 7])],  # one suit plus 6-8: flush vs boat
    ]


def test_random_showdowns_agree_with_rlcard() -> None:
    rng = np.random.default_rng(1)
    ties = _assert_agrees_with_rlcard(*_pairs_sharing_a_board(rng, 5_000, np.arange(52)))
    assert ties > 0


@pytest.mark.parametrize("deck_index", range(4))
def test_tie_heavy_decks_agree_with_rlcard(deck_index: int) -> None:
    rng = np.random.default_rng(100 + deck_index)
    deck = _restricted_decks()[deck_index]
    ties = _assert_agrees_with_rlcard(*_pairs_sharing_a_board(rng, 1_500, deck))
    assert ties > 0


@pytest.mark.slow
def test_100k_random_showdowns_agree_with_rlcard() -> None:
    rng = np.random.default_rng(2)
    _assert_agrees_with_rlcard(*_pairs_sharing_a_board(rng, 100_000, np.arange(52)))
    for deck in _restricted_decks():
        _assert_agrees_with_rlcard(*_pairs_sharing_a_board(rng, 10_000, deck))


@pytest.mark.parametrize(
    ("better", "worse"),
    [
        ("As Kd 7c 7d 2s 3s 9h", "Qs Kd 7c 7d 2s 3s 9h"),  # pair, first kicker
        ("Ah 2h 3d 4s 5c 6d Kc", "Ah 2h 3d 4s 5c 9d Kc"),  # 6-high straight beats the wheel
        ("Ah Kh 8h 4h 3h 2s 2c", "Ah Kh 8h 4h 2h 3s 3c"),  # flush decided by the fifth card
        ("Ks Kd Qs Qd 9c 9d Jh", "Ks Kd Qs Qd 9c 9d 8h"),  # two pair: J kicker beats the third pair
        ("7s 7d 7h 9s 9d 9c 2h", "7s 7d 7h 8s 8d 8c 2h"),  # two trips: the higher trips is the set
        ("9s 9h 9d 9c As 2h 3d", "9s 9h 9d 9c Ks Kh Kd"),  # quads: kicker
        ("5s 6s 7s 8s 9s Ts Jd", "Ah 2h 3h 4h 5h Kh Kd"),  # T-high straight flush > steel wheel
        ("2s 3s 4s 5s As Kd Kh", "Kc Kd Kh Ks Qc Qd Qh"),  # steel wheel beats quad kings
    ],
)
def test_targeted_orderings(better: str, worse: str) -> None:
    strength = hand_strength(np.array([_cards(better), _cards(worse)]))
    assert strength[0] > strength[1]
    _assert_agrees_with_rlcard(np.array([_cards(better)]), np.array([_cards(worse)]))


def test_board_plays_splits_the_pot() -> None:
    board = "As Ks Qd Jh Tc"
    strength = hand_strength(np.array([_cards(f"2c 3d {board}"), _cards(f"4c 5d {board}")]))
    assert strength[0] == strength[1]
    assert HAND_CATEGORIES[int(category(strength)[0])] == "straight"


def test_every_category_is_reached() -> None:
    rng = np.random.default_rng(3)
    hands = np.vstack([_pairs_sharing_a_board(rng, 2_000, deck)[0] for deck in _restricted_decks()])
    assert set(category(hand_strength(hands)).tolist()) == set(range(1, 10))


def test_order_of_cards_does_not_matter() -> None:
    rng = np.random.default_rng(4)
    cards = np.argsort(rng.random((1_000, 52)), axis=1)[:, :7]
    shuffled = np.take_along_axis(cards, np.argsort(rng.random((1_000, 7)), axis=1), axis=1)
    np.testing.assert_array_equal(hand_strength(cards), hand_strength(shuffled))


def test_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="shape"):
        hand_strength(np.zeros((3, 6), dtype=np.int64))
    with pytest.raises(ValueError, match=r"0..51"):
        hand_strength(np.full((1, 7), 52))


# --------------------------------------------------------------------------- against eval7


def _agree_in_order(ours: np.ndarray, theirs: np.ndarray) -> int:
    """Assert that two evaluators order hands alike (equal exactly when equal) and return
    how many classes they found."""
    order = np.argsort(ours, kind="stable")
    ours, theirs = ours[order], theirs[order]
    new_class = np.diff(ours) != 0
    assert (np.diff(theirs)[~new_class] == 0).all(), "ours ties hands eval7 tells apart"
    assert (np.diff(theirs)[new_class] > 0).all(), "ours orders hands eval7 orders otherwise"
    return int(new_class.sum()) + 1


def _eval7(cards: np.ndarray) -> np.ndarray:
    eval7 = pytest.importorskip("eval7")
    from equity_reference import eval7_cards

    deck = eval7_cards()
    return np.array([eval7.evaluate([deck[c] for c in row]) for row in cards.tolist()])


def test_every_five_card_class_is_ranked_as_eval7_ranks_it() -> None:
    """The 7,462 classes: every multiset of five ranks (a rank at most four times) in mixed
    suits, and every five distinct ranks as a flush."""
    from pokerirl.game.evaluator import five_card_strength

    hands = []
    for ranks in itertools.combinations_with_replacement(range(13), 5):
        if max(ranks.count(r) for r in ranks) > 4:
            continue
        seen: dict[int, int] = {}
        cards = []
        for r in ranks:  # the k-th card of a rank in suit k: never five of one suit
            k = seen.get(r, 0)
            seen[r] = k + 1
            cards.append(((k + len(cards)) % 4 if len(set(ranks)) == 5 else k) * 13 + r)
        hands.append(cards)
        if len(set(ranks)) == 5:
            hands.append([13 * 2 + r for r in ranks])  # all diamonds
    hands_array = np.array(hands)
    assert len({tuple(sorted(h)) for h in hands}) == len(hands) == 7_462
    ours = five_card_strength(hands_array)
    assert _agree_in_order(ours, _eval7(hands_array)) == 7_462


def test_random_seven_card_hands_are_ranked_as_eval7_ranks_them() -> None:
    cards = np.random.default_rng(8).random((200_000, 52)).argsort(axis=1)[:, :7]
    assert _agree_in_order(hand_strength(cards), _eval7(cards)) > 3_000


def test_showdown_strengths_rank_both_seats_as_seven_card_strengths() -> None:
    """The engine's showdown (the board's keys summed once for both seats) on random deals
    and on decks where flushes, boats and ties are common."""
    from pokerirl.game.evaluator import seven_card_strengths, showdown_strengths

    rng = np.random.default_rng(9)
    decks = [np.arange(52), *_restricted_decks()]
    for deck in decks:
        deals = deck[rng.random((5_000, deck.size)).argsort(axis=1)[:, :9]].astype(np.int8)
        both = showdown_strengths(deals)
        for seat, hole in ((0, [0, 1]), (1, [2, 3])):
            seven = deals[:, [*hole, 4, 5, 6, 7, 8]]
            np.testing.assert_array_equal(both[:, seat], seven_card_strengths(seven))
