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

from pokerirl.encoding import NUM_CARDS, card_str
from pokerirl.game.evaluator import hand_strength


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
    every seven-card hand ranked by :func:`hand_strength` (vectorized, 2.1 million rows)."""
    known = {int(c) for c in hole} | {int(c) for c in flop}
    unseen = np.array([c for c in range(NUM_CARDS) if c not in known])
    runouts = np.array(list(itertools.combinations(unseen, 2)))  # (1081, 2)
    boards = np.concatenate([np.broadcast_to(flop, (len(runouts), 3)), runouts], axis=1)
    ours = hand_strength(np.concatenate([np.broadcast_to(hole, (len(boards), 2)), boards], 1))
    total = 0
    for k, board in enumerate(boards):
        rest = np.setdiff1d(unseen, runouts[k])
        opponents = np.array(list(itertools.combinations(rest, 2)))  # (990, 2)
        theirs = hand_strength(np.concatenate(
            [opponents, np.broadcast_to(board, (len(opponents), 5))], axis=1))  # fmt: skip
        total += int(2 * (ours[k] > theirs).sum() + (ours[k] == theirs).sum())
    return total
