"""Leduc hold'em: our engine against RLCard's env, our CFR+ against OpenSpiel's, in one run.

    python benchmarks/leduc.py [--hands 200000] [--rlcard-hands 20000] [--replay 100000]
                               [--iterations 200] [--openspiel-iterations 10]

Prints (1) hands per second of random vs random in the batch engine
(:class:`~pokerirl.game.leduc.batch.LeducBatch`), the one-hand engine and RLCard's
``leduc-holdem`` env, with the ratios; (2) CFR+ iterations per second of ours and of
OpenSpiel's ``CFRPlusSolver`` on ``leduc_poker`` (skipped without open_spiel), with the
ratio; (3) the iterations and seconds our CFR+ needs to get below one milli-chip per hand
on each rule set (exploitability measured every 10 iterations); (4) with ``--replay N``, N
random hands replayed through RLCard and our engine decision by decision (issue 42's
100,000), and its time. Only ratios measured in one run are comparable: the machine may be
shared (the script prints the load average).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from pokerirl.game.leduc import OPENSPIEL, RLCARD, random_deal
from pokerirl.game.leduc.batch import LeducBatch
from pokerirl.game.leduc.cfr import CFRPlus
from pokerirl.game.leduc.exact import MILLI


def rlcard_hands_per_second(hands: int, seed: int) -> float:
    import rlcard

    env = rlcard.make("leduc-holdem", config={"seed": seed})
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    for _ in range(hands):
        state, _ = env.reset()
        while not env.is_over():
            state, _ = env.step(int(rng.choice(list(state["legal_actions"]))))
        env.get_payoffs()
    return hands / (time.perf_counter() - start)


def batch_hands_per_second(hands: int, seed: int) -> float:
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    batch = LeducBatch.dealt(RLCARD, hands, rng)
    batch.play_random(rng)
    batch.payoffs()
    return hands / (time.perf_counter() - start)


def engine_hands_per_second(hands: int, seed: int) -> float:
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    for _ in range(hands):
        state = random_deal(RLCARD, rng)
        while not state.is_over:
            legal = state.legal_actions()
            state = state.step(legal[int(rng.integers(len(legal)))])
        state.payoffs()
    return hands / (time.perf_counter() - start)


def cfr_iterations_per_second(iterations: int, theirs: int) -> tuple[float, float | None]:
    solver = CFRPlus(OPENSPIEL)
    start = time.perf_counter()
    for _ in range(iterations):
        solver.step()
    ours = iterations / (time.perf_counter() - start)
    try:
        import pyspiel
        from open_spiel.python.algorithms import cfr
    except ImportError:
        return ours, None
    their_solver = cfr.CFRPlusSolver(pyspiel.load_game("leduc_poker"))
    start = time.perf_counter()
    for _ in range(theirs):
        their_solver.evaluate_and_update_policy()
    return ours, theirs / (time.perf_counter() - start)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=200_000, help="batch engine hands")
    parser.add_argument("--engine-hands", type=int, default=20_000, help="one-hand engine hands")
    parser.add_argument("--rlcard-hands", type=int, default=20_000, help="RLCard env hands")
    parser.add_argument("--iterations", type=int, default=200, help="our CFR+ iterations timed")
    parser.add_argument("--openspiel-iterations", type=int, default=10)
    parser.add_argument("--replay", type=int, default=0, help="hands replayed against RLCard")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")

    rlcard = rlcard_hands_per_second(args.rlcard_hands, args.seed)
    batch = batch_hands_per_second(args.hands, args.seed)
    engine = engine_hands_per_second(args.engine_hands, args.seed)
    print(f"random vs random, hands/s: batch {batch:,.0f}, one-hand engine {engine:,.0f}, "
          f"RLCard env {rlcard:,.0f}")  # fmt: skip
    print(f"  batch / RLCard: {batch / rlcard:.1f}x; one-hand engine / RLCard: "
          f"{engine / rlcard:.2f}x")  # fmt: skip

    ours, theirs = cfr_iterations_per_second(args.iterations, args.openspiel_iterations)
    line = f"CFR+ on leduc_poker, iterations/s: ours {ours:,.1f}"
    if theirs is not None:
        line += f", OpenSpiel's CFRPlusSolver {theirs:,.2f} ({ours / theirs:.1f}x)"
    print(line)

    for rules in (RLCARD, OPENSPIEL):
        solver, start = CFRPlus(rules), time.perf_counter()
        while True:
            point = solver.run(10)[-1]
            if point.exploitability * MILLI < 1.0:
                break
        seconds = time.perf_counter() - start
        print(f"CFR+ {rules.name}: {point.iteration} iterations to "
              f"{point.exploitability * MILLI:.3f} milli-chips per hand, {seconds:.1f} s "
              "(measuring every 10 included)")  # fmt: skip

    if args.replay:
        from pokerirl.game.leduc.interop import replay_rlcard

        start = time.perf_counter()
        decisions = replay_rlcard(args.replay, seed=args.seed)
        print(f"replayed {args.replay:,} hands ({decisions:,} decisions) against RLCard: "
              f"identical, {time.perf_counter() - start:.1f} s")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
