"""Gymnasium speed: the IRL phase against a re-implementation of the authors' loop, and the
RL phase on a learned reward against SB3 on the env reward.

    python benchmarks/gym.py [--irl-only | --rl-only] [--steps 20000] [--repeats 2]
                             [--runs 10] [--transitions 20000] [--peer-batches 300]

**IRL phase** (``--irl-only``). On real expert data (collected from the shipped experts) for
MountainCar-v0 (discrete) and Pendulum-v1 (continuous), with the task's H-AIRL settings
(nets, batch 64, α, β, the authors' noise schedule), expert samples per second of
optimization for

* ``train_many``: ``--runs`` runs in lock-step (all runs' samples together), as
  ``pokerirl gym irl`` trains them;
* ``train``: one run;
* the peer: the authors' kind of loop, re-implemented: one run at a time in plain PyTorch
  (``nn.Sequential`` MLPs of the task's sizes, one ``torch.optim.Adam`` per net, a fresh
  permutation per epoch sliced into mini-batches); per mini-batch, one discriminator step on
  the expert's actions against the policy's noisy ones, then one policy step, with the same
  losses as the core (so the ratio measures the implementation, not the algorithm), and the
  losses read with ``.item()`` for logging. ``--runs`` runs in sequence go at its one-run rate.

**RL phase** (``--rl-only``). For each task the same SB3 learner (the authors' settings: PPO
on Acrobot-v1 and Pendulum-v1, rl-zoo's DQN on MountainCar-v0) trains ``--steps`` steps on

* the env reward (plain SB3), and
* a learned reward: :func:`pokerirl.gym.rewards.learned_reward_env` with an MLP like the IRL
  reward net (64 hidden units, ReLU, over the state and the action vector),

alternating A, B, A, B ``--repeats`` times, and prints steps per second of each by CPU time
(the steadier clock on a shared machine) and by wall-clock, and the wrapper's cost as a ratio.
The target: the wrapper costs under 10% of the RL phase. A last line measures the worst case,
stepping the environments alone with random actions (no learning), where the reward net's
forward pass is not hidden behind gradient updates.

Only ratios from one run are comparable; absolute figures depend on the machine's load
(printed).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: numpy and torch must not fan out
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import itertools
import statistics
import tempfile
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.gym.collect import collect
from pokerirl.gym.envs import make_env
from pokerirl.gym.expert_policies import load_expert, make_model, resolve_expert_dir
from pokerirl.gym.irl import irl_config, load_env_transitions
from pokerirl.gym.presets import TASKS
from pokerirl.gym.rewards import RewardCallable, learned_reward_env, module_reward
from pokerirl.irl import AIRLConfig, Transitions, train, train_many
from pokerirl.irl.adversarial import (
    discriminator_loss,
    gaussian_log_prob,
    noise_schedule,
    sample_one_hot,
)
from pokerirl.irl.nets import project_to_simplex

TASK_NAMES = ("Acrobot-v1", "MountainCar-v0", "Pendulum-v1")
IRL_TASKS = ("MountainCar-v0", "Pendulum-v1")  # one discrete, one continuous


# --------------------------------------------------------------------------- IRL phase


def mlp(sizes: list[int]) -> nn.Sequential:
    """Linear layers with ReLU between them, as the authors' MLPs and the core's defaults."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(itertools.pairwise(sizes)):
        layers.append(nn.Linear(a, b))
        if i < len(sizes) - 2:
            layers.append(nn.ReLU())
    return nn.Sequential(*layers)


def peer_seconds_per_batch(data: Transitions, config: AIRLConfig, batches: int) -> list[float]:
    """The authors' kind of loop, one run: seconds per mini-batch, in windows of batches."""
    torch.manual_seed(config.seed)
    obs, expert, env = data.obs, data.action_vectors(), data.rewards
    d, k, batch = data.obs_dim, data.action_dim, config.batch_size
    reward = mlp([d + k, *config.reward_hidden, 1])
    policy = mlp([d, *config.policy_hidden, k])
    log_std = nn.Parameter(torch.full((k,), -0.5))
    policy_params = list(policy.parameters()) + ([] if data.discrete else [log_std])
    reward_opt = torch.optim.Adam(
        reward.parameters(), lr=config.reward_lr, weight_decay=config.reward_weight_decay
    )
    policy_opt = torch.optim.Adam(policy_params, lr=config.policy_lr)
    sigma = noise_schedule(
        batch, config.sigma_start, config.sigma_end, kind="authors", decay=config.noise_decay
    )
    if not data.discrete:
        low, high = torch.tensor(data.action_low), torch.tensor(data.action_high)
    eye = torch.eye(k)

    def f(s: Tensor, a: Tensor) -> Tensor:
        return reward(torch.cat((s, a), dim=-1)).squeeze(-1)

    window, times, step = max(batches // 4, 1), [], 0
    start = time.perf_counter()
    while step < batches:
        perm = torch.randperm(len(obs))
        for rows in perm[: len(perm) // batch * batch].view(-1, batch):
            s, a_e, r_env = obs[rows], expert[rows], env[rows]
            noise = sigma[torch.randperm(batch)][:, None] * torch.randn(batch, k)
            if data.discrete:
                log_pi = torch.log_softmax(policy(s), dim=-1)
                pi = log_pi.exp()
                lp = log_pi.detach()
                seen = project_to_simplex(sample_one_hot(pi.detach(), torch.rand(batch)) + noise)
                lp_e, lp_seen = (a_e * lp).sum(-1), (seen * lp).sum(-1)
            else:
                mean = low + (high - low) / 2 * (torch.tanh(policy(s)) + 1)
                std_row = log_std.expand_as(mean)
                sample = mean + std_row.exp() * torch.randn_like(mean)
                m, ls = mean.detach(), std_row.detach()
                seen = torch.clamp(sample.detach() + noise * (high - low), low, high)
                lp_e, lp_seen = gaussian_log_prob(a_e, m, ls), gaussian_log_prob(seen, m, ls)
            d_loss = discriminator_loss(
                f(s, a_e), lp_e, f(s, seen), lp_seen, beta=config.beta, env_reward=r_env
            )[0]
            reward_opt.zero_grad()
            d_loss.backward()
            reward_opt.step()
            if data.discrete:  # the exact expectation over actions, as the core's
                with torch.no_grad():
                    g = f(s[:, None].expand(-1, k, -1), eye.expand(batch, -1, -1))
                adversarial = (pi * (log_pi - g)).sum(-1).mean()
                supervised = -(a_e * log_pi).sum(-1).mean()
            else:
                adversarial = (gaussian_log_prob(sample, mean, std_row) - f(s, sample)).mean()
                supervised = (mean - a_e).square().sum(-1).mean()
            p_loss = (1 - config.alpha) * adversarial + config.alpha * supervised
            policy_opt.zero_grad()
            p_loss.backward()
            policy_opt.step()
            d_loss.item(), p_loss.item()  # per-step logging, as reference loops do
            step += 1
            if step % window == 0:
                now = time.perf_counter()
                times.append((now - start) / window)
                start = now
            if step >= batches:
                break
    return times


def expert_data(env_id: str, transitions: int, folder: Path) -> Transitions:
    """``transitions`` rows of the shipped expert's play (seed 0), as the IRL phase reads them."""
    path = folder / f"{env_id}.parquet"
    expert = load_expert(resolve_expert_dir("shipped", env_id))
    collect(expert, path, transitions=transitions, seed=0)
    return load_env_transitions(env_id, path)


def irl_phase(args: argparse.Namespace) -> None:
    print(
        f"IRL phase, H-AIRL with each task's settings, {args.transitions:,} expert transitions, "
        f"1 thread, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    print(
        f"{'task':<16}{f'train_many x{args.runs}':>18}{'train':>14}{'peer':>14}"
        f"{f'{args.runs} lock-step / peer':>24}{'train / peer':>14}"
    )
    with tempfile.TemporaryDirectory(prefix="pokerirl-bench-") as scratch:
        for env_id in IRL_TASKS:
            data = expert_data(env_id, args.transitions, Path(scratch))
            config = irl_config("hairl", TASKS[env_id].irl, seed=0)
            config = replace(config, epochs=args.epochs)
            train_data, val_data, _ = data.split(val_fraction=config.val_fraction, seed=0)
            many = train_many(
                train_data, val_data, config=config, seeds=range(args.runs), progress=False
            )
            lock_step = statistics.median(many.samples_per_epoch / s for s in many.epoch_seconds)
            one = train(train_data, val_data, config=config, progress=False)
            single = statistics.median(one.samples_per_epoch / s for s in one.epoch_seconds)
            per_batch = peer_seconds_per_batch(train_data, config, args.peer_batches)
            peer = config.batch_size / statistics.median(per_batch)
            print(
                f"{env_id:<16}{lock_step:>12,.0f} sa/s{single:>10,.0f} sa/s{peer:>10,.0f} sa/s"
                f"{lock_step / peer:>23.1f}x{single / peer:>13.1f}x  (train: {one.gradients})"
            )
    print("(sa/s: expert samples per second of optimization, all runs together; medians)")


# --------------------------------------------------------------------------- RL phase


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


def rl_phase(args: argparse.Namespace) -> None:
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    only = parser.add_mutually_exclusive_group()
    only.add_argument("--irl-only", action="store_true", help="the IRL-phase half only")
    only.add_argument("--rl-only", action="store_true", help="the RL-phase half only")
    parser.add_argument("--steps", type=int, default=20_000, help="RL: training steps")
    parser.add_argument("--repeats", type=int, default=2, help="RL: alternating repeats")
    parser.add_argument("--tasks", nargs="+", default=list(TASK_NAMES), help="RL: tasks")
    parser.add_argument("--runs", type=int, default=10, help="IRL: runs in lock-step")
    parser.add_argument("--transitions", type=int, default=20_000, help="IRL: expert rows")
    parser.add_argument("--epochs", type=int, default=3, help="IRL: epochs of ours")
    parser.add_argument("--peer-batches", type=int, default=400, help="IRL: peer's batches")
    args = parser.parse_args()
    torch.set_num_threads(1)
    warnings.filterwarnings("ignore")
    if not args.rl_only:
        irl_phase(args)
    if not args.irl_only:
        if not args.rl_only:
            print()
        rl_phase(args)


if __name__ == "__main__":
    main()
