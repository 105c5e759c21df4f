"""Engine speed against RLCard's own loop, and raise-vs-random from both, in the same run.

    python benchmarks/engine.py [--hands 400000] [--rlcard-hands 5000] [--rounds 5] [--seed 0]

Prints hands per second of random vs random in :mod:`pokerirl.game` and in
``rlcard.utils.tournament`` with RLCard's ``RandomAgent`` (and the ratio), then always-raise
vs random in both: mbb/h with its standard error, and the engine's wall time. Only ratios
measured in one run are comparable; the machine may be shared.

The gate (issue 41): the engine's raise vs random (alternating seats) must play at least
:data:`MIN_RATIO` times RLCard's random-vs-random hands/s measured in the same run; below it
the script says so and exits 1 (it was 158x, then 37x when `pokerirl match` began timing the
AIVAT corrections and a match built observations no built-in agent reads; back over 300x, it
hovered at 286-327x on an AVX-512 machine until a step's legality and chips were computed
by int8 arithmetic rather than gathers from four-entry tables: 360-372x there,
docs/results/strength-cost/runs6/engine.txt). The ratio is
the median over ``--rounds`` rounds, each RLCard's run and then the engine's, back to back:
on a shared machine a burst of load then hits one round's pair, not one side's best (a
best of several short engine runs against a few long RLCard ones favoured the engine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import statistics
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from pokerirl.game import make_agent, play_match

MIN_RATIO = 300.0  # engine raise-vs-random over RLCard random-vs-random, same run


class RLCardRaiseAgent:
    """Always-raise in RLCard's agent interface: raise if legal, else call, else check."""

    use_raw = False

    @staticmethod
    def step(state: dict[str, Any]) -> int:
        legal = state["legal_actions"]
        return next(a for a in (1, 0, 3) if a in legal)  # raise, call, check

    def eval_step(self, state: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        return self.step(state), {}


def rlcard_env(agents: list[Any], seed: int) -> Any:
    import rlcard

    env = rlcard.make("limit-holdem", config={"seed": seed})
    np.random.seed(seed)  # RLCard's RandomAgent draws from numpy's global generator
    env.set_agents(agents)
    return env


def rlcard_random_agent() -> Any:
    # Imported late: `import rlcard.agents` runs `pip freeze` (about 3 s) in RLCard 1.2.0.
    from rlcard.agents import RandomAgent

    return RandomAgent(num_actions=4)


def rlcard_random_vs_random(hands: int, seed: int) -> float:
    """Hands per second of ``rlcard.utils.tournament`` with two RandomAgents."""
    from rlcard.utils import tournament

    env = rlcard_env([rlcard_random_agent(), rlcard_random_agent()], seed)
    started = time.perf_counter()
    tournament(env, hands)
    return hands / (time.perf_counter() - started)


def rlcard_raise_vs_random(hands: int, seed: int) -> tuple[float, float, float]:
    """(mbb/h, standard error, hands/s) of always-raise (player 0) vs random, RLCard's env.run.

    RLCard draws the small blind at random each hand, so seats are random, not alternating.
    """
    env = rlcard_env([RLCardRaiseAgent(), rlcard_random_agent()], seed)
    results = np.empty(hands)
    started = time.perf_counter()
    for i in range(hands):
        _, payoffs = env.run(is_training=False)
        results[i] = payoffs[0]
    seconds = time.perf_counter() - started
    return 1000 * results.mean(), 1000 * results.std(ddof=1) / np.sqrt(hands), hands / seconds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=400_000, help="engine hands per figure")
    parser.add_argument("--rlcard-hands", type=int, default=5_000, help="RLCard hands per figure")
    parser.add_argument("--rounds", type=int, default=5, help="RLCard-engine pairs for the gate")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    random, always_raise = make_agent("random"), make_agent("raise")

    play_match(random, random, hands=10_000, seed=args.seed)  # warm up: lookup tables, caches
    ours = play_match(random, random, hands=args.hands, seed=args.seed, duplicate=False)
    theirs = rlcard_random_vs_random(args.rlcard_hands, args.seed)
    print(
        f"random vs random, engine ({args.hands:,} hands): {ours.hands_per_second:12,.0f} hands/s"
    )
    print(f"random vs random, RLCard tournament ({args.rlcard_hands:,}): {theirs:12,.0f} hands/s")
    print(f"ratio engine / RLCard: {ours.hands_per_second / theirs:.0f}x")

    duplicate = play_match(always_raise, random, hands=args.hands, seed=args.seed)
    print(f"raise vs random, engine, duplicate ({args.hands:,} hands): "
          f"{duplicate.mbb_per_hand:.1f} +- {duplicate.std_error:.1f} mbb/h in "
          f"{duplicate.seconds:.2f} s ({duplicate.hands_per_second:,.0f} hands/s)")  # fmt: skip
    mbb, se, speed = rlcard_raise_vs_random(args.rlcard_hands, args.seed)
    print(
        f"raise vs random, RLCard env.run ({args.rlcard_hands:,} hands): "
        f"{mbb:.1f} +- {se:.1f} mbb/h ({speed:,.0f} hands/s)"
    )
    encodings(args)

    ratios = []
    for round_ in range(args.rounds):
        peer = rlcard_random_vs_random(args.rlcard_hands, args.seed)
        match = play_match(
            always_raise, random, hands=args.hands, seed=args.seed, duplicate=False
        )
        ratios.append(match.hands_per_second / peer)
        print(f"round {round_ + 1}: RLCard random vs random {peer:8,.0f} hands/s; engine raise "
              f"vs random, alternating seats, {match.mbb_per_hand:.1f} +- "
              f"{match.std_error:.1f} mbb/h, {match.hands_per_second:12,.0f} hands/s: "
              f"{ratios[-1]:.0f}x (load {os.getloadavg()[0]:.2f})")  # fmt: skip
    ratio = statistics.median(ratios)
    print(f"ratio engine raise vs random / RLCard random vs random: median {ratio:.0f}x "
          f"(range {min(ratios):.0f}x to {max(ratios):.0f}x over {args.rounds} rounds; gate "
          f"{MIN_RATIO:.0f}x; load {os.getloadavg()[0]:.2f})")  # fmt: skip
    if ratio < MIN_RATIO:
        print(f"FAIL: the engine is below {MIN_RATIO:.0f}x RLCard: a regression")
        return 1
    return 0


@dataclass(frozen=True)
class EncodedRandom:
    """A random agent that reads its observations in ``encoding``: what an agent of that
    encoding costs the engine to feed (the agent itself costs nothing)."""

    encoding: str
    name: str = "random"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> Any:
        return make_agent("random").act(obs, legal_mask, rng)


def encodings(args: argparse.Namespace) -> None:
    """Hands per second of random vs random when one agent reads each encoding."""
    hands = max(args.hands // 10, 2)
    rates = {}
    for name in ("rlcard", "strength"):
        match = play_match(EncodedRandom(encoding=name), make_agent("random"), hands=hands,
                           seed=args.seed, duplicate=False)  # fmt: skip
        rates[name] = match.hands_per_second
        print(f"random ({name} observations) vs random ({hands:,} hands): "
              f"{match.hands_per_second:12,.0f} hands/s")  # fmt: skip
    print(f"ratio strength / rlcard: {rates['strength'] / rates['rlcard']:.2f}")


if __name__ == "__main__":
    raise SystemExit(main())
