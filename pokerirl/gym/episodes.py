"""Episode evaluation, one home for every caller: :func:`episode_steps` plays seeded episodes
(episode k of every run from ``reset(seed=seed + k)``) and yields their steps,
:func:`play_episodes` returns each run's :class:`Evaluation` (returns and lengths).

Callers differ only in how a step's observations are batched for the policy (a batch's size can
change a network's floating-point bits, so each caller keeps its own; see :class:`Batching`):

- the IRL phase's epoch evaluation, :func:`random_return` and reward quality's rollouts: one
  policy, the running episodes (``RUNNING``);
- the lock-step RL group's curve: R policies at once, every episode each step (``ALL``);
- SB3 policies (``gym expert``'s records, ``train_rl``'s curve): :func:`sb3_evaluation`, an
  adapter playing SB3's ``evaluate_policy`` order, one episode after another (``SINGLE``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import torch
from torch import nn

if TYPE_CHECKING:
    import gymnasium
    from stable_baselines3.common.policies import BasePolicy

EVAL_SEED = 2_000_000  # evaluation episodes' seeds, apart from the experts' and the data's


class Batching(StrEnum):
    """Which observations ``act`` gets at each step."""

    RUNNING = "running"  # the episodes still running: (n, *obs_shape)
    ALL = "all"  # every episode of every run, finished ones on their last observation (acted
    # on, never stepped): (runs, episodes, *obs_shape), answered (runs, episodes, ...)
    SINGLE = "single"  # one episode after another on one env: (1, *obs_shape)


class Step(NamedTuple):
    """One env step; ``slot`` is ``run * episodes + episode``."""

    slot: int
    obs: np.ndarray
    action: Any
    reward: float
    next_obs: np.ndarray


@dataclass(frozen=True, kw_only=True)
class Evaluation:
    """Returns (and lengths) of a policy over whole episodes."""

    returns: tuple[float, ...]
    lengths: tuple[int, ...]

    @property
    def mean(self) -> float:
        return float(np.mean(self.returns))

    @property
    def std(self) -> float:
        return float(np.std(self.returns))


def policy_actions(policy: nn.Module, obs: np.ndarray, *, discrete: bool) -> np.ndarray:
    """The deterministic policy's actions for a batch: argmax, or the mean clipped to the box."""
    with torch.no_grad():
        obs_t = torch.as_tensor(obs, dtype=torch.float32)
        if discrete:
            return policy(obs_t, None).argmax(-1).numpy()
        mean, _ = policy(obs_t)
        low, high = policy.get_buffer("low"), policy.get_buffer("high")
        return torch.minimum(torch.maximum(mean, low), high).numpy()


def episode_steps(
    env_id: str,
    act: Callable[[np.ndarray], np.ndarray],
    *,
    episodes: int,
    seed: int = EVAL_SEED,
    runs: int = 1,
    batching: Batching = Batching.RUNNING,
) -> Iterator[Step]:
    """Every step of ``runs`` x ``episodes`` episodes (episode k of every run from
    ``reset(seed=seed + k)``); ``act`` maps the observations ``batching`` says to actions."""
    from pokerirl.gym.envs import make_env  # gymnasium is imported lazily

    if runs > 1 and batching != Batching.ALL:
        raise ValueError("a batch of policies plays with Batching.ALL: its rows say whose")
    seeds = [seed + k for _ in range(runs) for k in range(episodes)]
    if batching == Batching.SINGLE:
        env = make_env(env_id)
        try:
            for slot, one in enumerate(seeds):
                yield from _lockstep([env], [one], act, slot=slot)
        finally:
            env.close()
        return
    envs = [make_env(env_id) for _ in seeds]
    try:
        yield from _lockstep(envs, seeds, act, runs=runs if batching == Batching.ALL else None)
    finally:
        for env in envs:
            env.close()


def _lockstep(
    envs: list[gymnasium.Env],
    seeds: list[int],
    act: Callable[[np.ndarray], np.ndarray],
    *,
    runs: int | None = None,
    slot: int = 0,
) -> Iterator[Step]:
    """The loop: ``runs`` given, ``act`` gets every episode as (runs, episodes, ...); else the
    running ones. Slots are numbered from ``slot``."""
    obs = [env.reset(seed=one)[0] for env, one in zip(envs, seeds, strict=True)]
    running = list(range(len(envs)))
    while running:
        if runs is None:
            actions = act(np.stack([obs[k] for k in running]).astype(np.float32))
        else:
            batch = np.stack(obs).astype(np.float32)
            answer = act(batch.reshape(runs, len(envs) // runs, *batch.shape[1:]))
            actions = answer.reshape(len(envs), *answer.shape[2:])
        still = []
        for row, k in enumerate(running):
            action = actions[row if runs is None else k]
            nxt, reward, terminated, truncated, _ = envs[k].step(action)
            yield Step(slot + k, obs[k], action, float(reward), nxt)
            obs[k] = nxt
            if not (terminated or truncated):
                still.append(k)
        running = still


def play_episodes(
    env_id: str,
    act: Callable[[np.ndarray], np.ndarray],
    *,
    episodes: int,
    seed: int = EVAL_SEED,
    runs: int = 1,
    batching: Batching = Batching.RUNNING,
) -> tuple[Evaluation, ...]:
    """Each run's :class:`Evaluation` over the episodes of :func:`episode_steps`."""
    totals = np.zeros(runs * episodes)
    lengths = np.zeros(runs * episodes, dtype=np.int64)
    for step in episode_steps(env_id, act, episodes=episodes, seed=seed, runs=runs,
                              batching=batching):  # fmt: skip
        totals[step.slot] += step.reward
        lengths[step.slot] += 1
    return tuple(
        Evaluation(returns=tuple(float(x) for x in totals[r * episodes:(r + 1) * episodes]),
                   lengths=tuple(int(n) for n in lengths[r * episodes:(r + 1) * episodes]))
        for r in range(runs)
    )  # fmt: skip


def sb3_evaluation(policy: BasePolicy, env_id: str, *, episodes: int, seed: int) -> Evaluation:
    """An SB3 policy's deterministic episodes in SB3's ``evaluate_policy`` order (one after
    another on one env, a batch of one: the order the expert records and SB3 curves hold)."""

    def act(obs: np.ndarray) -> np.ndarray:
        actions, _ = policy.predict(obs, deterministic=True)
        return actions

    return play_episodes(env_id, act, episodes=episodes, seed=seed, batching=Batching.SINGLE)[0]


def random_return(env_id: str, *, episodes: int, seed: int = EVAL_SEED) -> float:
    """A uniformly random policy's mean return on the evaluation episodes (seeded)."""
    from pokerirl.gym.envs import make_env

    env = make_env(env_id)
    space = env.action_space
    env.close()
    space.seed(seed)
    return play_episodes(
        env_id, lambda obs: np.stack([space.sample() for _ in obs]), episodes=episodes, seed=seed
    )[0].mean
