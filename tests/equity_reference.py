"""Brute-force equity references for tests/test_equity.py and benchmarks/equity.py.

Nothing here shares code with :mod:`pokerirl.game.equity`: every opponent hand and every
runout is enumerated one by one and ranked by an independent evaluator (``eval7``), or, for
the flop's million cases a state, by the engine's original seven-card
:func:`~pokerirl.game.evaluator.hand_strength` (binary search, tested against RLCard's
``compare_hands``), never by the board ranking the tables are made with.
"""

from __future__ import annotations

import itertools

import numpy as np

from pokerirl.game.evaluator import hand_strength
from pokerirl.holdem import NUM_CARDS, card_str


def eval7_cards() -> list:
    """eval7's Card for each of our 52 card indices."""
    import eval7

    return [eval7.Card(card_str(c)[0] + card_str(c)[1].lower()) for c in range(NUM_CARDS)]


def eval7_count(hole: np.ndarray, board: np.ndarray, deck: list | None = None) -> int:
    """``2 x wins + ties`` of ``hole`` over every opponent hand and every runout of ``board``
    (3 to 5 cards), each ranked by eval7."""
    import eval7

    deck = deck or eval7_cards()
    known = {int(c) for c in hole} | {int(c) for c in board}
    unseen = [c for c in range(NUM_CARDS) if c not in known]
    mine = [deck[int(c)] for c in hole]
    total = 0
    for runout in itertools.combinations(unseen, 5 - len(board)):
        full = [deck[int(c)] for c in board] + [deck[c] for c in runout]
        ours = eval7.evaluate(mine + full)
        rest = [c for c in unseen if c not in runout]
        for a, b in itertools.combinations(rest, 2):
            theirs = eval7.evaluate([deck[a], deck[b], *full])
            total += 2 if ours > theirs else ours == theirs
    return total


def engine_flop_count(hole: np.ndarray, flop: np.ndarray) -> int:
    """``2 x wins + ties`` of ``hole`` over the 1,081 runouts and 990 opponents of a flop,
    every seven-card hand ranked by :func:`hand_strength` (one call, 1.07 million rows)."""
    known = {int(c) for c in hole} | {int(c) for c in flop}
    unseen = np.array([c for c in range(NUM_CARDS) if c not in known])
    runouts = np.array(list(itertools.combinations(range(len(unseen)), 2)))  # (1081, 2)
    boards = np.concatenate([np.broadcast_to(flop, (len(runouts), 3)), unseen[runouts]], 1)
    ours = hand_strength(np.concatenate([np.broadcast_to(hole, (len(boards), 2)), boards], 1))
    keep = np.ones((len(runouts), len(unseen)), dtype=bool)
    keep[np.arange(len(runouts))[:, None], runouts] = False
    rest = np.broadcast_to(unseen, keep.shape)[keep].reshape(len(runouts), -1)  # (1081, 45)
    pairs = np.array(list(itertools.combinations(range(rest.shape[1]), 2)))  # (990, 2)
    opponents = rest[:, pairs]  # (1081, 990, 2)
    full = np.broadcast_to(boards[:, None, :], (len(boards), len(pairs), 5))
    theirs = hand_strength(np.concatenate([opponents, full], axis=2).reshape(-1, 7))
    theirs = theirs.reshape(len(boards), len(pairs))
    return int(2 * (ours[:, None] > theirs).sum() + (ours[:, None] == theirs).sum())


def engine_turn_count(hole: np.ndarray, board: np.ndarray) -> int:
    """``2 x wins + ties`` of ``hole`` over the 46 rivers and 990 opponents of a four-card
    board: all 45,540 opponent hands and 46 own ranked by :func:`hand_strength` at once."""
    known = {int(c) for c in hole} | {int(c) for c in board}
    unseen = np.array([c for c in range(NUM_CARDS) if c not in known])
    pairs = np.array(list(itertools.combinations(range(len(unseen) - 1), 2)))  # of 45 cards
    total = 0
    rivers = unseen
    boards = np.concatenate([np.broadcast_to(board, (len(rivers), 4)), rivers[:, None]], 1)
    ours = hand_strength(np.concatenate([np.broadcast_to(hole, (len(boards), 2)), boards], 1))
    rest = np.array([np.delete(unseen, k) for k in range(len(unseen))])  # (46, 45)
    opponents = rest[:, pairs]  # (46, 990, 2)
    full = np.broadcast_to(boards[:, None, :], (len(boards), len(pairs), 5))
    theirs = hand_strength(np.concatenate([opponents, full], axis=2).reshape(-1, 7))
    theirs = theirs.reshape(len(boards), len(pairs))
    total = int(2 * (ours[:, None] > theirs).sum() + (ours[:, None] == theirs).sum())
    return total
