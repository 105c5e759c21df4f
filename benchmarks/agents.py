"""DQN training speed against RLCard's own training loop, measured in the same run.

    python benchmarks/agents.py [--hands 50000] [--rlcard-hands 3000] [--seed 0]

Prints training decisions (stored transitions) per second of

* RLCard 1.2.0: ``env.run(is_training=True)``, ``reorganize`` and ``DQNAgent.feed`` per
  transition, its ``DQNAgent`` defaults (one update per transition), against its
  ``RandomAgent`` (the loop of RLCard's ``examples/run_rl.py``);
* :func:`pokerirl.agents.dqn.train_dqn` against random, with our defaults
  (``train_every=16``) and with RLCard's ``train_every=1`` (the same updates per decision);

and each one's ratio to RLCard. Both run on one CPU thread. Only ratios measured in one run
are comparable; the machine may be shared.

Then the quality check of the default run (``--hands`` sparse-reward hands against random,
seed ``--seed``): its greedy policy and always-call, each against random over
``--eval-hands`` duplicate hands of the same deals, in mbb/h with standard errors.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy and torch must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import dataclasses  # noqa: E402
import io  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

from pokerirl.agents.dqn import DQNConfig, train_dqn  # noqa: E402
from pokerirl.game import make_agent, play_match  # noqa: E402


def rlcard_decisions_per_second(hands: int, seed: int) -> float:
    """RLCard's DQN training loop on limit hold'em: stored transitions per second."""
    import rlcard

    # Imported late: `import rlcard.agents` runs `pip freeze` (about 3 s) in RLCard 1.2.0.
    from rlcard.agents import DQNAgent, RandomAgent
    from rlcard.utils import reorganize, set_seed

    env = rlcard.make("limit-holdem", config={"seed": seed})
    set_seed(seed)
    agent = DQNAgent(num_actions=4, state_shape=[72], mlp_layers=[64, 64], device="cpu")
    env.set_agents([agent, RandomAgent(num_actions=4)])
    decisions = 0
    # DQNAgent.train prints a line per update; discard it rather than time the terminal.
    with contextlib.redirect_stdout(io.StringIO()) as sink:
        started = time.perf_counter()
        for _ in range(hands):
            trajectories, payoffs = env.run(is_training=True)
            for transition in reorganize(trajectories, payoffs)[0]:
                agent.feed(transition)
                decisions += 1
            sink.seek(0)
            sink.truncate()
        seconds = time.perf_counter() - started
    return decisions / seconds


def ours_decisions_per_second(config: DQNConfig, hands: int, seed: int) -> tuple[float, Any]:
    started = time.perf_counter()
    learner = train_dqn(config, hands=hands, seed=seed, opponent=make_agent("random"))
    return learner.total_t / (time.perf_counter() - started), learner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=50_000, help="our training hands")
    parser.add_argument("--rlcard-hands", type=int, default=3_000, help="RLCard training hands")
    parser.add_argument("--eval-hands", type=int, default=200_000, help="quality check hands")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    np.random.seed(args.seed)

    rlcard_rate = rlcard_decisions_per_second(args.rlcard_hands, args.seed)
    print(f"RLCard DQNAgent (train_every=1): {rlcard_rate:10,.0f} decisions/s")
    default = DQNConfig()
    learners = []
    for label, config in (
        (f"pokerirl train_dqn (train_every={default.train_every})", default),
        ("pokerirl train_dqn (train_every=1)", dataclasses.replace(default, train_every=1)),
    ):
        hands = args.hands if config.train_every > 1 else args.hands // 10
        rate, learner = ours_decisions_per_second(config, hands, args.seed)
        learners.append(learner)
        print(f"{label + ':':40s} {rate:10,.0f} decisions/s  ({rate / rlcard_rate:5.1f}x RLCard)")

    random = make_agent("random")
    for label, agent in (
        (f"sparse DQN, {args.hands:,} hands (defaults)", learners[0].greedy_agent()),
        ("always-call", make_agent("call")),
    ):
        result = play_match(agent, random, hands=args.eval_hands, seed=args.seed + 1)
        print(
            f"{label + ' vs random:':45s} {result.mbb_per_hand:+8.1f} +- {result.std_error:.1f}"
            f" mbb/h over {result.hands:,} duplicate hands"
        )


if __name__ == "__main__":
    main()
