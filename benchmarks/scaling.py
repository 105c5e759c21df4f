"""Fan-out speed: the same units on local ``--jobs 1``, local ``--jobs 2`` and Ray with 2 CPUs.

    python benchmarks/scaling.py [--tournament-seeds 20] [--tournament-hands 200000]
                                 [--agent-seeds 8] [--agent-hands 20000] [--no-ray]

Two workloads, each through the real entry points (``run_tournament``, ``train_seeds``) and
:mod:`pokerirl.execution`:

1. a tournament of two saved DQN agents (trained first, untimed), ``--tournament-seeds``
   seeds of ``--tournament-hands`` duplicate hands;
2. an agent set: ``--agent-seeds`` DQN seeds of ``--agent-hands`` training hands each, with
   the default evaluation (every 10,000 hands, 20,000 duplicate hands).

For each backend it prints units per second, total wall time (from the call to the last
result: worker start-up, or connecting to Ray and its workers' start-up, included), the mean
time a unit measured inside itself (it grows when workers share a core), the
speed-up from 1 to 2 local workers (target >= 1.8x) and Ray's overhead over 2 local workers
as a share of wall time (target <= 10%). The Ray cluster is started first with
``ray start --head --num-cpus 2`` (:func:`pokerirl.execution.ray_head`, untimed), as a
user's cluster would already be running. It also checks that every backend gives the same
per-seed numbers and the same model bytes.

The machine may be shared with other work: compare figures from one run only, and say what
else was running.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

from pokerirl.agents.dqn import DQNConfig
from pokerirl.agents.train import TrainConfig, train_agent, train_seeds
from pokerirl.execution import Backend, ray_head
from pokerirl.tournaments import run_tournament


def timed(run: Callable[[], object]) -> tuple[float, object]:
    started = time.perf_counter()
    result = run()
    return time.perf_counter() - started, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tournament-seeds", type=int, default=20)
    parser.add_argument("--tournament-hands", type=int, default=200_000)
    parser.add_argument("--agent-seeds", type=int, default=8)
    parser.add_argument("--agent-hands", type=int, default=20_000)
    parser.add_argument("--no-ray", action="store_true", help="local backends only")
    args = parser.parse_args()

    root = Path(tempfile.mkdtemp(prefix="pokerirl-scaling-"))
    print(
        f"cores: {os.cpu_count()}, load average before: {os.getloadavg()[0]:.2f}; "
        f"tournament {args.tournament_seeds} seeds x {args.tournament_hands:,} DQN-vs-DQN "
        f"hands; agents {args.agent_seeds} seeds x {args.agent_hands:,} hands"
    )
    small = TrainConfig(
        hands=2_000, seed=0, eval_every=2_000, eval_hands=2_000, dqn=DQNConfig(concurrent_hands=256)
    )
    for seed in (100, 101):  # the two agents of the tournament (untimed)
        train_agent(root / f"dqn-{seed}", TrainConfig(**{**small.__dict__, "seed": seed}))
    matchup = [(str(root / "dqn-100"), str(root / "dqn-101"))]
    agent_config = TrainConfig(hands=args.agent_hands, seed=0)

    with contextlib.ExitStack() as stack:
        backends = {"local --jobs 1": Backend(jobs=1), "local --jobs 2": Backend(jobs=2)}
        if not args.no_ray:
            started = time.perf_counter()
            address = stack.enter_context(ray_head(num_cpus=2, say=print))
            print(f"ray start --head --num-cpus 2: up in {time.perf_counter() - started:.1f} s")
            backends["ray, 2 CPUs"] = Backend(kind="ray", address=address)

        rows: list[tuple[str, str, int, float]] = []
        inside: dict[tuple[str, str], float] = {}  # mean seconds a unit took, inside the unit
        numbers: dict[str, object] = {}
        weights: dict[str, dict[str, bytes]] = {}
        for name, backend in backends.items():
            tag = name.split()[0] + name.split()[-1]
            wall, report = timed(
                lambda backend=backend, tag=tag: run_tournament(
                    matchup,
                    hands=args.tournament_hands,
                    seeds=range(args.tournament_seeds),
                    out=root / f"tournament-{tag}",
                    backend=backend,
                )
            )
            numbers[name] = [(s.mbb_per_hand, s.std_error) for s in report.matchups[0].seeds]
            rows.append(("tournament seeds", name, args.tournament_seeds, wall))
            seconds = [s.seconds for s in report.matchups[0].seeds]
            inside["tournament seeds", name] = sum(seconds) / len(seconds)
            print(f"  tournament on {name}: {wall:.1f} s", flush=True)
            out = root / f"agents-{tag}"
            wall, _ = timed(
                lambda backend=backend, out=out: train_seeds(
                    out, agent_config, list(range(args.agent_seeds)), backend=backend
                )
            )
            weights[name] = {p.parent.name: p.read_bytes() for p in out.glob("seed-*/model.pt")}
            rows.append(("agent seeds", name, args.agent_seeds, wall))
            seconds = [json.loads(p.read_text())["seconds"] for p in out.glob("*/timings.json")]
            inside["agent seeds", name] = sum(seconds) / len(seconds)
            print(f"  agent set on {name}: {wall:.1f} s", flush=True)

    print()
    header = f"{'workload':<18}{'backend':<16}{'units':>6}{'wall s':>9}{'units/s':>9}"
    print(f"{header}{'vs jobs 1':>11}{'s/unit inside':>15}")
    walls = {(w, b): s for w, b, _, s in rows}
    for workload, backend, units, wall in rows:
        ratio = walls[workload, "local --jobs 1"] / wall
        print(
            f"{workload:<18}{backend:<16}{units:>6}{wall:>9.1f}{units / wall:>9.3f}{ratio:>10.2f}x"
            f"{inside[workload, backend]:>15.2f}"
        )
    print(
        "(s/unit inside: the mean time a unit measured for itself. If it grows with 2 workers,\n"
        " the 2 workers did not get 2 free cores: the machine is shared, not the backend slow.)"
    )
    print()
    for workload in ("tournament seeds", "agent seeds"):
        speedup = walls[workload, "local --jobs 1"] / walls[workload, "local --jobs 2"]
        line = f"{workload}: speed-up 1 -> 2 local workers {speedup:.2f}x (target >= 1.8x)"
        if (workload, "ray, 2 CPUs") in walls:
            local, ray = walls[workload, "local --jobs 2"], walls[workload, "ray, 2 CPUs"]
            line += f"; Ray overhead {(ray - local) / ray:+.1%} of wall time (target <= 10%)"
        print(line)
    same_numbers = len({repr(v) for v in numbers.values()}) == 1
    same_weights = len({repr(sorted(v.items())) for v in weights.values()}) == 1
    print(f"identical per-seed numbers on every backend: {same_numbers}")
    print(f"identical model.pt bytes on every backend: {same_weights}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
