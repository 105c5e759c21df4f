"""Lock-step PPO vs sequential SB3 PPO: wall time and env steps/s for R runs (issue 19).

    python benchmarks/rl.py [--quick] [--env Acrobot-v1] [--runs 1 3 10]

One thread for both (torch.set_num_threads(1)); prints each backend's steps/s and the ratio.
Target (issue 19): 10 Acrobot runs, lock-step >= 5x SB3.
"""

from __future__ import annotations

import argparse
import time

import torch

from pokerirl.gym.lockstep import LockstepPPO
from pokerirl.gym.presets import TASKS


def _sb3_seconds(env_id: str, runs: int, steps: int) -> float:
    from stable_baselines3 import PPO

    s = TASKS[env_id].rl.ppo
    assert s is not None
    hidden = list(s.net_arch or (64, 64))
    act = torch.nn.Tanh if s.activation == "tanh" else torch.nn.LeakyReLU
    t0 = time.perf_counter()
    for seed in range(runs):
        PPO("MlpPolicy", env_id, n_steps=s.n_steps, batch_size=s.batch_size, gamma=s.gamma,
            gae_lambda=s.gae_lambda, clip_range=s.clip_range, ent_coef=s.ent_coef,
            vf_coef=s.vf_coef, max_grad_norm=s.max_grad_norm, learning_rate=s.learning_rate,
            n_epochs=s.n_epochs, seed=seed, device="cpu",
            policy_kwargs={"net_arch": {"pi": hidden, "vf": hidden}, "activation_fn": act,
                           "log_std_init": s.log_std_init, "ortho_init": s.ortho_init},
            ).learn(steps)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="Acrobot-v1")
    parser.add_argument("--runs", type=int, nargs="+", default=[1, 3, 10])
    parser.add_argument("--steps", type=int, default=None, help="env steps per run")
    parser.add_argument("--quick", action="store_true", help="2 rollouts per run")
    args = parser.parse_args()
    if args.env not in TASKS or TASKS[args.env].rl.ppo is None:
        parser.error(f"--env {args.env!r}: not a PPO task of the presets")
    torch.set_num_threads(1)
    s = TASKS[args.env].rl.ppo
    steps = args.steps or (2 * s.n_steps if args.quick else TASKS[args.env].rl.timesteps)
    print(f"{args.env}: {steps} steps per run, n_epochs {s.n_epochs}, one thread")
    for runs in args.runs:
        t0 = time.perf_counter()
        result = LockstepPPO(args.env, s, seeds=range(runs)).learn(steps)
        lock = time.perf_counter() - t0
        sb3 = _sb3_seconds(args.env, runs, steps)
        total = runs * result.timesteps
        print(f"R={runs:3d}  lockstep {lock:7.1f}s {total / lock:8.0f} steps/s "
              f"(env {result.env_seconds:.1f}s, update {result.update_seconds:.1f}s)  "
              f"sb3 {sb3:7.1f}s {total / sb3:8.0f} steps/s  ratio {sb3 / lock:5.2f}x")


if __name__ == "__main__":
    main()
