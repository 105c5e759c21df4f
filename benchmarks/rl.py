"""Lock-step PPO vs sequential SB3 PPO: wall time and env steps/s for R runs (issue 19).

    python benchmarks/rl.py [--quick] [--env Acrobot-v1 HalfCheetah-v4] [--runs 1 3 10]

Both backends run the task's preset PPO settings (pokerirl.gym.presets.TASKS[env].rl) on the
env reward, one thread (torch.set_num_threads(1)), in this process, one after the other for
each R; each row prints both backends' wall time and steps/s, the ratio, and the env / update
split (lock-step: its own timers; SB3: the time in ``model.train`` is the update, the rest of
``learn`` the rollouts, env steps and SB3's per-step policy calls). Targets (issue 19): 10
Acrobot runs >= 5x SB3 (aim 10x); 10 HalfCheetah-v4 runs >= 1.8x.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import torch

from pokerirl.gym.lockstep import LockstepPPO
from pokerirl.gym.presets import TASKS


@dataclass(frozen=True, kw_only=True)
class Timing:
    seconds: float
    update_seconds: float
    steps: int  # env steps, all runs together


def sb3_runs(env_id: str, runs: int, steps: int) -> Timing:
    """``runs`` SB3 PPO runs one after the other, as the sb3 backend trains them."""
    from pokerirl.gym.expert_policies import make_model

    update = 0.0
    total = 0
    t0 = time.perf_counter()
    for seed in range(runs):
        model = make_model(env_id, TASKS[env_id].rl, seed=seed)
        train = model.train

        def timed_train(train=train) -> None:
            nonlocal update
            start = time.perf_counter()
            train()
            update += time.perf_counter() - start

        model.train = timed_train
        model.learn(steps)
        total += model.num_timesteps
    return Timing(seconds=time.perf_counter() - t0, update_seconds=update, steps=total)


def lockstep_runs(env_id: str, runs: int, steps: int) -> tuple[Timing, float]:
    """One lock-step group of ``runs`` runs; also its env seconds."""
    settings = TASKS[env_id].rl.ppo
    assert settings is not None
    t0 = time.perf_counter()
    result = LockstepPPO(env_id, settings, seeds=range(runs)).learn(steps)
    seconds = time.perf_counter() - t0
    timing = Timing(seconds=seconds, update_seconds=result.update_seconds,
                    steps=runs * result.timesteps)  # fmt: skip
    return timing, result.env_seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", nargs="+", default=["Acrobot-v1", "HalfCheetah-v4"])
    parser.add_argument("--runs", type=int, nargs="+", default=[1, 3, 10])
    parser.add_argument("--steps", type=int, default=None, help="env steps per run")
    parser.add_argument("--quick", action="store_true", help="2 rollouts per run")
    args = parser.parse_args()
    for env in args.env:
        if env not in TASKS or TASKS[env].rl.ppo is None:
            parser.error(f"--env {env!r}: not a PPO task of the presets")
    torch.set_num_threads(1)
    # Warm-up outside the timings: first-call costs (imports, MuJoCo compile) are not a backend's.
    for env in args.env:
        lockstep_runs(env, 1, 1)
        sb3_runs(env, 1, 1)
    for env in args.env:
        s = TASKS[env].rl.ppo
        assert s is not None
        steps = args.steps or (2 * s.n_steps if args.quick else TASKS[env].rl.timesteps)
        arch = s.net_arch or (64, 64)
        print(f"\n{env}: {steps} steps per run (n_steps {s.n_steps}, batch {s.batch_size}, "
              f"n_epochs {s.n_epochs}, pi/vf {list(arch)}), one thread")  # fmt: skip
        print("| R | lock-step s | steps/s | env s | update s | SB3 s | steps/s | update s "
              "| ratio |")
        print("|---|---|---|---|---|---|---|---|---|")
        for runs in args.runs:
            lock, env_seconds = lockstep_runs(env, runs, steps)
            sb3 = sb3_runs(env, runs, steps)
            print(f"| {runs} | {lock.seconds:.1f} | {lock.steps / lock.seconds:,.0f} | "
                  f"{env_seconds:.1f} | {lock.update_seconds:.1f} | {sb3.seconds:.1f} | "
                  f"{sb3.steps / sb3.seconds:,.0f} | {sb3.update_seconds:.1f} | "
                  f"{sb3.seconds / lock.seconds:.2f}x |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
