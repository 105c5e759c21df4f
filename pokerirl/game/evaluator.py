"""Vectorized seven-card hand strength, ranked exactly like RLCard 1.2.0's ``compare_hands``.

A strength is an ``int64``: higher is better, equal is a split pot. It packs the category
(1 high card .. 9 straight flush, RLCard's numbering) above five 4-bit tie-break ranks
(2 = 0 .. A = 12), so ``hex(strength)`` reads as ``0x<category><ranks>``.

Two lookup tables are built on first use and cached for the process:

* ``flush``: best straight flush or flush for each 13-bit rank mask of one suit (8,192 entries);
* ``ranks``: best non-flush hand for each multiset of seven ranks (49,205 entries), found by
  binary search on a base-5 key (one digit per rank: how many cards of that rank).

Flushes never coexist with quads or full houses in seven cards, so a hand with five or more
cards of one suit is scored by the flush table alone.

>>> from pokerirl.encoding import parse_card
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

from pokerirl.encoding import NUM_CARDS

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
    """Build the lookup tables now (about 0.1 s) instead of on the first evaluation."""
    _tables()


def hand_strength(cards: np.ndarray) -> np.ndarray:
    """Strength of the best five of seven cards, for many hands at once.

    Args:
        cards: (N, 7) card indices in :mod:`pokerirl.encoding` order (hole cards and board,
            any order, no duplicates within a row).

    Returns:
        (N,) int64; ``a > b`` exactly when RLCard's ``compare_hands`` says hand a beats hand b,
        and ``a == b`` when it splits the pot.

    >>> from pokerirl.encoding import parse_card
    >>> quads = [parse_card(c) for c in "9s 9h 9d 9c Ks 2h 3d".split()]
    >>> int(category(hand_strength(np.array([quads])))[0])
    8
    """
    cards = np.asarray(cards)
    if cards.ndim != 2 or cards.shape[1] != 7:
        raise ValueError(f"cards must have shape (N, 7), got {cards.shape}")
    if cards.size and (cards.min() < 0 or cards.max() >= NUM_CARDS):
        raise ValueError("card indices must lie in 0..51")
    tables = _tables()
    cards = cards.astype(np.int64, copy=False)
    suit = cards // NUM_RANKS
    rank = (cards % NUM_RANKS + NUM_RANKS - 1) % NUM_RANKS  # RLCard's A,2..K -> 2..K,A as 0..12

    strength = tables.rank_strength[np.searchsorted(tables.rank_keys, _POW5[rank].sum(axis=1))]

    # Suit counts packed 3 bits per suit (at most 7 cards, so no carry between suits).
    suit_counts = (np.int64(1) << (3 * suit)).sum(axis=1)
    counts = (suit_counts[:, None] >> (3 * np.arange(4))) & 7
    flush_rows = np.flatnonzero(counts.max(axis=1) >= 5)
    if flush_rows.size:
        flush_suit = counts[flush_rows].argmax(axis=1)
        in_suit = suit[flush_rows] == flush_suit[:, None]
        mask = np.where(in_suit, np.int64(1) << rank[flush_rows], 0).sum(axis=1)
        strength[flush_rows] = tables.flush[mask]
    return strength
