"""DQN training speed against RLCard's own training loop, measured in the same run.

    python benchmarks/agents.py [--hands 50000] [--rlcard-hands 3000] [--seed 0]

Prints training decisions (stored transitions) per second of

* RLCard 1.2.0: ``env.run(is_training=True)``, ``reorganize`` and ``DQNAgent.feed`` per
  transition, its ``DQNAgent`` defaults (one update per transition), against its
  ``RandomAgent`` (the loop of RLCard's ``examples/run_rl.py``);
* :func:`pokerirl.agents.dqn.train_dqn` against random, with our defaults
  (``train_every=16``, 1,024 concurrent hands) and with RLCard's ``train_every=1`` (the
  same updates per decision);

and each one's ratio to RLCard, by wall-clock and by CPU time (the steadier of the two on a
shared machine). Both run on one CPU thread; RLCard's hands are split before and after ours.
Only ratios measured in one run are comparable.

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
from collections.abc import Iterator  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

from pokerirl.agents.dqn import DQNConfig, train_dqn  # noqa: E402
from pokerirl.game import make_agent, play_match  # noqa: E402


@dataclass
class Tally:
    """Decisions and the wall-clock and CPU seconds they took."""

    decisions: int = 0
    wall: float = 0.0
    cpu: float = 0.0

    @contextlib.contextmanager
    def timing(self) -> Iterator[None]:
        wall, cpu = time.perf_counter(), time.process_time()
        yield
        self.wall += time.perf_counter() - wall
        self.cpu += time.process_time() - cpu

    def rates(self) -> tuple[float, float]:
        return self.decisions / self.wall, self.decisions / self.cpu


class RLCardLoop:
    """RLCard's DQN training loop on limit hold'em (``examples/run_rl.py``), resumable."""

    def __init__(self, seed: int) -> None:
        import rlcard

        # Imported late: `import rlcard.agents` runs `pip freeze` (about 3 s) in RLCard 1.2.0.
        from rlcard.agents import DQNAgent, RandomAgent
        from rlcard.utils import set_seed

        self.env = rlcard.make("limit-holdem", config={"seed": seed})
        set_seed(seed)
        self.agent = DQNAgent(num_actions=4, state_shape=[72], mlp_layers=[64, 64], device="cpu")
        self.env.set_agents([self.agent, RandomAgent(num_actions=4)])
        self.tally = Tally()

    def train(self, hands: int) -> None:
        from rlcard.utils import reorganize

        # DQNAgent.train prints a line per update; discard it rather than time the terminal.
        with contextlib.redirect_stdout(io.StringIO()) as sink, self.tally.timing():
            for _ in range(hands):
                trajectories, payoffs = self.env.run(is_training=True)
                for transition in reorganize(trajectories, payoffs)[0]:
                    self.agent.feed(transition)
                    self.tally.decisions += 1
                sink.seek(0)
                sink.truncate()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=50_000, help="our training hands")
    parser.add_argument("--rlcard-hands", type=int, default=3_000, help="RLCard training hands")
    parser.add_argument("--eval-hands", type=int, default=200_000, help="quality check hands")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    np.random.seed(args.seed)

    # RLCard runs half before and half after ours, so a change in machine load hits both.
    rlcard_loop = RLCardLoop(args.seed)
    rlcard_loop.train(args.rlcard_hands // 2)
    default = DQNConfig()
    runs = {}
    for label, config in (
        (f"pokerirl train_dqn (train_every={default.train_every})", default),
        ("pokerirl train_dqn (train_every=1)", dataclasses.replace(default, train_every=1)),
    ):
        hands = args.hands if config.train_every > 1 else args.hands // 10
        tally = Tally()
        with tally.timing():
            learner = train_dqn(config, hands=hands, seed=args.seed, opponent=make_agent("random"))
        tally.decisions = learner.total_t
        runs[label] = (tally, learner)
    rlcard_loop.train(args.rlcard_hands - args.rlcard_hands // 2)

    rlcard_wall, rlcard_cpu = rlcard_loop.tally.rates()
    print(f"{'':40s} {'wall':>10s} {'CPU':>10s}  decisions/s, ratio to RLCard (wall, CPU)")
    print(f"{'RLCard DQNAgent (train_every=1):':40s} {rlcard_wall:10,.0f} {rlcard_cpu:10,.0f}")
    for label, (tally, _) in runs.items():
        wall, cpu = tally.rates()
        print(
            f"{label + ':':40s} {wall:10,.0f} {cpu:10,.0f}"
            f"  {wall / rlcard_wall:5.1f}x {cpu / rlcard_cpu:5.1f}x"
        )

    random = make_agent("random")
    default_learner = next(iter(runs.values()))[1]
    for label, agent in (
        (f"sparse DQN, {args.hands:,} hands (defaults)", default_learner.greedy_agent()),
        ("always-call", make_agent("call")),
    ):
        result = play_match(agent, random, hands=args.eval_hands, seed=args.seed + 1)
        print(
            f"{label + ' vs random:':45s} {result.mbb_per_hand:+8.1f} +- {result.std_error:.1f}"
            f" mbb/h over {result.hands:,} duplicate hands"
        )


if __name__ == "__main__":
    main()
