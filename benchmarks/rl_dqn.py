"""Lock-step DQN vs sequential SB3 DQN: wall and CPU time, env steps/s for R runs (issue 19).

    python benchmarks/rl_dqn.py [--quick] [--steps N] [--runs 1 3 9]

MountainCar-v0 at the preset (rl-zoo) settings. Every measurement runs in its own subprocess
with one thread (OMP_NUM_THREADS=1, torch.set_num_threads(1)), so each reports its own peak RSS
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``, which includes the ~0.3-0.5 GB of the imported
torch/gymnasium/SB3). SB3 is run once per seed (0..max R - 1); its time for R runs is the sum of
seeds 0..R-1, the sequential cost. CPU time (``time.process_time``) is printed beside wall time:
on a shared machine it is the steadier of the two. Target (issue 19): R=9, lock-step >= 3x SB3.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ENV_ID = "MountainCar-v0"


def _worker(kind: str, runs: int, steps: int) -> dict[str, float]:
    import torch

    torch.set_num_threads(1)
    from pokerirl.gym.presets import TASKS

    rl = TASKS[ENV_ID].rl
    assert rl.dqn is not None
    out: dict[str, float] = {}
    if kind == "lockstep":
        from pokerirl.gym.lockstep.dqn import LockstepDQN

        wall, cpu = time.perf_counter(), time.process_time()
        result = LockstepDQN(ENV_ID, rl.dqn, seeds=range(runs)).learn(steps)
        out.update(env_seconds=result.env_seconds, update_seconds=result.update_seconds,
                   timesteps=result.timesteps)
    else:
        from pokerirl.gym.expert_policies import make_model

        model = make_model(ENV_ID, rl, seed=runs)  # "runs" is the seed here
        wall, cpu = time.perf_counter(), time.process_time()
        model.learn(steps)
        out["timesteps"] = model.num_timesteps
    out["wall"] = time.perf_counter() - wall
    out["cpu"] = time.process_time() - cpu
    out["maxrss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB
    return out


def _measure(kind: str, runs: int, steps: int) -> dict[str, float]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    root = Path(__file__).resolve().parents[1]
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    proc = subprocess.run([sys.executable, __file__, "--worker", kind, str(runs), str(steps)],
                          env=env, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        sys.exit(f"{kind} worker failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, nargs="+", default=[1, 3, 9])
    parser.add_argument("--steps", type=int, default=None, help="env steps per run")
    parser.add_argument("--quick", action="store_true", help="5,000 steps per run")
    parser.add_argument("--worker", nargs=3, metavar=("KIND", "RUNS", "STEPS"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        kind, runs, steps = args.worker
        print(json.dumps(_worker(kind, int(runs), int(steps))))
        return
    if any(r < 1 for r in args.runs):
        parser.error("--runs: each R must be >= 1")
    steps = args.steps or (5_000 if args.quick else 20_000)
    print(f"{ENV_ID}: preset DQN settings, {steps} steps per run, one thread, one process each")
    sb3: list[dict[str, float]] = []
    for runs in sorted(args.runs):
        lock = _measure("lockstep", runs, steps)
        while len(sb3) < runs:  # SB3 seeds measured once, interleaved with the groups
            sb3.append(_measure("sb3", len(sb3), steps))
        wall = sum(m["wall"] for m in sb3[:runs])
        cpu = sum(m["cpu"] for m in sb3[:runs])
        total = runs * lock["timesteps"]
        print(f"R={runs:2d}  lockstep {lock['wall']:6.1f}s wall {lock['cpu']:6.1f}s cpu "
              f"{total / lock['wall']:6.0f} steps/s (env {lock['env_seconds']:.1f}s, "
              f"update {lock['update_seconds']:.1f}s, peak RSS {lock['maxrss_mb']:.0f} MB) | "
              f"sb3 {wall:6.1f}s wall {cpu:6.1f}s cpu {total / wall:6.0f} steps/s "
              f"(peak RSS per run {max(m['maxrss_mb'] for m in sb3[:runs]):.0f} MB) | "
              f"ratio wall {wall / lock['wall']:4.2f}x cpu {cpu / lock['cpu']:4.2f}x")


if __name__ == "__main__":
    main()
