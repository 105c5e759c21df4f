"""The shared seven-card evaluator's speed against eval7 (pip), measured in the same run.

    python benchmarks/evaluator.py [--hands 1000000] [--seed 0]

Ranks the same random seven-card hands with :func:`pokerirl.game.evaluator.hand_strength`
(one vectorized call), with :func:`~pokerirl.game.evaluator.board_strengths` (all 1,326 hole
pairs on each of hands / 1,326 boards: the equity tables' path) and with eval7's
``evaluate`` (a C evaluator called once a hand from Python, as its users call it); checks that
both order the hands alike (exit 1 if not) and prints hands per second and the ratios.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from equity_reference import eval7_cards

from pokerirl.game.evaluator import board_strengths, hand_strength, prepare_tables


def main() -> int:
    import eval7

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=1_000_000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    prepare_tables()
    cards = np.random.default_rng(args.seed).random((args.hands, 52)).argsort(axis=1)[:, :7]
    started = time.perf_counter()
    ours = hand_strength(cards)
    ours_rate = args.hands / (time.perf_counter() - started)
    boards = cards[: max(args.hands // 1326, 1), 2:]
    started = time.perf_counter()
    board_strengths(boards)
    board_rate = boards.shape[0] * 1326 / (time.perf_counter() - started)
    deck = eval7_cards()
    hands = [[deck[c] for c in row] for row in cards.tolist()]  # eval7's own objects, untimed
    started = time.perf_counter()
    theirs = np.array([eval7.evaluate(hand) for hand in hands])
    eval7_rate = args.hands / (time.perf_counter() - started)
    order = np.argsort(ours, kind="stable")
    step_ours, step_theirs = np.diff(ours[order]), np.diff(theirs[order])
    agree = bool((step_theirs[step_ours == 0] == 0).all()
                 and (step_theirs[step_ours > 0] > 0).all())
    load = os.getloadavg()[0]
    print(f"{args.hands:,} random seven-card hands (load {load:.2f}); same order as eval7: {agree}")
    for name, rate in (("hand_strength (vectorized)", ours_rate),
                       ("board_strengths (all pairs)", board_rate),
                       ("eval7.evaluate (one a call)", eval7_rate)):  # fmt: skip
        print(f"{name:30s} {rate:14,.0f} hands/s {rate / eval7_rate:8.1f}x eval7")
    return 0 if agree else 1


if __name__ == "__main__":
    raise SystemExit(main())
