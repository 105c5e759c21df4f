"""Showdown equity for local best response and the AIVAT corrections: hole-card pairs against
many boards at once, ranked exactly as :func:`pokerirl.game.evaluator.hand_strength` ranks.

The 1,326 hole-card pairs are numbered in :data:`PAIRS` (``(a, b)`` with ``a < b``, card
indices of :mod:`pokerirl.encoding`). :func:`board_strengths` ranks every pair on every
one of M five-card boards in one vectorized pass; the ranks equal ``hand_strength`` of the
seven cards (``tests/test_lbr.py`` checks it on random boards), but a board's rank key is
summed once and shared by the 91 rank combinations of a pair, so it runs many times faster
than calling ``hand_strength`` on M x 1,326 rows. Pairs that share a card with their board
get a meaningless strength: callers mask them with :data:`CLASH`.

>>> from pokerirl.encoding import parse_card
>>> board = np.array([[parse_card(c) for c in "As Ks Qs 7d 2c".split()]])
>>> aces, tens = pair_index(parse_card("Ah"), parse_card("Ad")), pair_index(
...     parse_card("Js"), parse_card("Ts"))
>>> strength = board_strengths(board)
>>> bool(strength[0, tens] > strength[0, aces])  # a royal flush beats trip aces
True
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np

from pokerirl.encoding import NUM_CARDS, NUM_PAIRS, PAIRS
from pokerirl.game.evaluator import _tables, hand_strength  # noqa: F401 (doctests)

NUM_RANKS = 13
_INDEX = np.full((NUM_CARDS, NUM_CARDS), -1, dtype=np.int64)
_INDEX[PAIRS[:, 0], PAIRS[:, 1]] = _INDEX[PAIRS[:, 1], PAIRS[:, 0]] = np.arange(NUM_PAIRS)
# CLASH[c, p]: pair p holds card c (so p is impossible once c is seen elsewhere).
CLASH = np.zeros((NUM_CARDS, NUM_PAIRS), dtype=bool)
CLASH[PAIRS[:, 0], np.arange(NUM_PAIRS)] = CLASH[PAIRS[:, 1], np.arange(NUM_PAIRS)] = True

# Keys in int32 (seven cards stay below 2**31, even five of a rank): half the memory traffic.
_RANK = (np.arange(NUM_CARDS) % NUM_RANKS + NUM_RANKS - 1) % NUM_RANKS  # 2 .. A as 0 .. 12
_SUIT = np.arange(NUM_CARDS) // NUM_RANKS
_POW5 = (5 ** np.arange(NUM_RANKS)).astype(np.int32)
_CARD_KEY = _POW5[_RANK]  # a card's part of a rank key: sum 5**rank over the cards
_CARD_SUIT = (1 << (4 * _SUIT)).astype(np.int32)  # a card's count in its suit's 4-bit field
_FIELDS = 0x1111  # 1 in each suit's field
# The 91 rank combinations of two cards, and each pair's combination.
_COMBOS = np.array(list(itertools.combinations_with_replacement(range(NUM_RANKS), 2)))
_COMBO_KEY = _POW5[_COMBOS[:, 0]] + _POW5[_COMBOS[:, 1]]
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


@functools.cache
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
    index = dense.low_base[keys % _LOW] + dense.high_index[np.minimum(keys // _LOW, 5**6 - 1)]
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


def hole_strengths(boards: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """(M,) strength of hole cards ``holes`` (M, 2) on boards (M, 5), row by row, as
    ``hand_strength`` of the seven cards.

    >>> rng = np.random.default_rng(0)
    >>> cards = np.argsort(rng.random((1000, 52)), axis=1)[:, :7]
    >>> bool((hole_strengths(cards[:, 2:], cards[:, :2]) == hand_strength(cards)).all())
    True
    """
    cards = np.concatenate([np.asarray(holes, np.int64), np.asarray(boards, np.int64)], axis=1)
    strength = _non_flush(_card_sum(_CARD_KEY, cards))
    rows = np.flatnonzero(_flushable(_card_sum(_CARD_SUIT, cards)))
    if rows.size:
        suits, ranks = _SUIT[cards[rows]], _RANK[cards[rows]]
        suit = (suits[:, :, None] == np.arange(4)).sum(axis=1).argmax(axis=1)
        bits = np.where(suits == suit[:, None], np.int64(1) << ranks, 0).sum(axis=1)
        strength[rows] = _dense().flush[bits]
    return strength


def showdown_shares(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(N, S) seat 0's share of the pot (1 win, 0.5 split, 0 loss) on each of S boards of each
    row: ``holes`` (N, 2, 2) are both seats' hole cards, ``boards`` (N, S, 5).

    A board's rank key and suit counts are summed once for both seats; the few boards where a
    suit can reach five cards are ranked in full by :func:`hole_strengths`.

    >>> rng = np.random.default_rng(2)
    >>> cards = np.argsort(rng.random((300, 52)), axis=1)[:, :9]
    >>> found = showdown_shares(cards[:, :4].reshape(-1, 2, 2), cards[:, None, 4:])[:, 0]
    >>> mine = hand_strength(np.concatenate([cards[:, :2], cards[:, 4:]], axis=1))
    >>> theirs = hand_strength(cards[:, 2:])
    >>> bool((found == win_share(mine, theirs)).all())
    True
    """
    holes = np.asarray(holes, dtype=np.int64)
    boards = np.asarray(boards, dtype=np.int64)
    # Card-major copies: each card's column is contiguous for the sums.
    by_card = np.ascontiguousarray(np.moveaxis(boards, 2, 0))
    board_key = _card_sum(_CARD_KEY, np.moveaxis(by_card, 0, -1))
    board_suits = _card_sum(_CARD_SUIT, np.moveaxis(by_card, 0, -1))
    strength = []
    flushable = np.zeros(board_key.shape, dtype=bool)
    for seat in (0, 1):
        hole = holes[:, seat]
        strength.append(_non_flush(board_key + _card_sum(_CARD_KEY, hole)[:, None]))
        flushable |= _flushable(board_suits + _card_sum(_CARD_SUIT, hole)[:, None])
    rows, columns = np.nonzero(flushable)
    if rows.size:  # a flush for one seat or both: rank those boards in full
        for seat in (0, 1):
            strength[seat][rows, columns] = hole_strengths(boards[rows, columns], holes[rows, seat])
    return win_share(strength[0], strength[1])
