"""Exact equity against a uniformly random opponent hand, on every street (ties count 1/2).

A hand's equity is ``P(win) + P(tie) / 2`` over every opponent hand and every runout of the
board, all equally likely. Everything is counted in integers (``2 x wins + ties``) and
divided once at the end, so the same cards give the same bytes on every platform.

* **river**: the 990 opponent hands (two of the 45 unseen cards), each ranked by
  :func:`~pokerirl.game.evaluator.board_strengths`;
* **turn**: the same count summed over the 46 rivers (45,540 cases), or read from the turn
  table where ``pokerirl data turn-table`` built it (:func:`turn_table`: every turn board up
  to a permutation of the suits by every pair, 87 MB in the data cache; the same integers);
* **flop**: a shipped table (:data:`FLOP_TABLE_FILE`): for each of the 1,755 flops up to a
  permutation of the suits, and each of the 1,326 hole pairs, the count summed over the
  1,081 turn-river runouts (1,070,190 cases). :func:`build_flop_table` makes it (about two
  minutes on one core: every pair is ranked on each runout by a sort, see
  :func:`river_counts`); a flop is mapped to its class, and the hole cards through the same
  suit permutation, which changes no equity. The file carries its SHA-256 here
  (:data:`FLOP_TABLE_SHA256`) and is refused if it differs;
* **preflop**: :mod:`pokerirl.game.preflop`'s 169 classes, summed exactly from the flop
  table over the 19,600 flops.

``tests/test_equity.py`` checks the river and turn against an independent evaluator
(``eval7``) by brute force, the flop table on random flops, and the preflop classes.

>>> from pokerirl.holdem import parse_card
>>> def cards(text):
...     return np.array([[parse_card(c) for c in text.split()]])
>>> round(float(river_equity(cards("As Ah"), cards("Ad Kc 7h 2s 3d"))[0]), 4)  # 45: a wheel
0.9838
>>> round(float(turn_equity(cards("7c 2d"), cards("Kh Qh 9s 4c"))[0]), 4)
0.139
"""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache, lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from pokerirl.atomic import atomic_path
from pokerirl.cache import TURN_TABLE_NAME, cache_folder
from pokerirl.errors import InputError
from pokerirl.game.cases import (
    FLOP_DENOMINATOR,
    RIVER_DENOMINATOR,
    TURN_DENOMINATOR,
    TURN_RIVERS,
)
from pokerirl.game.evaluator import (
    _CARD_BIT,
    _CARD_KEY,
    _CARD_SUIT,
    _COMBO_KEY,
    _COMBO_OF,
    _COMBOS,
    _PAIR_BITS,
    _PAIR_COMBO,
    _POW5_32,
    _RANK,
    _SUIT,
    CLASH,
    _card_sum,
    _dense,
    _keyed_strengths,
    _non_flush,
    board_strengths,
    pair_index,
    seven_card_strengths,
)
from pokerirl.game.preflop import preflop_equity  # its table is summed from our flop table
from pokerirl.holdem import NUM_CARDS, NUM_PAIRS, PAIRS

NUM_RANKS = 13
FLOP_CLASSES = 1_755  # flops up to a permutation of the suits
TURN_CLASSES = 16_432  # turn boards up to a permutation of the suits
FLOP_TABLE_FILE = Path(__file__).parent / "data" / "flop_equity.npz"
FLOP_TABLE_SHA256 = "7b69bc3c318aff63cb2a07a0ee442f5b5d5d021c3cd99921406ff725288eae8c"
CHUNK_BOARDS = 512  # boards ranked at once: (512, 1326) int32 arrays stay small
TURN_CHUNK = 64  # turn states counted at once (their 2,208 rivers)

# The 24 permutations of the four suits, and each one applied to every card and pair.
_SUIT_PERMS = np.array(list(itertools.permutations(range(4))), dtype=np.int64)  # (24, 4)
_CARDS = np.arange(NUM_CARDS)
_PERMUTED_CARD = _SUIT_PERMS[:, _CARDS // NUM_RANKS] * NUM_RANKS + _CARDS % NUM_RANKS
_PERMUTED_PAIR = pair_index(_PERMUTED_CARD[:, PAIRS[:, 0]], _PERMUTED_CARD[:, PAIRS[:, 1]])
# _WAYS[5 * a + b, same]: unseen pairs of a rank combination with a and b unseen cards of its
# two ranks (C(a, 2) when both ranks are one).
_LEFT = np.arange(25)
_WAYS = np.stack([(_LEFT // 5) * (_LEFT % 5), (_LEFT // 5) * (_LEFT // 5 - 1) // 2], axis=1)
_WAYS = _WAYS.astype(np.int16)
_SAME_RANK = (_COMBOS[:, 0] == _COMBOS[:, 1]).astype(np.int64)
_WAYS_FLAT = _WAYS.reshape(-1)  # [2 * (5 * a + b) + same]: one 1-D gather
# Where a rank combination reads _WAYS_FLAT with no card of its ranks seen, and what each seen
# card of a rank takes off that place (10 for the first rank, 2 for the second).
_WAYS_AT_NONE_SEEN = 2 * (5 * 4 + 4) + _SAME_RANK
_WAYS_STEP = np.zeros((NUM_RANKS, len(_COMBOS)))
np.add.at(_WAYS_STEP, (_COMBOS[:, 0], np.arange(len(_COMBOS))), 10)
np.add.at(_WAYS_STEP, (_COMBOS[:, 1], np.arange(len(_COMBOS))), 2)
_SUIT_FIELD_SHIFTS = 4 * np.arange(4)  # each suit's 4-bit count in packed suit counts
_PAIR_CARD_BITS = (np.int64(1) << PAIRS[:, 0]) | (np.int64(1) << PAIRS[:, 1])
# The pairs of two cards of suit s (4, 78): they alone complete its flush beside three of it.
_TWO_SUITED = np.array([np.flatnonzero((_SUIT[PAIRS] == s).all(axis=1)) for s in range(4)])
# Pairs holding each card: _CARD_PAIRS[c] (51 pair numbers); a pair's place in its cards' rows.
_CARD_PAIRS = np.array([np.flatnonzero(CLASH[c]) for c in range(NUM_CARDS)])  # (52, 51)
_PLACE = np.zeros((NUM_PAIRS, 2), dtype=np.int64)  # flat index card * 51 + place
# Per suit, those pairs' card bits, rank bits of the suit and rank combinations: three (4, 78)
# tables read by the board's suit.
_TWO_SUITED_BITS = (
    _PAIR_CARD_BITS[_TWO_SUITED],
    np.take_along_axis(_PAIR_BITS, _TWO_SUITED, axis=1),
    _PAIR_COMBO[_TWO_SUITED],
)
# _CARD_OF[13 * s + r]: the card of suit s and rank r (2 .. A as 0 .. 12); a rank's bit.
_CARD_OF = (np.arange(4)[:, None] * NUM_RANKS + (np.arange(NUM_RANKS) + 1) % NUM_RANKS).reshape(-1)
_RANK_BITS = (1 << np.arange(NUM_RANKS)).astype(np.int32)
for _c in range(NUM_CARDS):
    for _k, _p in enumerate(_CARD_PAIRS[_c]):
        _PLACE[_p, int(PAIRS[_p, 1] == _c)] = _c * (NUM_CARDS - 1) + _k


def _ranks(values: np.ndarray, *, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """For each entry of ``values`` (..., n): how many entries of its row are smaller, and
    how many equal it (itself included). ``bits``: the values lie in [-1, 2**bits).

    One sort of ``value << s | place`` gives the order and the sorted values together (a
    plain sort is several times faster than an argsort; in int32 when it fits)."""
    n = values.shape[-1]
    shift = int(n - 1).bit_length()
    dtype = np.int32 if bits + shift < 31 else np.int64
    widened = np.left_shift(values.astype(dtype), shift)
    keys = np.sort(np.bitwise_or(widened, np.arange(n).astype(dtype)), axis=-1)
    ordered, order = keys >> shift, keys & ((1 << shift) - 1)
    place = np.arange(n, dtype=np.int32)
    starts = np.ones(values.shape, dtype=bool)
    starts[..., 1:] = ordered[..., 1:] != ordered[..., :-1]
    first = np.maximum.accumulate(np.where(starts, place, 0), axis=-1)
    ends = np.ones(values.shape, dtype=bool)
    ends[..., :-1] = starts[..., 1:]
    last = np.minimum.accumulate(np.where(ends, place + 1, n)[..., ::-1], axis=-1)[..., ::-1]
    at = (order + np.arange(values.size // n).reshape((*order.shape[:-1], 1)) * n).reshape(-1)
    below, equal = np.empty(values.size, dtype=np.int32), np.empty(values.size, dtype=np.int32)
    below[at], equal[at] = first.reshape(-1), (last - first).reshape(-1)
    return below.reshape(values.shape), equal.reshape(values.shape)


def river_counts(boards: np.ndarray) -> np.ndarray:
    """(M, 1326) int32: ``2 x wins + ties`` of every hole pair against its 990 opponent
    hands on each of M five-card boards; 0 for pairs that share a card with the board.

    Every pair is ranked among the 1,081 that miss the board, and among the pairs holding
    each of its two cards (the opponents it cannot meet): wins = below all - below in the
    first card's pairs - below in the second's (only the pair itself holds both).
    """
    boards = np.asarray(boards, dtype=np.int64)
    if len(boards) > CHUNK_BOARDS:
        return np.concatenate([river_counts(boards[i : i + CHUNK_BOARDS])
                               for i in range(0, len(boards), CHUNK_BOARDS)])  # fmt: skip
    clash = CLASH[boards].any(axis=1)  # (M, 1326)
    strength = np.where(clash, -1, board_strengths(boards)).astype(np.int32)
    below, equal = _ranks(strength, bits=24)  # strengths stay below 2**24
    # Within each card's pairs, order by the global rank (the same order, fewer bits).
    by_card = below[:, _CARD_PAIRS]  # (M, 52, 51)
    card_below, card_equal = _ranks(by_card, bits=11)
    card_below = card_below.reshape(len(boards), -1)
    card_equal = card_equal.reshape(len(boards), -1)
    # Below counts include the pairs that hit the board (strength -1): 245 of all pairs, and
    # 5 of a card's 51 when the card itself misses the board.
    wins = (
        (below - (NUM_PAIRS - 1_081))
        - (card_below[:, _PLACE[:, 0]] - 5)
        - (card_below[:, _PLACE[:, 1]] - 5)
    )
    ties = equal - card_equal[:, _PLACE[:, 0]] - card_equal[:, _PLACE[:, 1]] + 1
    return np.where(clash, 0, 2 * wins + ties).astype(np.int32)


def hole_counts(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(N,) int64 ``2 x wins + ties`` of hole cards (N, 2) on five-card boards (N, 5) against
    the 990 opponent hands.

    Opponents are counted by their 91 rank combinations (how many unseen pairs each has,
    and its non-flush strength on the board), not one by one: where the board holds three or
    four of a suit, the pairs that complete a flush are then moved to their flush's
    strength; boards of five of a suit are ranked pair by pair (:func:`_pairwise_counts`).
    """
    holes = np.asarray(holes, dtype=np.int64)
    boards = np.asarray(boards, dtype=np.int64)
    found = np.empty(len(holes), dtype=np.int64)
    for first in range(0, len(holes), 4 * CHUNK_BOARDS):
        rows = slice(first, first + 4 * CHUNK_BOARDS)
        found[rows] = _combo_counts(holes[rows], boards[rows])
    return found


def _combo_counts(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    # Every row as if the board held no five of a suit, in few array operations (a DQN's
    # river rows come a few at a time); the rows whose board does are then ranked pair by
    # pair.
    board_suits = _CARD_SUIT[boards].sum(axis=1)
    suit_counts = (board_suits[:, None] >> _SUIT_FIELD_SHIFTS) & 15
    suit, most = suit_counts.argmax(axis=1), suit_counts.max(axis=1)
    board_key = _CARD_KEY[boards].sum(axis=1)
    hand_key = board_key + _CARD_KEY[holes].sum(axis=1)
    known = np.concatenate([holes, boards], axis=1)
    mine = _keyed_strengths(known, hand_key, board_suits + _CARD_SUIT[holes].sum(axis=1))
    plain, combo = _plain_counts(board_key, hand_key, mine)
    found = plain + _flush_corrections(known, mine, combo, suit, most)
    many = np.flatnonzero(most >= 5)  # a flush on the board: every pair plays one
    if many.size:
        found[many] = _pairwise_counts(holes[many], boards[many])
    return found


def _plain_counts(
    board_key: np.ndarray, hand_key: np.ndarray, mine: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(``2 x wins + ties`` against the 990 opponent hands as if no opponent held a flush,
    the opponents' non-flush strengths (m, 91) by rank combination) of hands whose five-card
    board has the rank key ``board_key`` (``_CARD_KEY`` summed), whose seven cards have
    ``hand_key`` and whose own strength is ``mine``.

    Both depend on the cards' ranks alone (and ``mine``): rivers of one rank that leave
    ``mine`` as it is share them (:func:`turn_counts`)."""
    keys, strengths = _board_combos()
    combo = strengths[np.searchsorted(keys, board_key)]
    # Unseen pairs of each rank combination (C(left, 2) of a pair of ranks, else the
    # product), read at 2 x (5 x left_a + left_b) + same, where left = 4 - the rank's digit
    # in the hand's key: one product of the digits (in float64, exact for these small
    # integers, where numpy's integer product is several times slower).
    digits = (hand_key[:, None] // _POW5_32 % 5).astype(np.float64)  # (m, 13) cards seen
    ways = _WAYS_FLAT[_WAYS_AT_NONE_SEEN - (digits @ _WAYS_STEP).astype(np.int64)]
    # 2 x wins + ties of a strength x against mine: (x < mine) + (x <= mine).
    me = mine[:, None]
    score = (combo < me).view(np.int8) + (combo <= me).view(np.int8)
    return (score * ways).sum(axis=1, dtype=np.int64), combo


@cache
def _board_combos() -> tuple[np.ndarray, np.ndarray]:
    """(sorted rank keys (K,) of the five-card boards' rank multisets, the non-flush strength
    (K, 91) int32 of each with each rank combination of two more cards): a board's 91
    opponents' strengths by one row gather (about 2 MB, built in a few ms)."""
    multisets = np.array(list(itertools.combinations_with_replacement(range(NUM_RANKS), 5)))
    keys = np.unique(_POW5_32[multisets].sum(axis=1))  # sum 5**rank, as _CARD_KEY sums
    keys = keys[_digits_at_most_4(keys)]
    return keys, _non_flush(keys[:, None] + _COMBO_KEY[None, :])


def _digits_at_most_4(keys: np.ndarray) -> np.ndarray:
    """Where base-5 rank keys hold no rank five times (no digit carried past 4)."""
    ok = np.ones(keys.shape, dtype=bool)
    rest = keys.astype(np.int64)
    for _ in range(NUM_RANKS):
        ok &= rest % 5 <= 4
        rest = rest // 5
    return ok


def _flush_corrections(
    known: np.ndarray, mine: np.ndarray, combo: np.ndarray, suit: np.ndarray, most: np.ndarray
) -> np.ndarray:
    """What :func:`_plain_counts` misses on boards (``known[:, 2:]``) with ``most`` (< 5) cards
    of ``suit``: the unseen pairs that complete the board's suit hold a flush, not their
    non-flush strength (``combo``).

    Beside three of the suit, the pairs of two cards of it complete it (78, pair by pair).
    Beside four, so do the pairs of one card of it and one of another suit (507): those are
    counted by ranks (13 x 13, :func:`_one_suited_gains`), since the flush depends on the
    suited card's rank alone and the non-flush strength on the two ranks."""
    found = np.zeros(len(known), dtype=np.int64)
    at = np.flatnonzero(most >= 3)
    if at.size == 0:
        return found
    s = suit[at]
    board = known[at, 2:]
    board_bits = np.where(_SUIT[board] == s[:, None], _CARD_BIT[board], 0)
    board_bits = board_bits.sum(axis=1, dtype=np.int32)
    card_bits, suit_bits, combos = _TWO_SUITED_BITS
    known_bits = np.bitwise_or.reduce(np.int64(1) << known[at], axis=1)
    unseen = (card_bits[s] & known_bits[:, None]) == 0
    # No quads or full house fit beside a flush in seven cards: the flush is the hand.
    flush = _dense().flush[board_bits[:, None] | suit_bits[s]]
    plain = combo.reshape(-1)[(at * combo.shape[1])[:, None] + combos[s]]  # one gather
    me = mine[at, None]
    gained = np.where(unseen, _score(flush, me) - _score(plain, me), 0)
    found[at] = gained.sum(axis=1, dtype=np.int64)
    four = np.flatnonzero(most[at] == 4)
    if four.size:
        rows = at[four]
        found[rows] += _one_suited_gains(known[rows], mine[rows], combo[rows], s[four],
                                         board_bits[four])  # fmt: skip
    return found


def _score(strength: np.ndarray, me: np.ndarray) -> np.ndarray:
    """``2 x wins + ties`` (int8) of a hand of strength ``me`` against ``strength``."""
    return (strength < me).view(np.int8) + (strength <= me).view(np.int8)


def _one_suited_gains(
    known: np.ndarray, mine: np.ndarray, combo: np.ndarray, suit: np.ndarray,
    board_bits: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The flush correction of the unseen pairs of one card of ``suit`` (rank a) and one of
    another suit (rank b), beside four of the suit on the board (rank bits ``board_bits``):
    the flush of rank a against the non-flush strength of (a, b), times the unseen such
    pairs (a unseen in the suit, times the unseen cards of rank b outside it)."""
    m = len(known)
    seen = np.zeros((m, NUM_CARDS), dtype=bool)
    seen[np.arange(m)[:, None], known] = True
    by_rank = seen[:, _CARD_OF].reshape(m, 4, NUM_RANKS)  # (m, suit, rank)
    suited = ~by_rank[np.arange(m), suit]  # (m, 13): rank a unseen in the suit
    others = (3 - by_rank.sum(axis=1) + ~suited).astype(np.int64)  # unseen outside the suit
    me = mine[:, None]
    flush = _score(_dense().flush[board_bits[:, None] | _RANK_BITS], me)  # (m, 13) by a
    plain = _score(combo[:, _COMBO_OF.reshape(-1)], me).reshape(m, NUM_RANKS, NUM_RANKS)
    per_a = flush * others.sum(axis=1, keepdims=True) - (plain * others[:, None, :]).sum(axis=2)
    return np.where(suited, per_a, 0).sum(axis=1, dtype=np.int64)


def _pairwise_counts(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """:func:`hole_counts` by ranking all 1,326 pairs on each board."""
    found = np.empty(len(holes), dtype=np.int64)
    for first in range(0, len(holes), CHUNK_BOARDS):
        rows = slice(first, first + CHUNK_BOARDS)
        hole, board = holes[rows], boards[rows]
        strength = board_strengths(board)
        mine = strength[np.arange(len(hole)), pair_index(hole[:, 0], hole[:, 1])]
        seen = np.concatenate([hole, board], axis=1)
        opponent = ~CLASH[seen].any(axis=1)
        wins = (opponent & (strength < mine[:, None])).sum(axis=1)
        ties = (opponent & (strength == mine[:, None])).sum(axis=1)
        found[rows] = 2 * wins + ties
    return found


def river_equity(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(N,) exact equity of hole cards (N, 2) on five-card boards (N, 5)."""
    return _street_equity(_pair_numbers(holes), boards)


def _unseen(known: np.ndarray) -> np.ndarray:
    """(N, 52 - k) the cards not in each row of ``known`` (N, k), ascending."""
    free = np.ones((len(known), NUM_CARDS), dtype=bool)
    free[np.arange(len(known))[:, None], known] = False
    return np.nonzero(free)[1].reshape(len(known), NUM_CARDS - known.shape[1])


def turn_counts(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(N,) int64 ``2 x wins + ties`` summed over the 46 rivers of four-card boards (N, 4).

    A river's count is a part that depends on the ranks alone and the hand's own strength
    (:func:`_plain_counts`), plus, where the five-card board holds three or four of a suit,
    the opponents' flushes (:func:`_flush_corrections`). The rivers of one rank that give
    the hand the same strength (all but those that make its own flush) share the first
    part: counted once, weighted by how many they are (about 13 of the 46 rivers are
    counted); those off the board's flush suit share the second as well. A board of five
    of a suit is counted one pair at a time (:func:`_pairwise_counts`)."""
    holes = np.asarray(holes, dtype=np.int64)
    boards = np.asarray(boards, dtype=np.int64)
    if len(holes) > TURN_CHUNK:  # bounded temporaries: 46 rivers of each state at once
        return np.concatenate([turn_counts(holes[i : i + TURN_CHUNK], boards[i : i + TURN_CHUNK])
                               for i in range(0, len(holes), TURN_CHUNK)])  # fmt: skip
    n = len(holes)
    rivers = _unseen(np.concatenate([holes, boards], axis=1)).reshape(-1)  # (N * 46,)
    state = np.repeat(np.arange(n), TURN_RIVERS)
    five = np.concatenate([boards[state], rivers[:, None]], axis=1)
    known = np.concatenate([holes[state], five], axis=1)
    suit_counts = (_card_sum(_CARD_SUIT, five)[:, None] >> (4 * np.arange(4))) & 15
    suit, most = suit_counts.argmax(axis=1), suit_counts.max(axis=1)
    found = np.zeros(n, dtype=np.int64)
    full = np.flatnonzero(most >= 5)  # a flush on the board: every pair plays one
    if full.size:
        found += np.bincount(state[full], _pairwise_counts(holes[state[full]], five[full]),
                             minlength=n).astype(np.int64)  # fmt: skip
    rest = np.flatnonzero(most < 5)
    mine = seven_card_strengths(known[rest])
    # Strengths stay below 2**24: (state, river rank, strength) as one int64 key, a group.
    group_key = (state[rest] * NUM_RANKS + _RANK[rivers[rest]]) << 24 | mine
    _, first, group, weight = np.unique(group_key, return_index=True, return_inverse=True,
                                        return_counts=True)  # fmt: skip
    rows = rest[first]
    board_key = _card_sum(_CARD_KEY, five[rows])
    hand_key = board_key + _card_sum(_CARD_KEY, holes[state[rows]])
    plain, combo = _plain_counts(board_key, hand_key, mine[first])
    found += np.bincount(state[rows], plain * weight, minlength=n).astype(np.int64)
    # Opponents' flushes, where the board holds three or four of a suit. A river of that suit
    # changes who can flush: it is counted alone. The group's other rivers leave the board's
    # suited cards, and how many unseen cards of each rank are left outside the suit, as
    # they are: they share the correction. (Two rivers of one rank, of two suits of two
    # cards each, make three of different suits: two corrections.)
    flushing = np.flatnonzero(most[rest] >= 3)
    if flushing.size:
        river_suit = _SUIT[rivers[rest[flushing]]]
        suited = np.where(river_suit == suit[rest[flushing]], 1 + river_suit, 0)
        key = group.reshape(-1)[flushing] * 5 + suited
        _, pick, times = np.unique(key, return_index=True, return_counts=True)
        at = rest[flushing[pick]]
        corrections = _flush_corrections(known[at], mine[flushing[pick]],
                                         combo[group.reshape(-1)[flushing[pick]]], suit[at],
                                         most[at])  # fmt: skip
        found += np.bincount(state[at], corrections * times, minlength=n).astype(np.int64)
    return found


def turn_equity(holes: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(N,) exact equity of hole cards (N, 2) on four-card boards (N, 4): read from the turn
    table where it is built (:func:`turn_table`), else counted; the same integers."""
    return _street_equity(_pair_numbers(holes), boards)


def all_pairs_turn_counts(board: np.ndarray) -> np.ndarray:
    """(1326,) int64 :func:`turn_counts` of every pair on one four-card board (0 for pairs
    that meet it): :func:`river_counts` on its 48 rivers, summed (a river that meets a pair
    counts 0 for it, so each pair sums its own 46)."""
    board = np.asarray(board, dtype=np.int64)
    rivers = np.setdiff1d(np.arange(NUM_CARDS), board)
    boards = np.concatenate([np.broadcast_to(board, (len(rivers), 4)), rivers[:, None]], axis=1)
    return river_counts(boards).sum(axis=0, dtype=np.int64)


@lru_cache(maxsize=4096)
def _cached_turn_counts(board: tuple[int, ...]) -> np.ndarray:
    """:func:`all_pairs_turn_counts` kept for recent boards (a state's rows come back at the
    agent's next decision on the same turn): 4,096 boards, about 40 MB."""
    found = all_pairs_turn_counts(np.array(board))
    found.flags.writeable = False
    return found


@lru_cache(maxsize=4096)
def _cached_river_counts(board: tuple[int, ...]) -> np.ndarray:
    """:func:`river_counts` of one board kept for recent boards, as the turn's: 4,096 boards,
    about 40 MB."""
    found = river_counts(np.array(board, dtype=np.int64)[None])[0].astype(np.int64)
    found.flags.writeable = False
    return found


# Rows sharing a board from which every pair's count is computed at once, not row by row
# (local best response encodes the live pairs of one state, and again at its next decision:
# a board's counts are cached). Row by row a turn state costs about 1/60 of a board's
# all pairs, a river state 1/50.
ALL_PAIRS_TURN_ROWS = 16
ALL_PAIRS_RIVER_ROWS = 64


# A sorted turn or river board's number (one int a set): its cards as base-52 digits.
_PLACES = {size: NUM_CARDS ** np.arange(size, dtype=np.int64) for size in (4, 5)}


def _by_board(
    per_row: Callable[[np.ndarray, np.ndarray], np.ndarray],
    all_pairs: Callable[[np.ndarray], np.ndarray],
    pairs: np.ndarray,
    boards: np.ndarray,
    least: int,
) -> np.ndarray:
    """``per_row(pairs, boards)``, with the boards shared by at least ``least`` rows done by
    ``all_pairs(board)`` once: the same integers either way."""
    boards = np.sort(np.asarray(boards, dtype=np.int64), axis=1)  # a board is a set
    if len(pairs) < least:  # no board can have enough rows
        return per_row(pairs, boards)
    found = np.empty(len(pairs), dtype=np.int64)
    code = boards @ _PLACES[boards.shape[1]]  # one int a set
    _, first, group, sizes = np.unique(code, return_index=True, return_inverse=True,
                                       return_counts=True)  # fmt: skip
    group = group.reshape(-1)
    shared = sizes[group] >= least
    for k in np.flatnonzero(sizes >= least):
        rows = np.flatnonzero(group == k)
        found[rows] = all_pairs(boards[first[k]])[pairs[rows]]
    rows = np.flatnonzero(~shared)
    if rows.size:
        found[rows] = per_row(pairs[rows], boards[rows])
    return found


class _RecentCounts:
    """``per_row(pairs, boards)`` remembered for recent states (hole pair and sorted board):
    a player who acts again on the same street (checks, then calls a raise) is the same
    state again, at a later lock-step (about a quarter of a DQN's turn states). The same
    integers either way; at most ``size`` states are kept (then it starts afresh)."""

    def __init__(self, per_row: Callable[[np.ndarray, np.ndarray], np.ndarray], size: int):
        self.per_row = per_row
        self.size = size
        self.counts: dict[int, int] = {}

    def __call__(self, pairs: np.ndarray, boards: np.ndarray) -> np.ndarray:
        """``per_row`` of pair numbers ``pairs`` (n,) on ``boards`` (n, k) sorted along each
        row."""
        size = boards.shape[1]
        code = (pairs * NUM_CARDS**size + boards @ _PLACES[size]).tolist()
        known = [self.counts.get(key, -1) for key in code]
        missing = [i for i, count in enumerate(known) if count < 0]
        found = np.array(known, dtype=np.int64)
        if missing:
            found[missing] = counted = self.per_row(pairs[missing], boards[missing])
            if len(self.counts) + len(missing) > self.size:
                self.counts.clear()
            self.counts.update(zip([code[i] for i in missing], counted.tolist(), strict=True))
        return found


_RIVER_ROWS = _RecentCounts(lambda pairs, boards: hole_counts(PAIRS[pairs], boards), 1 << 16)
_TURN_ROWS = _RecentCounts(lambda pairs, boards: turn_counts(PAIRS[pairs], boards), 1 << 16)


def forget_recent_states() -> None:
    """Empty the memory of recent states' counts (the rows' and the boards'): what a
    benchmark does between repeats of one seed, so that no repeat reads the one before."""
    _RIVER_ROWS.counts.clear()
    _TURN_ROWS.counts.clear()
    _cached_turn_counts.cache_clear()
    _cached_river_counts.cache_clear()


def _set_code(boards: np.ndarray) -> np.ndarray:
    """A number for each set of cards (any order; the last axis): sorted, base 52, the
    smallest card the most significant digit (so that itertools' combinations ascend)."""
    ordered = np.sort(np.asarray(boards, dtype=np.int64), axis=-1)
    size = ordered.shape[-1]
    return ordered @ (NUM_CARDS ** np.arange(size - 1, -1, -1, dtype=np.int64))


class BoardClasses(NamedTuple):
    """The k-card boards up to a permutation of the suits (which changes no equity).

    A class's representative is the permuted board with the smallest code; a board's
    permutation is the first of the 24 (itertools order) that takes it there. A board is
    found by its colex number (:func:`_colex`), which numbers the k-card sets without a
    search."""

    codes: np.ndarray  # (C(52, k),) every board's code, ascending
    class_of: np.ndarray  # (C(52, k),) its class
    perm: np.ndarray  # (C(52, k),) the suit permutation taking it to its representative
    representatives: np.ndarray  # (classes, k)
    colex_class: np.ndarray  # (C(52, k),) class_of, by the board's colex number
    colex_perm: np.ndarray  # (C(52, k),) perm, by the board's colex number

    def find(self, boards: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(class, suit permutation) of each board (N, k), its cards in any order: the hole
        pair is mapped through ``_PERMUTED_PAIR[perm]`` to read the class's row."""
        at = _colex(np.sort(np.asarray(boards, dtype=np.int64), axis=-1))
        return self.colex_class[at], self.colex_perm[at]


# _BINOMIAL[i * 52 + c] = C(c, i): the i-th smallest card c of a set adds C(c, i) to its colex
# number, which numbers the k-card sets 0 .. C(52, k) - 1.
_BINOMIAL = np.array([math.comb(c, i) for i in range(6) for c in range(NUM_CARDS)], np.int64)


def _colex(boards: np.ndarray) -> np.ndarray:
    """(N,) the colex number of each set of cards (N, k), sorted ascending along each row."""
    return _BINOMIAL[boards + NUM_CARDS * np.arange(1, boards.shape[1] + 1)].sum(axis=1)


@cache
def board_classes(size: int) -> BoardClasses:
    """:class:`BoardClasses` of the ``size``-card boards: 1,755 flops, 16,432 turns."""
    boards = np.array(list(itertools.combinations(range(NUM_CARDS), size)), dtype=np.int64)
    codes = _set_code(boards)
    smallest, perm = codes.copy(), np.zeros(len(boards), dtype=np.int8)
    for k in range(1, len(_SUIT_PERMS)):  # one permutation at a time: bounded memory
        permuted = _set_code(_PERMUTED_CARD[k, boards])
        better = permuted < smallest  # strictly: the first permutation wins a tie
        smallest[better], perm[better] = permuted[better], k
    classes, class_of = np.unique(smallest, return_inverse=True)
    expected = {3: FLOP_CLASSES, 4: TURN_CLASSES}.get(size)
    if expected is not None and classes.size != expected:
        raise AssertionError(f"{classes.size} {size}-card classes, expected {expected}")
    digits = NUM_CARDS ** np.arange(size - 1, -1, -1, dtype=np.int64)
    representatives = classes[:, None] // digits % NUM_CARDS
    colex_class, colex_perm = np.empty_like(class_of, np.int16), np.empty_like(perm)
    at = _colex(boards)  # itertools' combinations ascend along each row
    colex_class[at], colex_perm[at] = class_of, perm
    return BoardClasses(codes, class_of.astype(np.int16), perm, representatives, colex_class,
                        colex_perm)  # fmt: skip


def flop_class_counts(flop: np.ndarray) -> np.ndarray:
    """(1326,) int64: each pair's ``2 x wins + ties`` summed over the 1,081 runouts of one
    flop (3,) that miss it (0 for pairs holding a flop card): one row of the table."""
    flop = np.asarray(flop, dtype=np.int64)
    rest = np.setdiff1d(np.arange(NUM_CARDS), flop)
    runouts = np.array(list(itertools.combinations(rest, 2)), dtype=np.int64)  # 1,176
    boards = np.concatenate([np.broadcast_to(flop, (len(runouts), 3)), runouts], axis=1)
    return river_counts(boards).sum(axis=0, dtype=np.int64)


def build_flop_table(*, on_class: Callable[[int], None] | None = None) -> np.ndarray:
    """(1755, 1326) uint32: :func:`flop_class_counts` of each flop class's representative
    (``on_class(k)`` after class k: a progress hook)."""
    representatives = board_classes(3).representatives
    table = np.zeros((FLOP_CLASSES, NUM_PAIRS), dtype=np.uint32)
    for k, flop in enumerate(representatives):
        table[k] = flop_class_counts(flop)
        if on_class is not None:
            on_class(k)
    return table


def table_digest(table: np.ndarray) -> str:
    """SHA-256 of the table's bytes (little-endian uint32, C order)."""
    return hashlib.sha256(np.ascontiguousarray(table, dtype="<u4").tobytes()).hexdigest()


@cache
def flop_table() -> np.ndarray:
    """The shipped flop table, checked against :data:`FLOP_TABLE_SHA256`."""
    with np.load(FLOP_TABLE_FILE, allow_pickle=False) as data:
        table = data["counts"].astype(np.uint32)
    if table.shape != (FLOP_CLASSES, NUM_PAIRS) or table_digest(table) != FLOP_TABLE_SHA256:
        raise RuntimeError(f"{FLOP_TABLE_FILE} is not the flop table this version shipped")
    return table


# The turn table: every turn class's :func:`all_pairs_turn_counts` (16,432 x 1,326 uint32,
# 87 MB), built once into the data cache (about 90 s of one quiet core), not shipped.
TURN_TABLE_SHA256 = "ee212a81133e23db8fe4f15ba7c099b6de6ed2cd6a16344efaadbbefa57d2b84"


@dataclass
class _TurnTableUse:
    """Whether turn states read the table (:func:`use_turn_table`), and the table once loaded."""

    enabled: bool = True
    table: np.ndarray | None = None


_TURN_TABLE = _TurnTableUse()


def turn_table_path() -> Path:
    """Where the turn table is built and read: the data cache (``$POKERIRL_DATA``)."""
    return cache_folder() / TURN_TABLE_NAME


def turn_table() -> np.ndarray | None:
    """The turn table, memory-mapped and checked against :data:`TURN_TABLE_SHA256` once a
    process; ``None`` where it is not built (or :func:`use_turn_table` turned it off).
    :class:`InputError` for a file there that is not it."""
    if not _TURN_TABLE.enabled:
        return None
    if _TURN_TABLE.table is None:
        path = turn_table_path()
        if not path.is_file():
            return None
        table = np.load(path, mmap_mode="r", allow_pickle=False)
        if table.shape != (TURN_CLASSES, NUM_PAIRS) or table_digest(table) != TURN_TABLE_SHA256:
            raise InputError(f"{path} is not the turn table this version builds: delete it")
        _TURN_TABLE.table = table
    return _TURN_TABLE.table


def use_turn_table(enabled: bool) -> None:
    """Read the turn table where it is built (the default), or count every turn state (a
    benchmark's baseline, a test of both paths): the same integers either way."""
    _TURN_TABLE.enabled = enabled


def build_turn_table(
    path: Path, *, on_class: Callable[[int], None] | None = None
) -> np.ndarray:
    """Count every turn class's pairs (:func:`all_pairs_turn_counts` of its representative)
    and write the table to ``path`` (:func:`~pokerirl.atomic.atomic_path`: the temporary file
    is made before the counting, so that a place it cannot write fails at once, and an
    interrupted build leaves nothing); ``on_class(k)`` after class k. Returns the table.
    A table whose SHA-256 is not :data:`TURN_TABLE_SHA256` is a bug: ``RuntimeError``, and
    nothing is written."""
    representatives = board_classes(4).representatives
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as temporary:
        table = np.zeros((TURN_CLASSES, NUM_PAIRS), dtype="<u4")
        for k, board in enumerate(representatives):
            table[k] = all_pairs_turn_counts(board)
            if on_class is not None:
                on_class(k)
        digest = table_digest(table)
        if digest != TURN_TABLE_SHA256:
            raise RuntimeError(f"the turn table built has SHA-256 {digest}, not the recorded one")
        with temporary.open("wb") as out:
            np.save(out, table, allow_pickle=False)
    _TURN_TABLE.table = None  # the next read loads (and checks) the new file
    return table


def flop_counts(holes: np.ndarray, flops: np.ndarray) -> np.ndarray:
    """(N,) int64 ``2 x wins + ties`` over all runouts, from the table."""
    return _class_counts(flop_table(), board_classes(3), holes, flops)


def _class_counts(
    table: np.ndarray, classes: BoardClasses, holes: np.ndarray, boards: np.ndarray
) -> np.ndarray:
    """(N,) int64: each state's count read from a table of (board class, hole pair)."""
    return _pair_class_counts(table, classes, _pair_numbers(holes), boards, slice(None))


def _pair_class_counts(
    table: np.ndarray, classes: BoardClasses, pairs: np.ndarray, boards: np.ndarray,
    of: np.ndarray | slice = slice(None),
) -> np.ndarray:  # fmt: skip
    """(R,) int64: the count of pair ``pairs[r]`` on board ``boards[of[r]]`` read from a
    table of (board class, hole pair); each board's class found once."""
    k, perm = classes.find(boards)
    return np.asarray(table[k[of], _PERMUTED_PAIR[perm[of], pairs]], dtype=np.int64)


def flop_equity(holes: np.ndarray, flops: np.ndarray) -> np.ndarray:
    """(N,) exact equity of hole cards (N, 2) on flops (N, 3)."""
    return _street_equity(_pair_numbers(holes), flops)


def preflop_counts() -> np.ndarray:
    """(1326,) int64: each pair's count summed over every flop and runout (exact)."""
    classes = board_classes(3)  # every flop, in code order
    table = flop_table()
    total = np.zeros(NUM_PAIRS, dtype=np.int64)
    for first in range(0, len(classes.codes), 1_000):
        rows = slice(first, first + 1_000)
        pairs = _PERMUTED_PAIR[classes.perm[rows].astype(np.int64)]  # (k, 1326)
        total += table[classes.class_of[rows].astype(np.int64)[:, None], pairs].sum(
            axis=0, dtype=np.int64
        )
    return total


# Rows of one board from which a range's equities are read from the board's counts of every
# pair (computed once and cached), not counted row by row (see ALL_PAIRS_RIVER_ROWS).
RANGE_ROWS = 16


def range_equity(pairs: np.ndarray, boards: np.ndarray, of: np.ndarray | None) -> np.ndarray:
    """(R,) exact equity of hole pair ``pairs[r]`` (a number of ``PAIRS``) on board
    ``boards[of[r]]`` (boards (n, 5), ``-1`` beyond the cards shown; ``of`` None: board r): what
    :func:`exact_equity` gives those states, with each board's work done once for all its
    rows (its class and suit permutation, or its counts of every pair) where it has at least
    :data:`RANGE_ROWS` of them, as the many pairs of a range in local best response.

    >>> board = np.array([[0, 14, 28, -1, -1]])  # A, 2, 3 of three suits
    >>> cards = np.concatenate([PAIRS[[5, 900]], np.repeat(board, 2, axis=0)], axis=1)
    >>> bool((range_equity(np.array([5, 900]), board, np.array([0, 0]))
    ...       == exact_equity(cards)).all())
    True
    """
    pairs, boards = np.asarray(pairs, dtype=np.int64), np.asarray(boards, dtype=np.int64)
    if of is None:
        return _row_equity(pairs, boards)
    of = np.asarray(of, dtype=np.int64)
    rows_of_state = np.bincount(of, minlength=len(boards))
    if len(pairs) < RANGE_ROWS or rows_of_state.max() < RANGE_ROWS:  # a DQN: a row a state
        return _row_equity(pairs, boards[of])
    found = np.empty(len(pairs))
    shared = rows_of_state[of] >= RANGE_ROWS
    alone = np.flatnonzero(~shared)
    if alone.size:
        found[alone] = _row_equity(pairs[alone], boards[of[alone]])
    rows = np.flatnonzero(shared)
    shown = (boards >= 0).sum(axis=1)[of[rows]]
    preflop = rows[shown == 0]
    if preflop.size:
        found[preflop] = _PREFLOP_EQUITY[pairs[preflop]]
    for count in (3, 4, 5):
        at = rows[shown == count]
        if at.size == 0:
            continue
        states, row_state = np.unique(of[at], return_inverse=True)
        board = np.sort(boards[states, :count], axis=1)  # a board is a set
        table = _street_table(count)
        if table is not None:
            counts = _pair_class_counts(table, board_classes(count), pairs[at], board, row_state)
        else:  # every pair's counts of each board, kept for its next decision
            every = np.stack([_every_pair_counts(tuple(b)) for b in board.tolist()])
            counts = every[row_state, pairs[at]]
        found[at] = counts / _DENOMINATOR[count]
    return found


_PREFLOP_EQUITY = preflop_equity(PAIRS)  # (1326,) by pair number


def exact_equity(cards: np.ndarray) -> np.ndarray:
    """(N,) exact equity of states' cards (N, 7): hole cards, then the board shown (``-1``
    beyond, 0, 3, 4 or 5 cards)."""
    cards = np.asarray(cards, dtype=np.int64)
    return _row_equity(_pair_numbers(cards[:, :2]), cards[:, 2:])


def _row_equity(pairs: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(R,) exact equity of hole pair ``pairs[r]`` on board ``boards[r]`` (R, 5), ``-1``
    beyond the cards shown: each street's rows at once, in few array operations (a DQN's
    batches are small and many: their cost is per call, not per row)."""
    boards = np.sort(boards, axis=1)  # a board is a set: the cards shown last, ascending
    shown = (boards >= 0).sum(axis=1)
    found = np.empty(len(pairs))
    for count in (0, 3, 4, 5):
        rows = np.flatnonzero(shown == count)
        if rows.size:
            found[rows] = _street_equity(pairs[rows], boards[rows, 5 - count :])
    return found


def _street_equity(pairs: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(R,) exact equity of hole pair ``pairs[r]`` on board ``boards[r]`` (R, k), k = 0, 3,
    4 or 5 cards, in any order: preflop and flop from their tables, the turn from its table
    where built, else counted, the river counted (rows of a board shared by many at once)."""
    boards = np.asarray(boards, dtype=np.int64)
    count = boards.shape[1]
    if count == 0:
        return _PREFLOP_EQUITY[pairs]
    table = _street_table(count)
    if table is not None:
        counts = _pair_class_counts(table, board_classes(count), pairs, boards)
    else:  # row by row, or every pair's counts of a board many rows share
        recent, least = _counted(count)
        every = lambda board: _every_pair_counts(tuple(board.tolist()))  # noqa: E731
        counts = _by_board(recent, every, pairs, boards, least)
    return counts / _DENOMINATOR[count]


_DENOMINATOR = {3: FLOP_DENOMINATOR, 4: TURN_DENOMINATOR, 5: RIVER_DENOMINATOR}  # by cards shown


def _street_table(count: int) -> np.ndarray | None:
    """The (board class, hole pair) counts of the street with ``count`` board cards: the
    flop's (shipped), the turn's where built; ``None``: counted."""
    return flop_table() if count == 3 else turn_table() if count == 4 else None


def _counted(count: int) -> tuple[_RecentCounts, int]:
    """A counted street's memory of recent rows, and how many rows share a board before it
    is counted whole (read when called: the tests stand in for them)."""
    if count == 4:
        return _TURN_ROWS, ALL_PAIRS_TURN_ROWS
    return _RIVER_ROWS, ALL_PAIRS_RIVER_ROWS


def _every_pair_counts(board: tuple[int, ...]) -> np.ndarray:
    """(1326,) every pair's count on a turn or river board (its sorted cards), cached."""
    return _cached_turn_counts(board) if len(board) == 4 else _cached_river_counts(board)


def _pair_numbers(holes: np.ndarray) -> np.ndarray:
    """(N,) the pair number of each row of hole cards (N, 2)."""
    holes = np.asarray(holes, dtype=np.int64)
    return pair_index(holes[:, 0], holes[:, 1])
