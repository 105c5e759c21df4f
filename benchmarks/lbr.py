"""Local best response speed, and the AIVAT corrections' standard-error reduction.

    python benchmarks/lbr.py [--agent SPEC] [--hands 2000] [--streets turn preflop]
                             [--opponents call SPEC] [--match-hands 200000]

1. LBR hands per second on one core (one torch thread, the hands of one unit in lock-step,
   as ``pokerirl exploit`` plays them) for each ``--check-until`` street in ``--streets``,
   and the projected wall time of 20,000 hands; the issue's target is 20,000 hands against
   a DQN agent in at most 10 minutes on one core from the turn. ``--agent`` defaults to an
   untrained DQN of the authors' shape (72 -> 64 -> 64 -> 4, random weights: the forward
   cost of a real one; a trained agent folds and narrows its range differently, so pass a
   trained agent folder for the figure that counts).
2. For each of ``--opponents``: the agent against it over ``--match-hands`` duplicate hands,
   raw and AIVAT-corrected standard errors, their ratio, and the time the corrections add
   (the issue's target: SD -30% or better beyond duplicate).

The machine may be shared: the load average is printed; compare figures from one run only.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy and torch must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import time

import numpy as np
import torch

from pokerirl.agents import resolve_agent
from pokerirl.agents.dqn import GreedyQAgent, QNetwork, input_norm
from pokerirl.game.bots import Agent
from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import get_encoding
from pokerirl.game.match import play_match
from pokerirl.tournaments.aivat import play_corrected_match
from pokerirl.tournaments.lbr import LBRSettings, play_lbr

TARGET_HANDS, TARGET_SECONDS = 20_000, 600.0


def _agent(spec: str | None, encoding: str = "rlcard") -> Agent:
    if spec is not None:
        return resolve_agent(spec)
    torch.manual_seed(0)
    chosen = get_encoding(encoding)
    network = QNetwork(hidden=(64, 64), obs_size=chosen.width, input_norm=input_norm(chosen))
    return GreedyQAgent(name=f"untrained-dqn-{chosen.spec}", network=network.eval(),
                        encoding=chosen.spec)  # fmt: skip


def bench_lbr(agent: Agent, hands: int, street: str) -> None:
    deals = np.repeat(deal_cards(seed=0, start=0, count=hands // 2), 2, axis=0)
    seats = np.arange(hands) % 2
    started, cpu = time.perf_counter(), time.process_time()
    with torch.inference_mode():
        found = play_lbr(agent, deals, seats, np.random.default_rng(0),
                         LBRSettings(check_until=street))  # fmt: skip
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    rate = hands / wall
    units = 1000.0 * found.payoffs.reshape(-1, 2).mean(axis=1)
    print(
        f"LBR vs {agent.name}, check until {street}: {hands:,} hands in {wall:.1f} s "
        f"({rate:,.1f} hands/s wall, {hands / cpu:,.1f} per CPU second); "
        f"{TARGET_HANDS:,} hands: {TARGET_HANDS / rate / 60:.1f} min "
        f"(target {TARGET_SECONDS / 60:.0f} min from the turn); LBR "
        f"{units.mean():+.0f} ± {units.std(ddof=1) / np.sqrt(units.size):.0f} mbb/h"
    )


def bench_aivat(agent: Agent, opponent: Agent, hands: int) -> None:
    started = time.perf_counter()
    play_match(agent, opponent, hands=hands, seed=0)
    plain_seconds = time.perf_counter() - started
    started = time.perf_counter()
    found = play_corrected_match(agent, opponent, hands=hands, seed=0)
    corrected_seconds = time.perf_counter() - started
    raw, fixed = found.match, found
    ratio = fixed.corrected_std_error / raw.std_error if raw.std_error > 0 else float("nan")
    print(
        f"AIVAT {agent.name} vs {opponent.name}, {hands:,} duplicate hands: raw "
        f"{raw.mbb_per_hand:+.1f} ± {raw.std_error:.2f}, corrected "
        f"{fixed.corrected_mbb_per_hand:+.1f} ± {fixed.corrected_std_error:.2f} mbb/h; "
        f"SE ratio {ratio:.3f} ({100 * (ratio - 1):+.0f}%); time {plain_seconds:.1f} s -> "
        f"{corrected_seconds:.1f} s with the corrections"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", default=None, help="agent spec (default: untrained DQN)")
    parser.add_argument("--hands", type=int, default=2_000, help="LBR hands per street")
    parser.add_argument("--streets", nargs="+", default=["turn", "preflop"])
    parser.add_argument("--opponents", nargs="*", default=["call"])
    parser.add_argument("--match-hands", type=int, default=200_000)
    parser.add_argument("--encodings", nargs="+", default=["rlcard"],
                        help="the untrained DQN's encodings (strength: the issue-41 target, "
                        ">= 50 hands/s from the turn)")  # fmt: skip
    args = parser.parse_args()
    torch.set_num_threads(1)
    print(f"cores: {os.cpu_count()}, load average before: {os.getloadavg()[0]:.2f}")
    agent: Agent | None = None
    for encoding in args.encodings if args.agent is None else [None]:
        agent = _agent(args.agent, encoding or "rlcard")
        for street in args.streets:
            bench_lbr(agent, args.hands, street)
    assert agent is not None
    for spec in args.opponents:
        bench_aivat(agent, resolve_agent(spec), args.match_hands)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
