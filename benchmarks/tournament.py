"""Tournament speed: the issue's 1,000,000-hand x 20-seed evaluation, and a DQN-sized estimate.

    python benchmarks/tournament.py [--hands 1000000] [--seeds 0-19] [--jobs 1 2]
                                    [--mlp-hands 1000000] [--layers 64,64] [--agents A B]

1. ``raise`` vs ``call`` (or ``--agents A B``: built-ins, agent folders or agent sets) through
   ``run_tournament`` for each ``--jobs`` value: wall time, hands/s and the pooled mbb/h
   (which must not depend on jobs).
2. A DQN-sized network against itself without any saved agent: an MLP of RLCard's DQN shape
   (72 -> layers -> 4, greedy over legal actions) under ``torch.inference_mode`` with one torch
   thread, ``--mlp-hands`` hands of one seed through ``play_match``; the projected wall time of
   20 seeds on 2 processes is hands/s scaled up (it leaves out process start and loading).

The machine may be shared: compare figures from one run only.
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
import time

import numpy as np
import torch

from pokerirl.game.match import play_match
from pokerirl.holdem import FOLD
from pokerirl.tournaments import format_seeds, parse_seeds, run_tournament


class MLPAgent:
    """Greedy Q-network over legal actions, the shape of RLCard's DQN estimator.

    Untrained weights would fold at random and end hands early, flattering the speed; this
    one never folds, so hands run to showdown as often as raise vs call (the slow case).
    """

    def __init__(self, layers: list[int], seed: int) -> None:
        torch.manual_seed(seed)
        sizes = [72, *layers]
        modules: list[torch.nn.Module] = []
        for fan_in, fan_out in itertools.pairwise(sizes):
            modules += [torch.nn.Linear(fan_in, fan_out), torch.nn.Tanh()]
        self.net = torch.nn.Sequential(*modules, torch.nn.Linear(sizes[-1], 4)).eval()
        self.name = f"mlp-{seed}"
        self.decisions = 0

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        self.decisions += len(obs)
        q = self.net(torch.from_numpy(obs).float())
        allowed = torch.from_numpy(legal_mask).clone()
        allowed[:, FOLD] = False  # check or call is always legal instead
        q = q.masked_fill(~allowed, float("-inf"))
        return q.argmax(dim=1).numpy().astype(np.int64)


def bench_tournament(
    agents: tuple[str, str], hands: int, seeds: tuple[int, ...], jobs: int
) -> None:
    with tempfile.TemporaryDirectory() as out:
        started = time.perf_counter()
        report = run_tournament([agents], hands=hands, seeds=seeds, out=out, jobs=jobs)
        wall = time.perf_counter() - started
    pooled = report.matchups[0].pooled
    total = hands * len(seeds)
    print(
        f"{agents[0]} vs {agents[1]}, {hands:,} hands x {len(seeds)} seeds, jobs {jobs}: "
        f"{wall:.1f} s wall ({total / wall:,.0f} hands/s), pooled {pooled.mbb_per_hand:+.3f} "
        f"+- {pooled.std_error:.3f} mbb/h"
    )


def bench_mlp(hands: int, layers: list[int], seeds: int, jobs: int) -> None:
    torch.set_num_threads(1)  # what each of the tournament's worker processes gets on 2 cores
    a, b = MLPAgent(layers, 0), MLPAgent(layers, 1)
    with torch.inference_mode():
        result = play_match(a, b, hands=hands, seed=0)
    projected = hands * seeds / result.hands_per_second / jobs
    print(
        f"MLP 72-{'-'.join(map(str, layers))}-4 vs MLP, {hands:,} hands, 1 process, 1 thread: "
        f"{result.seconds:.1f} s ({result.hands_per_second:,.0f} hands/s, "
        f"{(a.decisions + b.decisions) / hands:.1f} decisions/hand); projected "
        f"{seeds} seeds x {hands:,} hands on {jobs} processes: {projected:.0f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=1_000_000)
    parser.add_argument("--seeds", default="0-19")
    parser.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--agents", nargs=2, default=["raise", "call"])
    parser.add_argument("--mlp-hands", type=int, default=1_000_000)
    parser.add_argument("--layers", default="64,64")
    args = parser.parse_args()
    seeds = parse_seeds(args.seeds)
    print(f"seeds {format_seeds(seeds)}")
    for jobs in args.jobs:
        bench_tournament(tuple(args.agents), args.hands, seeds, jobs)
    if args.mlp_hands:
        layers = [int(x) for x in args.layers.split(",")]
        bench_mlp(args.mlp_hands, layers, len(seeds), max(args.jobs))


if __name__ == "__main__":
    main()
