"""Vectorized seven-card hand strength, ranked exactly like RLCard 1.2.0's ``compare_hands``.

A strength is an ``int64``: higher is better, equal is a split pot. It packs the category
(1 high card .. 9 straight flush, RLCard's numbering) above five 4-bit tie-break ranks
(2 = 0 .. A = 12), so ``hex(strength)`` reads as ``0x<category><ranks>``.

Two lookup tables are built on first use and cached for the process:

* ``flush``: best straight flush or flush for each 13-bit rank mask of one suit (8,192 entries);
* ``ranks``: best non-flush hand for each multiset of seven ranks (49,205 entries), read by
  a dense index of its base-5 key (one digit per rank: how many cards of that rank; see
  :class:`_Dense`), the key summed from one small table per card.

This one evaluator serves the engine's showdowns (:func:`hand_strength`), the strength
encoding's exact equity and LBR (:func:`board_strengths`: every hole pair on many boards)
and the AIVAT corrections. ``tests/test_game_evaluator.py`` checks it against eval7 on all
7,462 five-card classes and on random seven-card hands; ``benchmarks/evaluator.py`` times it
against eval7.

Flushes never coexist with quads or full houses in seven cards, so a hand with five or more
cards of one suit is scored by the flush table alone.

>>> from pokerirl.holdem import parse_card
>>> def cards(text):
...     return np.array([[parse_card(c) for c in text.split()]])
>>> royal = hand_strength(cards("As Ks Qs Js Ts 2c 3d"))
>>> wheel = hand_strength(cards("Ah 2c 3d 4s 5h 9c Kd"))
>>> hex(int(royal[0])), hex(int(wheel[0]))
('0x9c0000', '0x530000')
>>> ace_kicker, queen_kicker = cards("Ah Kd 7c 7d 2s 3s 9h"), cards("Qh Kd 7c 7d 2s 3s 9h")
>>> bool(hand_strength(ace_kicker)[0] > hand_strength(queen_kicker)[0])
True
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cache

import numpy as np

from pokerirl.holdem import NUM_CARDS, NUM_PAIRS, PAIRS

HAND_CATEGORIES: tuple[str, ...] = (
    "",  # RLCard's 0, "not yet evaluated"; never returned
    "high card",
    "one pair",
    "two pairs",
    "three of a kind",
    "straight",
    "flush",
    "full house",
    "four of a kind",
    "straight flush",
)
HIGH_CARD, PAIR, TWO_PAIRS, TRIPS, STRAIGHT, FLUSH, FULL_HOUSE, QUADS, STRAIGHT_FLUSH = range(1, 10)

NUM_RANKS = 13
CATEGORY_SHIFT = 20  # five 4-bit tie-break ranks below the category
_POW5 = 5 ** np.arange(NUM_RANKS, dtype=np.int64)


def category(strength: np.ndarray) -> np.ndarray:
    """Hand category (1 high card .. 9 straight flush) of strengths from :func:`hand_strength`."""
    return np.asarray(strength) >> CATEGORY_SHIFT


def _pack(cat: np.ndarray | int, ranks: list[np.ndarray]) -> np.ndarray:
    """Category and up to five tie-break ranks (most significant first) as one int64."""
    value = np.asarray(cat, dtype=np.int64) << CATEGORY_SHIFT
    for slot, rank in enumerate(ranks):
        value = value | (np.asarray(rank, dtype=np.int64) << (16 - 4 * slot))
    return value


def _rank_bits(masks: np.ndarray) -> np.ndarray:
    """(M, 13) bool: which ranks a 13-bit mask holds."""
    return ((masks[:, None] >> np.arange(NUM_RANKS)) & 1).astype(bool)


def _straight_high(present: np.ndarray) -> np.ndarray:
    """Highest straight in a (M, 13) rank-presence matrix, ``-1`` if none; the wheel is 5-high."""
    high = np.full(present.shape[0], -1, dtype=np.int64)
    for top in range(4, NUM_RANKS):  # ascending, so the last hit is the highest straight
        high[present[:, top - 4 : top + 1].all(axis=1)] = top
    wheel = present[:, [12, 0, 1, 2, 3]].all(axis=1) & (high < 0)
    high[wheel] = 3
    return high


def _top_ranks(present: np.ndarray, k: int) -> list[np.ndarray]:
    """The k highest present ranks of each row, highest first (rows must hold at least k)."""
    ordered = np.sort(np.where(present, np.arange(NUM_RANKS), -1), axis=1)[:, ::-1]
    return [ordered[:, i] for i in range(k)]


def _flush_table() -> np.ndarray:
    """Strength of the best flush or straight flush for every 13-bit mask of one suit."""
    masks = np.arange(1 << NUM_RANKS, dtype=np.int64)
    present = _rank_bits(masks)
    table = np.zeros(masks.shape[0], dtype=np.int64)
    flush = present.sum(axis=1) >= 5
    high = _straight_high(present)
    top5 = _top_ranks(present[flush], 5)
    table[flush] = _pack(FLUSH, top5)
    straight_flush = flush & (high >= 0)
    table[straight_flush] = _pack(STRAIGHT_FLUSH, [high[straight_flush]])
    return table


def _non_flush_strength(counts: np.ndarray) -> np.ndarray:
    """Best non-flush strength for (M, 13) rank counts of seven cards."""
    m = counts.shape[0]
    ranks = np.broadcast_to(np.arange(NUM_RANKS), counts.shape)
    # Groups ordered by (count, rank) descending: pairs before singletons, higher rank first.
    group_key = np.where(counts > 0, counts * 16 + ranks, -1)
    groups = np.sort(group_key, axis=1)[:, ::-1]
    size = np.where(groups >= 0, groups >> 4, 0)
    rank = np.where(groups >= 0, groups & 15, -1)

    def best_rank_from(first_group: int) -> np.ndarray:
        # Kicker: highest rank among the remaining groups, whatever their size.
        return rank[:, first_group:].max(axis=1)

    straight = _straight_high(counts > 0)
    strength = np.zeros(m, dtype=np.int64)
    # Assign from weakest to strongest so that the strongest category that applies wins.
    strength[:] = _pack(HIGH_CARD, [rank[:, i] for i in range(5)])
    largest, second = size[:, 0], size[:, 1]
    cases = [
        (largest == 2, PAIR, [rank[:, 0], rank[:, 1], rank[:, 2], rank[:, 3]]),
        ((largest == 2) & (second == 2), TWO_PAIRS, [rank[:, 0], rank[:, 1], best_rank_from(2)]),
        (largest == 3, TRIPS, [rank[:, 0], rank[:, 1], rank[:, 2]]),
        (straight >= 0, STRAIGHT, [straight]),
        ((largest == 3) & (second >= 2), FULL_HOUSE, [rank[:, 0], rank[:, 1]]),
        (largest == 4, QUADS, [rank[:, 0], best_rank_from(1)]),
    ]
    for applies, cat, tie_break in cases:
        strength[applies] = _pack(cat, tie_break)[applies]
    return strength


@dataclass(frozen=True, kw_only=True)
class _Tables:
    flush: np.ndarray  # (8192,) strength by one suit's rank mask
    rank_keys: np.ndarray  # (49205,) sorted base-5 keys of seven-rank multisets
    rank_strength: np.ndarray  # (49205,) non-flush strength per key


@cache
def _tables() -> _Tables:
    multisets = np.array(list(itertools.combinations_with_replacement(range(NUM_RANKS), 7)))
    counts = np.zeros((multisets.shape[0], NUM_RANKS), dtype=np.int64)
    np.add.at(counts, (np.arange(multisets.shape[0])[:, None], multisets), 1)
    counts = counts[(counts <= 4).all(axis=1)]  # a rank has four suits
    keys = counts @ _POW5
    order = np.argsort(keys)
    return _Tables(
        flush=_flush_table(),
        rank_keys=keys[order],
        rank_strength=_non_flush_strength(counts[order]),
    )


def prepare_tables() -> None:
    """Build the lookup tables now (about 0.2 s) instead of on the first evaluation."""
    _dense()


def hand_strength(cards: np.ndarray) -> np.ndarray:
    """Strength of the best five of seven cards, for many hands at once.

    Args:
        cards: (N, 7) card indices in :mod:`pokerirl.holdem` order (hole cards and board,
            any order, no duplicates within a row).

    Returns:
        (N,) int64; ``a > b`` exactly when RLCard's ``compare_hands`` says hand a beats hand b,
        and ``a == b`` when it splits the pot.

    >>> from pokerirl.holdem import parse_card
    >>> quads = [parse_card(c) for c in "9s 9h 9d 9c Ks 2h 3d".split()]
    >>> int(category(hand_strength(np.array([quads])))[0])
    8
    """
    cards = np.asarray(cards)
    if cards.ndim != 2 or cards.shape[1] != 7:
        raise ValueError(f"cards must have shape (N, 7), got {cards.shape}")
    if cards.size and (cards.min() < 0 or cards.max() >= NUM_CARDS):
        raise ValueError("card indices must lie in 0..51")
    return seven_card_strengths(cards.astype(np.int64, copy=False)).astype(np.int64)


# ---------------------------------------------------------------------------------------------
# Every hole-card pair on many boards at once: the fast path shared by the engine's showdowns,
# the strength encoding's exact equity, AIVAT and local best response.
#
# The 1,326 hole-card pairs are numbered in :data:`~pokerirl.holdem.PAIRS` (``(a, b)``,
# ``a < b``). :func:`board_strengths` ranks every pair on M five-card boards in one pass: a
# board's rank key is summed once and shared by the 91 rank combinations of a pair, and a
# dense index replaces the binary search. Pairs that share a card with their board get a
# meaningless strength: callers mask them with :data:`CLASH`.
# ---------------------------------------------------------------------------------------------

_INDEX = np.full((NUM_CARDS, NUM_CARDS), -1, dtype=np.int64)
_INDEX[PAIRS[:, 0], PAIRS[:, 1]] = _INDEX[PAIRS[:, 1], PAIRS[:, 0]] = np.arange(NUM_PAIRS)
# CLASH[c, p]: pair p holds card c (so p is impossible once c is seen elsewhere).
CLASH = np.zeros((NUM_CARDS, NUM_PAIRS), dtype=bool)
CLASH[PAIRS[:, 0], np.arange(NUM_PAIRS)] = CLASH[PAIRS[:, 1], np.arange(NUM_PAIRS)] = True

# Keys in int32 (seven cards stay below 2**31, even five of a rank): half the memory traffic.
_RANK = (np.arange(NUM_CARDS) % NUM_RANKS + NUM_RANKS - 1) % NUM_RANKS  # 2 .. A as 0 .. 12
_SUIT = np.arange(NUM_CARDS) // NUM_RANKS
_POW5_32 = _POW5.astype(np.int32)
_CARD_KEY = _POW5_32[_RANK]  # a card's part of a rank key: sum 5**rank over the cards
_CARD_SUIT = (1 << (4 * _SUIT)).astype(np.int32)  # a card's count in its suit's 4-bit field
_FIELDS = 0x1111  # 1 in each suit's field
# The 91 rank combinations of two cards, and each pair's combination.
_COMBOS = np.array(list(itertools.combinations_with_replacement(range(NUM_RANKS), 2)))
_COMBO_KEY = _POW5_32[_COMBOS[:, 0]] + _POW5_32[_COMBOS[:, 1]]
_COMBO_OF = np.zeros((NUM_RANKS, NUM_RANKS), dtype=np.int64)
_COMBO_OF[_COMBOS[:, 0], _COMBOS[:, 1]] = _COMBO_OF[_COMBOS[:, 1], _COMBOS[:, 0]] = np.arange(91)
_PAIR_COMBO = _COMBO_OF[_RANK[PAIRS[:, 0]], _RANK[PAIRS[:, 1]]]
# _PAIR_BITS[s, p]: the rank bits of pair p's cards of suit s.
_PAIR_BITS = np.zeros((4, NUM_PAIRS), dtype=np.int32)
for _k in (0, 1):
    np.add.at(_PAIR_BITS, (_SUIT[PAIRS[:, _k]], np.arange(NUM_PAIRS)), 1 << _RANK[PAIRS[:, _k]])
_CARD_BIT = (1 << _RANK).astype(np.int32)  # a card's bit in its suit's 13-bit rank mask
# _HOLDING[s][k]: the pairs with at least k cards of suit s (k = 0, 1, 2).
_SUITED_CARDS = (_SUIT[PAIRS][:, :, None] == np.arange(4)).sum(axis=1)  # (1326, 4)
_HOLDING = [[np.flatnonzero(_SUITED_CARDS[:, s] >= k) for k in range(3)] for s in range(4)]
_LOW = 5**7  # a rank key's part for ranks 2 .. 8 (key % _LOW), the rest is key // _LOW


@dataclass(frozen=True, kw_only=True)
class _Dense:
    """The evaluator's non-flush strengths by a dense index instead of a binary search.

    A seven-rank key splits into the counts of ranks 2..8 (``low``) and of 9..A (``high``);
    every low multiset of size k goes with every high one of size 7 - k, so ``low_base[low]
    + high_index[high]`` numbers the 49,205 multisets without a gap (size classes in turn).
    """

    low_base: np.ndarray  # (5**7,) int32
    high_index: np.ndarray  # (5**6,) int32
    strength: np.ndarray  # (49205,) int32 (strengths stay below 2**24)
    flush: np.ndarray  # (8192,) int32: the evaluator's flush table


def _digit_sum(codes: np.ndarray, digits: int) -> np.ndarray:
    total, rest = np.zeros_like(codes), codes.copy()
    for _ in range(digits):
        total, rest = total + rest % 5, rest // 5
    return total


@cache
def _dense() -> _Dense:
    tables = _tables()
    low, high = tables.rank_keys % _LOW, tables.rank_keys // _LOW
    low_size, high_size = _digit_sum(low, 7), _digit_sum(high, 6)
    low_base = np.zeros(_LOW, dtype=np.int32)
    high_index = np.zeros(5**6, dtype=np.int32)
    offset = 0
    for k in range(8):
        lows, highs = np.unique(low[low_size == k]), np.unique(high[high_size == 7 - k])
        low_base[lows] = offset + np.arange(lows.size) * highs.size
        high_index[highs] = np.arange(highs.size)
        offset += lows.size * highs.size
    index = low_base[low] + high_index[high]
    if offset != tables.rank_keys.size or np.unique(index).size != offset:
        raise AssertionError("the dense rank index is not one to one")  # a bug if it fires
    strength = np.empty(offset, dtype=np.int32)
    strength[index] = tables.rank_strength
    flush = tables.flush.astype(np.int32)
    return _Dense(low_base=low_base, high_index=high_index, strength=strength, flush=flush)


def _non_flush(keys: np.ndarray) -> np.ndarray:
    """Non-flush strength of seven-rank keys (int32 ``sum 5**rank``). A key no seven cards
    make (a fifth card of a rank: only a clashing pair gives one) gets some strength; callers
    mask those pairs."""
    dense = _dense()
    high = keys // _LOW
    low = keys - _LOW * high  # not keys % _LOW: numpy's remainder is several times a divide
    index = dense.low_base[low] + dense.high_index[np.minimum(high, 5**6 - 1)]
    return dense.strength[np.minimum(index, dense.strength.size - 1)]


def _card_sum(table: np.ndarray, cards: np.ndarray) -> np.ndarray:
    """``table[cards].sum(axis=-1)`` by one add per card (numpy's reduction over a short last
    axis is several times slower)."""
    cards = np.asarray(cards)
    total = table[cards[..., 0]]
    for i in range(1, cards.shape[-1]):
        total = total + table[cards[..., i]]
    return total


def _flushable(suit_counts: np.ndarray, to_come: int = 0) -> np.ndarray:
    """Where packed suit counts (4 bits a suit) hold a suit that ``to_come`` more cards can
    bring to five: add to every field and test its top bit."""
    return ((suit_counts + (3 + to_come) * _FIELDS) & (8 * _FIELDS)) != 0


def pair_index(a: np.ndarray | int, b: np.ndarray | int) -> np.ndarray:
    """The pair number of hole cards ``a`` and ``b`` (either order).

    >>> int(pair_index(1, 0)), int(pair_index(50, 51))
    (0, 1325)
    """
    return _INDEX[np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)]


def board_strengths(boards: np.ndarray) -> np.ndarray:
    """(M, 1326) strength of every pair on each of M five-card boards (M, 5), as
    ``hand_strength`` ranks the seven cards."""
    boards = np.asarray(boards, dtype=np.int64)
    # Rank multiset key: the board's part once per board, then one of 91 combinations.
    board_key = _card_sum(_CARD_KEY, boards)
    strength = np.take(_non_flush(board_key[:, None] + _COMBO_KEY[None, :]), _PAIR_COMBO, axis=1)
    # Flushes: five cards of a suit need three of it on the board (only one suit can have
    # three of five cards), and then only the pairs holding the cards still missing.
    rows = np.flatnonzero(_flushable(_card_sum(_CARD_SUIT, boards), to_come=2))
    if rows.size == 0:
        return strength
    suits = _SUIT[boards[rows]]
    counts = (suits[:, :, None] == np.arange(4)).sum(axis=1)
    suit, have = counts.argmax(axis=1), counts.max(axis=1)
    board_bits = np.where(suits == suit[:, None], _CARD_BIT[boards[rows]], 0).sum(axis=1)
    flush = _dense().flush
    for s in range(4):
        for count in (3, 4, 5):
            at = np.flatnonzero((suit == s) & (have == count))
            if at.size == 0:
                continue
            cells = np.ix_(rows[at], _HOLDING[s][5 - count])
            mask = board_bits[at].astype(np.int32)[:, None] | _PAIR_BITS[s][cells[1]]
            # The flush table is 0 below five cards of the suit, and a flush beats every
            # hand that can be made beside it (no quads or full house fit in seven cards).
            strength[cells] = np.maximum(strength[cells], flush[mask])
    return strength


def win_share(mine: np.ndarray, theirs: np.ndarray) -> np.ndarray:
    """1 where ``mine`` wins, 0.5 on a split, 0 on a loss (elementwise strengths)."""
    return (mine > theirs) + 0.5 * (mine == theirs)


def five_card_strength(cards: np.ndarray) -> np.ndarray:
    """(N,) int64 strength of (N, 5) distinct cards, by the same category logic the seven-card
    tables are built with (the tests check it on all 7,462 five-card classes)."""
    cards = np.asarray(cards, dtype=np.int64)
    rank, suit = _RANK[cards], _SUIT[cards]
    counts = (rank[:, :, None] == np.arange(NUM_RANKS)).sum(axis=1)
    strength = _non_flush_strength(counts)
    flush = (suit == suit[:, :1]).all(axis=1)
    strength[flush] = _tables().flush[(np.int64(1) << rank[flush]).sum(axis=1)]
    return strength


def seven_card_strengths(cards: np.ndarray) -> np.ndarray:
    """(N,) int32 strength of (N, 7) distinct cards (unchecked), as :func:`hand_strength`:
    a rank key summed from one table per card and a dense index instead of a search; the
    rows where a suit reaches five cards are ranked by the flush table."""
    return _keyed_strengths(cards, _card_sum(_CARD_KEY, cards), _card_sum(_CARD_SUIT, cards))


def _keyed_strengths(cards: np.ndarray, keys: np.ndarray, suit_counts: np.ndarray) -> np.ndarray:
    """:func:`seven_card_strengths` of ``cards`` (N, 7) whose rank keys (``_CARD_KEY``
    summed) and packed suit counts (``_CARD_SUIT`` summed) a caller already has."""
    strength = _non_flush(keys)
    rows = np.flatnonzero(_flushable(suit_counts))
    if rows.size:
        strength[rows] = _flush_strengths(cards[rows])
    return strength


def _flush_strengths(cards: np.ndarray) -> np.ndarray:
    """Strengths of (N, 7) cards that hold five of a suit: the flush table of its ranks."""
    suits, ranks = _SUIT[cards], _RANK[cards]
    suit = (suits[:, :, None] == np.arange(4)).sum(axis=1).argmax(axis=1)
    bits = np.where(suits == suit[:, None], np.int64(1) << ranks, 0).sum(axis=1)
    return _dense().flush[bits]


# A deal's columns that make each seat's seven cards: its hole cards, then the board.
_SEAT_COLUMNS = np.array([[0, 1, 4, 5, 6, 7, 8], [2, 3, 4, 5, 6, 7, 8]])


def showdown_strengths(deals: np.ndarray) -> np.ndarray:
    """(N, 2) int32 strength of each seat's seven cards in (N, 9) deals (seat 0's hole
    cards, seat 1's, the board; unchecked), as :func:`seven_card_strengths`: the board's
    keys are summed once for both seats.

    >>> rng = np.random.default_rng(0)
    >>> deals = np.argsort(rng.random((1000, 52)), axis=1)[:, :9]
    >>> both = showdown_strengths(deals)
    >>> bool((both[:, 1] == seven_card_strengths(deals[:, [2, 3, 4, 5, 6, 7, 8]])).all())
    True
    """
    deals = np.asarray(deals, dtype=np.intp)  # gathers by int8 would convert each column
    keys, suits = np.empty((deals.shape[0], 2), np.int32), np.empty((deals.shape[0], 2), np.int32)
    for table, out in ((_CARD_KEY, keys), (_CARD_SUIT, suits)):
        board = _card_sum(table, deals[:, 4:])
        out[:, 0] = board + table[deals[:, 0]] + table[deals[:, 1]]
        out[:, 1] = board + table[deals[:, 2]] + table[deals[:, 3]]
    strength = _non_flush(keys)
    rows, seats = np.nonzero(_flushable(suits))
    if rows.size:
        strength[rows, seats] = _flush_strengths(deals[rows[:, None], _SEAT_COLUMNS[seats]])
    return strength


def hole_strengths(boards: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """(M,) strength of hole cards ``holes`` (M, 2) on boards (M, 5), row by row, as
    ``hand_strength`` of the seven cards.

    >>> rng = np.random.default_rng(0)
    >>> cards = np.argsort(rng.random((1000, 52)), axis=1)[:, :7]
    >>> bool((hole_strengths(cards[:, 2:], cards[:, :2]) == hand_strength(cards)).all())
    True
    """
    cards = np.concatenate([np.asarray(holes, np.int64), np.asarray(boards, np.int64)], axis=1)
    return seven_card_strengths(cards)
