"""DQN training speed against RLCard's own training loop, measured in the same run; and our
DQN against RLCard's at the authors' settings, learning curve beside learning curve.

    python benchmarks/agents.py [--part speed|authors|all] [--hands 50000]
        [--rlcard-hands 3000] [--seed 0] [--authors-seeds 0,1,2]

``--part authors`` (the issue-17 comparison): RLCard 1.2.0's ``DQNAgent`` and our
``train_dqn`` at the authors' settings (lr 5e-4, ``train_every`` 1: one update per stored
transition on both sides, epsilon 1.0 -> 0.0 over 5,000 steps, batch 32, replay 20,000,
target every 1,000 updates, MLP [64, 64]), 5,000 hands against random, one hand at a time on
both sides, for each seed. At 1,000, 2,000 and 5,000 hands each greedy policy plays
``--eval-hands`` duplicate hands against random on our engine, on the same deals (RLCard's
q-network is loaded into ours, layer for layer). Printed: both curves (mean and per seed),
updates per decision, and training decisions per second (wall and CPU) with their ratio.

``--part speed`` (the default before):
prints training decisions (stored transitions) per second of

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

import argparse
import contextlib
import dataclasses
import io
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch

from pokerirl.agents.dqn import DQNConfig, GreedyQAgent, QNetwork, train_dqn
from pokerirl.game import make_agent, play_match

CHECKPOINTS = (1_000, 2_000, 5_000)  # hands at which both learning curves are read


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
    """RLCard's DQN training loop on limit hold'em (``examples/run_rl.py``), resumable.

    ``settings`` are ``DQNAgent`` keyword arguments (default: its constructor's)."""

    def __init__(self, seed: int, **settings: object) -> None:
        import rlcard

        # Imported late: `import rlcard.agents` runs `pip freeze` (about 3 s) in RLCard 1.2.0.
        from rlcard.agents import DQNAgent, RandomAgent
        from rlcard.utils import set_seed

        self.env = rlcard.make("limit-holdem", config={"seed": seed})
        set_seed(seed)
        self.agent = DQNAgent(
            num_actions=4, state_shape=[72], mlp_layers=[64, 64], device="cpu", **settings
        )
        self.env.set_agents([self.agent, RandomAgent(num_actions=4)])
        self.tally = Tally()

    def greedy(self) -> GreedyQAgent:
        """The agent's current q-network as our greedy engine agent."""
        from pokerirl.agents.rlcard_import import _convert_state_dict

        network = QNetwork(hidden=(64, 64))
        network.load_state_dict(_convert_state_dict(self.agent.q_estimator.qnet.state_dict()))
        return GreedyQAgent(name="rlcard-dqn", network=network.eval())

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


def authors_comparison(seeds: list[int], eval_hands: int) -> None:
    """Our DQN and RLCard's at the authors' settings: learning curves, updates, speed."""
    from pokerirl.agents.config import AUTHORS_DQN

    rlcard_settings = {
        "learning_rate": AUTHORS_DQN.learning_rate,
        "train_every": AUTHORS_DQN.train_every,
        "epsilon_start": AUTHORS_DQN.epsilon_start,
        "epsilon_end": AUTHORS_DQN.epsilon_end,
        "epsilon_decay_steps": AUTHORS_DQN.epsilon_decay_steps,
        "batch_size": AUTHORS_DQN.batch_size,
        "replay_memory_size": AUTHORS_DQN.replay_size,
        "replay_memory_init_size": AUTHORS_DQN.replay_init,
        "update_target_estimator_every": AUTHORS_DQN.target_update_every,
    }
    random = make_agent("random")

    def vs_random(agent: GreedyQAgent) -> float:
        return play_match(agent, random, hands=eval_hands, seed=12_345).mbb_per_hand

    curves: dict[str, list[list[float]]] = {"RLCard DQNAgent": [], "pokerirl train_dqn": []}
    tallies = {name: Tally() for name in curves}
    updates = {name: [0, 0] for name in curves}  # updates, decisions
    for seed in seeds:
        loop = RLCardLoop(seed, **rlcard_settings)
        points = []
        for done, target in zip((0, *CHECKPOINTS), CHECKPOINTS, strict=False):
            loop.train(target - done)
            points.append(vs_random(loop.greedy()))
        curves["RLCard DQNAgent"].append(points)
        tallies["RLCard DQNAgent"].wall += loop.tally.wall
        tallies["RLCard DQNAgent"].cpu += loop.tally.cpu
        tallies["RLCard DQNAgent"].decisions += loop.tally.decisions
        updates["RLCard DQNAgent"][0] += loop.agent.train_t
        updates["RLCard DQNAgent"][1] += loop.agent.total_t

        ours: list[float] = []
        evaluation = Tally()

        def read(hands: int, learner: object, ours: list[float] = ours,
                 evaluation: Tally = evaluation) -> None:  # fmt: skip
            if hands in CHECKPOINTS:
                with evaluation.timing():
                    ours.append(vs_random(learner.greedy_agent()))  # type: ignore[attr-defined]

        tally = tallies["pokerirl train_dqn"]  # training only: the evaluations are taken out
        with tally.timing():
            learner = train_dqn(AUTHORS_DQN, hands=CHECKPOINTS[-1], seed=seed, opponent=random,
                                on_hands=read)  # fmt: skip
        tally.wall, tally.cpu = tally.wall - evaluation.wall, tally.cpu - evaluation.cpu
        tally.decisions += learner.total_t
        curves["pokerirl train_dqn"].append(ours)
        updates["pokerirl train_dqn"][0] += learner.train_t
        updates["pokerirl train_dqn"][1] += learner.total_t

    print(f"At the authors' settings, {len(seeds)} seeds ({', '.join(map(str, seeds))}); greedy "
          f"vs random, {eval_hands:,} duplicate hands on our engine (mbb/h):")  # fmt: skip
    header = "".join(f"{h:>10,}" for h in CHECKPOINTS)
    print(f"{'hands:':28s}{header}   updates/decision  decisions/s (wall, CPU)")
    rlcard_rates = tallies["RLCard DQNAgent"].rates()
    for name, runs in curves.items():
        mean = np.mean(runs, axis=0)
        done, decisions = updates[name]
        wall, cpu = tallies[name].rates()
        ratio = f" ({wall / rlcard_rates[0]:.1f}x, {cpu / rlcard_rates[1]:.1f}x)"
        print(f"{name + ' (mean)':28s}" + "".join(f"{v:+10,.0f}" for v in mean)
              + f"   {done / decisions:16.3f}  {wall:,.0f}, {cpu:,.0f}"
              + (ratio if name != "RLCard DQNAgent" else ""))  # fmt: skip
        for seed, run in zip(seeds, runs, strict=True):
            print(f"{'  seed ' + str(seed):28s}" + "".join(f"{v:+10,.0f}" for v in run))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=("speed", "authors", "all"), default="all")
    parser.add_argument("--hands", type=int, default=50_000, help="our training hands")
    parser.add_argument("--rlcard-hands", type=int, default=3_000, help="RLCard training hands")
    parser.add_argument("--eval-hands", type=int, default=200_000, help="quality check hands")
    parser.add_argument("--authors-seeds", default="0,1,2", help="seeds of the authors' part")
    parser.add_argument("--authors-eval-hands", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    np.random.seed(args.seed)
    if args.part in ("authors", "all"):
        seeds = [int(s) for s in args.authors_seeds.split(",")]
        authors_comparison(seeds, args.authors_eval_hands)
    if args.part in ("speed", "all"):
        speed(args)


def speed(args: argparse.Namespace) -> None:
    """Training decisions per second: RLCard's loop and ours (defaults and train_every 1)."""

    # RLCard runs half before and half after ours, so a change in machine load hits both.
    rlcard_loop = RLCardLoop(args.seed)
    rlcard_loop.train(args.rlcard_hands // 2)
    default = DQNConfig()
    runs = {}
    for label, config, encoding in (
        (f"pokerirl train_dqn (train_every={default.train_every})", default, "rlcard"),
        ("pokerirl train_dqn (train_every=1)", dataclasses.replace(default, train_every=1),
         "rlcard"),
        (f"  ... strength encoding (train_every={default.train_every})", default, "strength"),
    ):  # fmt: skip
        hands = args.hands if config.train_every > 1 else args.hands // 10
        tally = Tally()
        with tally.timing():
            learner = train_dqn(config, hands=hands, seed=args.seed, opponent=make_agent("random"),
                                encoding=encoding)  # fmt: skip
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

    # Both ran args.hands hands: the ratio of their times is that of their hands per second.
    (ours, _), (strength, _) = runs[next(iter(runs))], runs[list(runs)[-1]]
    print(f"strength / rlcard training hands per second: {ours.wall / strength.wall:.2f} wall, "
          f"{ours.cpu / strength.cpu:.2f} CPU ({args.hands / strength.wall:,.0f} and "
          f"{args.hands / ours.wall:,.0f} hands/s wall)")  # fmt: skip

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
