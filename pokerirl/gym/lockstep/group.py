"""The RL phase for R runs of one task in lock-step: :func:`train_rl_group`.

Per run it produces what :func:`pokerirl.gym.rl.train_rl` produces: the true-return curve
(deterministic evaluations of ``eval_episodes`` episodes, seeds ``EVAL_SEED + i``, at the same
timesteps as ``train_rl``'s callback, ``num_timesteps % every == 0`` before the budget, and one
at the end), the training episodes' env returns, and, given ``outs``, a run folder laid out as
``train_rl`` writes it (``config.json`` with ``"backend": "lockstep"``, an SB3-loadable
``model.pt``, ``metrics.jsonl``). The R runs' evaluation episodes are played together too, by
:func:`pokerirl.gym.episodes.play_episodes` with ``Batching.ALL``: one batched ``predict`` per
step for every run and episode.

Run r of a group equals a group of one with seed r (each run has its own random streams), which
is what lets a resumed study train only its unfinished runs as a group.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.execution import unit_progress
from pokerirl.gym.episodes import EVAL_SEED, Batching, play_episodes
from pokerirl.gym.presets import RLSettings
from pokerirl.gym.rewards import RewardCallable
from pokerirl.gym.rl import CurvePoint, RLBackend, RLResult, check_reward, save_run
from pokerirl.gym.tasks import task

BACKEND = RLBackend.LOCKSTEP


class LockstepAlgo(Protocol):
    """What the runner needs of LockstepPPO and LockstepDQN."""

    def learn(self, total_timesteps: int, *, callback: Any = None) -> Any: ...

    def predict(self, obs: np.ndarray) -> np.ndarray: ...


def lockstep_class(algo: str) -> type:
    """LockstepPPO (``ppo``) or LockstepDQN (``dqn``)."""
    if algo == "dqn":
        from pokerirl.gym.lockstep.dqn import LockstepDQN

        return LockstepDQN
    from pokerirl.gym.lockstep.ppo import LockstepPPO

    return LockstepPPO


def make_group(
    env_id: str,
    settings: RLSettings,
    *,
    seeds: Sequence[int],
    rewards: Sequence[RewardCallable | None],
) -> LockstepAlgo:
    """The lock-step algorithm of ``settings.algo`` for these runs."""
    algo_settings = settings.dqn if settings.algo == "dqn" else settings.ppo
    return lockstep_class(settings.algo)(env_id, algo_settings, seeds=seeds, rewards=rewards)


def train_rl_group(
    env_id: str,
    *,
    rewards: Sequence[RewardCallable | None],
    reward_names: Sequence[str],
    seeds: Sequence[int],
    settings: RLSettings | None = None,
    timesteps: int | None = None,
    evaluations: int = 10,
    eval_episodes: int = 5,
    outs: Sequence[str | os.PathLike[str]] | None = None,
) -> list[RLResult]:
    """R = ``len(seeds)`` runs of ``train_rl`` in lock-step: run r trains on ``rewards[r]``
    (``None``: the env reward) with seed ``seeds[r]``; ``outs[r]``, when given, gets its run
    folder."""
    from pokerirl.gym.envs import require_gym

    require_gym()
    settings = settings or task(env_id).rl
    timesteps = timesteps or settings.timesteps
    if timesteps < 1 or evaluations < 1 or eval_episodes < 1:
        raise ConfigError("timesteps, evaluations and eval_episodes must be positive")
    R = len(seeds)
    if R < 1 or len(rewards) != R or len(reward_names) != R or (outs is not None
                                                               and len(outs) != R):
        raise ValueError(f"a lock-step group needs one reward, name (and folder) per seed; "
                         f"got {R} seeds, {len(rewards)} rewards, {len(reward_names)} names")
    named = {id(reward): (reward, name) for reward, name in zip(rewards, reward_names, strict=True)}
    for reward, name in named.values():
        check_reward(env_id, reward, f"the reward of {name}")
    algo = make_group(env_id, settings, seeds=seeds, rewards=rewards)
    every = max(timesteps // evaluations, 1)
    curves: list[list[CurvePoint]] = [[] for _ in range(R)]

    def evaluate_now(steps: int) -> None:
        # Every run's episodes each step, finished ones included: the batch shape never changes.
        evaluations = play_episodes(env_id, algo.predict, episodes=eval_episodes, seed=EVAL_SEED,
                                    runs=R, batching=Batching.ALL)  # fmt: skip
        for r, evaluation in enumerate(evaluations):
            curves[r].append(CurvePoint(timesteps=steps, return_mean=evaluation.mean,
                                        return_std=evaluation.std))  # fmt: skip

    def on_step(steps: int) -> None:
        unit_progress(steps, timesteps)  # the driver's bar, when this group is a unit
        if steps % every == 0 and steps < timesteps:
            evaluate_now(steps)

    group = algo.learn(timesteps, callback=on_step)
    evaluate_now(group.timesteps)
    results = [
        RLResult(
            env=env_id,
            reward=reward_names[r],
            seed=int(seeds[r]),
            timesteps=timesteps,
            curve=tuple(curves[r]),
            train_episode_returns=tuple(float(x) for x in group.episode_returns[r]),
        )
        for r in range(R)
    ]
    if outs is not None:
        for r, out in enumerate(outs):
            save_run(Path(out), results[r], settings, group.state_dicts[r], backend=BACKEND)
    return results
