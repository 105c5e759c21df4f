"""Exact equity against brute force on many random states, and its speed.

    python benchmarks/equity.py [--river 10000] [--turn 10000] [--turn-eval7 1000]
                                [--flop 1000] [--seed 0]

Draws random states of each street (seeded) and compares :mod:`pokerirl.game.equity`'s
``2 x wins + ties`` counts with a brute-force enumeration of every opponent hand and runout:
eval7 (an independent evaluator) for the river and ``--turn-eval7`` turn states (45,540
hands a state, one eval7 call each), the engine's seven-card ``hand_strength`` (one
vectorized call over all cases; tested against RLCard and eval7) for ``--turn`` turn states
and the flop's 1,070,190 cases a state. Prints how many states agree exactly (all must),
each side's time, and exits 1 on any difference. Also prints the old version-1 estimate's
error on the same river and turn states.
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

from equity_reference import engine_flop_count, engine_turn_count, eval7_cards, eval7_count

from pokerirl.game.encodings import sampled_equity
from pokerirl.game.equity import (
    FLOP_DENOMINATOR,
    RIVER_DENOMINATOR,
    TURN_DENOMINATOR,
    flop_counts,
    hole_counts,
    turn_counts,
)


def states(n: int, seed: int, board: int) -> tuple[np.ndarray, np.ndarray]:
    cards = np.random.default_rng(seed).random((n, 52)).argsort(axis=1)[:, : 2 + board]
    return cards[:, :2], cards[:, 2:]


def check(name: str, n: int, seed: int, board: int, ours, reference, denominator: int) -> bool:
    holes, boards = states(n, seed, board)
    started = time.perf_counter()
    found = ours(holes, boards)
    ours_s = time.perf_counter() - started
    started = time.perf_counter()
    expected = np.array([reference(h, b) for h, b in zip(holes, boards, strict=True)])
    reference_s = time.perf_counter() - started
    same = int((found == expected).sum())
    print(f"{name}: {same:,} / {n:,} states equal the enumeration exactly; exact "
          f"{ours_s:.2f} s, brute force {reference_s:.1f} s (load "
          f"{os.getloadavg()[0]:.2f})")  # fmt: skip
    if board in (4, 5) and n:
        cards = np.concatenate([holes, boards, np.full((n, 5 - board), -1)], axis=1)
        error = np.abs(sampled_equity(cards) - expected / denominator)
        print(f"  version 1 (64 runouts) on these states: mean |error| {error.mean():.4f}, "
              f"max {error.max():.4f}")  # fmt: skip
    return same == n


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--river", type=int, default=10_000)
    parser.add_argument("--turn", type=int, default=10_000)
    parser.add_argument("--turn-eval7", type=int, default=1_000)
    parser.add_argument("--flop", type=int, default=1_000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    deck = eval7_cards()
    ok = check("river", args.river, args.seed, 5, hole_counts,
               lambda h, b: eval7_count(h, b, deck), RIVER_DENOMINATOR)  # fmt: skip
    ok &= check("turn (eval7)", args.turn_eval7, args.seed + 1, 4, turn_counts,
                lambda h, b: eval7_count(h, b, deck), TURN_DENOMINATOR)  # fmt: skip
    ok &= check("turn (engine)", args.turn, args.seed + 3, 4, turn_counts, engine_turn_count,
                TURN_DENOMINATOR)  # fmt: skip
    ok &= check("flop", args.flop, args.seed + 2, 3, flop_counts, engine_flop_count,
                FLOP_DENOMINATOR)  # fmt: skip
    if not ok:
        print("FAIL: exact equity differs from the enumeration")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
