"""Make (or check) the exact equity tables the strength encoding ships.

    python benchmarks/equity_tables.py [--check] [--from PARTIAL.npy]

Builds the flop table of :mod:`pokerirl.game.equity` (1,755 flop classes x 1,326 hole pairs,
each entry ``2 x wins + ties`` summed over the 1,081 runouts: about half an hour of one
busy core, two minutes of a quiet one at 0.07 s a class), writes it to
``pokerirl/game/data/flop_equity.npz`` and prints its SHA-256 (for ``FLOP_TABLE_SHA256``)
and the exact preflop counts of the 169 classes summed from it (for
``pokerirl/game/preflop.py``'s ``PREFLOP_COUNTS``). ``--check`` rebuilds ``--classes``
random classes and compares them with the shipped table.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from pokerirl.game import equity
from pokerirl.game.preflop import NUM_RANKS, class_index
from pokerirl.holdem import PAIRS


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the shipped table")
    parser.add_argument("--classes", type=int, default=20, help="classes to check")
    parser.add_argument("--from", dest="partial", help="a finished (1755, 1326) .npy to ship")
    args = parser.parse_args()
    if args.check:
        shipped = equity.flop_table()
        representatives = equity.board_classes(3).representatives
        picked = np.random.default_rng(0).choice(equity.FLOP_CLASSES, args.classes, False)
        started = time.perf_counter()
        for k in picked:
            if not np.array_equal(equity.flop_class_counts(representatives[k]), shipped[k]):
                print(f"FAIL: flop class {k} differs from the shipped table")
                return 1
        print(f"{args.classes} flop classes rebuilt equal the shipped table "
              f"({time.perf_counter() - started:.1f} s)")  # fmt: skip
        return 0
    if args.partial:
        table = np.load(args.partial, allow_pickle=False)
        if table.shape != (equity.FLOP_CLASSES, 1326) or table.min() < 0:
            print(f"FAIL: {args.partial} is not a finished table")
            return 1
        table = table.astype(np.uint32)
    else:
        table = equity.build_flop_table(
            on_class=lambda k: print(f"class {k}", flush=True) if k % 100 == 0 else None
        )
    equity.FLOP_TABLE_FILE.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(equity.FLOP_TABLE_FILE, counts=table)
    print(f"wrote {equity.FLOP_TABLE_FILE} ({equity.FLOP_TABLE_FILE.stat().st_size:,} bytes)")
    print(f'FLOP_TABLE_SHA256 = "{equity.table_digest(table)}"')
    equity.FLOP_TABLE_SHA256 = equity.table_digest(table)  # to sum the preflop counts now
    equity.flop_table.cache_clear()
    counts = equity.preflop_counts()
    row, column = class_index(PAIRS)
    grid = np.zeros((NUM_RANKS, NUM_RANKS), dtype=np.int64)
    grid[row, column] = counts
    if not np.array_equal(grid[row, column], counts):
        print("FAIL: hands of one class have different counts")
        return 1
    print("PREFLOP_COUNTS = np.array([")
    for line in grid.tolist():
        print(f"    {line},")
    print("], dtype=np.int64)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
