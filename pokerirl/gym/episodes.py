"""Episodes played in lock-step: every step of N seeded episodes (:func:`lockstep_steps`),
their returns (:func:`episode_returns`), a trained policy's deterministic actions
(:func:`policy_actions`) and a random policy's return (:func:`random_return`). What the IRL
phase evaluates each epoch and what reward quality rolls out; apart from both so that neither
imports the other.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import torch
from torch import nn

from pokerirl.gym.experts import make_env
from pokerirl.gym.rl import EVAL_SEED


def policy_actions(policy: nn.Module, obs: np.ndarray, *, discrete: bool) -> np.ndarray:
    """The deterministic policy's actions for a batch: argmax, or the mean clipped to the box."""
    with torch.no_grad():
        obs_t = torch.as_tensor(obs, dtype=torch.float32)
        if discrete:
            return policy(obs_t, None).argmax(-1).numpy()
        mean, _ = policy(obs_t)
        low, high = policy.get_buffer("low"), policy.get_buffer("high")
        return torch.minimum(torch.maximum(mean, low), high).numpy()


def lockstep_steps(
    env_id: str,
    act: Callable[[np.ndarray], np.ndarray],
    *,
    episodes: int,
    seed: int = EVAL_SEED,
) -> Iterator[tuple[int, np.ndarray, Any, float, np.ndarray]]:
    """Every step ``(episode, obs, action, reward, next_obs)`` of ``episodes`` episodes played
    in lock-step (episode k from ``reset(seed=seed + k)``); ``act`` maps a batch of
    observations (the episodes still running) to actions."""
    envs = [make_env(env_id) for _ in range(episodes)]
    try:
        obs = [env.reset(seed=seed + k)[0] for k, env in enumerate(envs)]
        running = list(range(episodes))
        while running:
            actions = act(np.stack([obs[k] for k in running]).astype(np.float32))
            still = []
            for row, k in enumerate(running):
                nxt, reward, terminated, truncated, _ = envs[k].step(actions[row])
                yield k, obs[k], actions[row], float(reward), nxt
                obs[k] = nxt
                if not (terminated or truncated):
                    still.append(k)
            running = still
    finally:
        for env in envs:
            env.close()


def episode_returns(
    env_id: str,
    act: Callable[[np.ndarray], np.ndarray],
    *,
    episodes: int,
    seed: int = EVAL_SEED,
) -> np.ndarray:
    """Returns of ``episodes`` episodes played in lock-step (see :func:`lockstep_steps`)."""
    totals = np.zeros(episodes)
    for k, _, _, reward, _ in lockstep_steps(env_id, act, episodes=episodes, seed=seed):
        totals[k] += reward
    return totals


def random_return(env_id: str, *, episodes: int, seed: int = EVAL_SEED) -> float:
    """A uniformly random policy's mean return on the evaluation episodes (seeded)."""
    env = make_env(env_id)
    space = env.action_space
    env.close()
    space.seed(seed)
    return float(
        episode_returns(
            env_id,
            lambda obs: np.stack([space.sample() for _ in obs]),
            episodes=episodes,
            seed=seed,
        ).mean()
    )
