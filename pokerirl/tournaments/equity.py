"""Showdown equity for local best response and the AIVAT corrections: hole-card pairs against
many boards at once, ranked exactly as :func:`pokerirl.game.evaluator.hand_strength` ranks.

The 1,326 hole-card pairs are numbered in :data:`PAIRS` (``(a, b)`` with ``a < b``, card
indices of :mod:`pokerirl.holdem`). :func:`board_strengths` ranks every pair on every
one of M five-card boards in one vectorized pass; the ranks equal ``hand_strength`` of the
seven cards (``tests/test_lbr.py`` checks it on random boards), but a board's rank key is
summed once and shared by the 91 rank combinations of a pair, so it runs many times faster
than calling ``hand_strength`` on M x 1,326 rows. Pairs that share a card with their board
get a meaningless strength: callers mask them with :data:`CLASH`.

>>> from pokerirl.holdem import parse_card
>>> board = np.array([[parse_card(c) for c in "As Ks Qs 7d 2c".split()]])
>>> aces, tens = pair_index(parse_card("Ah"), parse_card("Ad")), pair_index(
...     parse_card("Js"), parse_card("Ts"))
>>> strength = board_strengths(board)
>>> bool(strength[0, tens] > strength[0, aces])  # a royal flush beats trip aces
True
"""

from __future__ import annotations

import numpy as np

from pokerirl.game.evaluator import (  # the shared evaluator, re-exported for LBR and AIVAT
    _CARD_KEY,
    _CARD_SUIT,
    CLASH,
    _card_sum,
    _flushable,
    _non_flush,
    board_strengths,
    hand_strength,  # noqa: F401 (doctests)
    hole_strengths,
    pair_index,
    win_share,
)
from pokerirl.holdem import NUM_PAIRS, PAIRS

__all__ = ["CLASH", "NUM_PAIRS", "PAIRS", "board_strengths", "hole_strengths", "pair_index",
           "showdown_shares", "win_share"]  # fmt: skip

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
