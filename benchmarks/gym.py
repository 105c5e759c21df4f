"""RL-phase speed: SB3 on a learned reward (our VecEnv wrapper) against SB3 on the env reward.

    python benchmarks/gym.py [--steps 20000] [--repeats 2]

For each task the same SB3 learner (the authors' settings: PPO on Acrobot-v1 and Pendulum-v1,
rl-zoo's DQN on MountainCar-v0) trains ``--steps`` steps on

* the env reward (plain SB3), and
* a learned reward: :func:`pokerirl.gym.rewards.learned_reward_env` with an MLP like the IRL
  reward net (64 hidden units, ReLU, over the state and the action vector),

alternating A, B, A, B ``--repeats`` times, and prints steps per second of each by CPU time
(the steadier clock on a shared machine) and by wall-clock, and the wrapper's cost as a ratio.
The target: the wrapper costs under 10% of the RL phase. A last line measures the worst case,
stepping the environments alone with random actions (no learning), where the reward net's
forward pass is not hidden behind gradient updates. Only ratios from one run are comparable.

(The IRL-phase half of this benchmark, against a re-implementation of the authors' loop,
comes with the Gymnasium IRL phase.)
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy and torch must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

from pokerirl.gym.experts import make_env, make_model  # noqa: E402
from pokerirl.gym.presets import TASKS  # noqa: E402
from pokerirl.gym.rewards import RewardCallable, learned_reward_env, module_reward  # noqa: E402

TASK_NAMES = ("Acrobot-v1", "MountainCar-v0", "Pendulum-v1")


def reward_mlp(env_id: str) -> RewardCallable:
    env = make_env(env_id)
    obs_dim = env.observation_space.shape[0]
    discrete = hasattr(env.action_space, "n")
    action_dim = env.action_space.n if discrete else env.action_space.shape[0]
    env.close()
    torch.manual_seed(0)
    net = torch.nn.Sequential(
        torch.nn.Linear(obs_dim + action_dim, 64), torch.nn.ReLU(), torch.nn.Linear(64, 1)
    )
    return module_reward(net, num_actions=action_dim if discrete else None)


def venv_for(env_id: str, reward: RewardCallable | None, seed: int):
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import DummyVecEnv

    venv = DummyVecEnv([lambda: Monitor(make_env(env_id))])
    return venv if reward is None else learned_reward_env(venv, reward)


def train_seconds(env_id: str, reward: RewardCallable | None, steps: int) -> tuple[float, float]:
    """(CPU, wall) seconds of ``steps`` SB3 training steps (model construction excluded)."""
    model = make_model(env_id, TASKS[env_id].rl, seed=0, env=venv_for(env_id, reward, 0))
    wall, cpu = time.perf_counter(), time.process_time()
    model.learn(total_timesteps=steps)
    return time.process_time() - cpu, time.perf_counter() - wall


def rollout_seconds(env_id: str, reward: RewardCallable | None, steps: int) -> float:
    """CPU seconds of ``steps`` random-action vector steps, no learning."""
    venv = venv_for(env_id, reward, 0)
    venv.reset()
    rng = np.random.default_rng(0)
    space = venv.action_space
    actions = (
        rng.integers(0, space.n, size=(steps, 1))
        if hasattr(space, "n")
        else rng.uniform(space.low, space.high, size=(steps, 1, *space.shape)).astype(np.float32)
    )
    cpu = time.process_time()
    for a in actions:
        venv.step(a)
    return time.process_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--tasks", nargs="+", default=list(TASK_NAMES))
    args = parser.parse_args()
    torch.set_num_threads(1)
    warnings.filterwarnings("ignore")

    print(f"RL phase, {args.steps:,} training steps x {args.repeats} alternating repeats, 1 thread")
    print(f"{'task':<16}{'algo':<6}{'env reward':>14}{'learned':>14}{'cost (cpu)':>12}"
          f"{'cost (wall)':>13}")  # fmt: skip
    for env_id in args.tasks:
        reward = reward_mlp(env_id)
        plain, learned = np.zeros(2), np.zeros(2)
        for _ in range(args.repeats):
            plain += train_seconds(env_id, None, args.steps)
            learned += train_seconds(env_id, reward, args.steps)
        total = args.steps * args.repeats
        cost = learned / plain - 1
        print(
            f"{env_id:<16}{TASKS[env_id].rl.algo:<6}{total / plain[0]:>10,.0f} st/s"
            f"{total / learned[0]:>10,.0f} st/s{cost[0]:>+11.1%}{cost[1]:>+13.1%}"
        )
    steps = 20_000
    print(f"\nworst case: {steps:,} random-action steps, no learning (CPU time)")
    for env_id in args.tasks:
        reward = reward_mlp(env_id)
        plain = sum(rollout_seconds(env_id, None, steps) for _ in range(args.repeats))
        learned = sum(rollout_seconds(env_id, reward, steps) for _ in range(args.repeats))
        per_step_us = (learned - plain) / (steps * args.repeats) * 1e6
        print(
            f"{env_id:<16}{steps * args.repeats / plain:>10,.0f} st/s"
            f"{steps * args.repeats / learned:>10,.0f} st/s  +{per_step_us:.0f} us/step"
        )


if __name__ == "__main__":
    main()
