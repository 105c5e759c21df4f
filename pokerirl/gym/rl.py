"""The RL phase: SB3 PPO (DQN for MountainCar) on a learned reward or on the env reward.

The learning curve is always the environment's true return: periodic deterministic
evaluations on a plain environment, plus Monitor's returns of the training episodes. A run
folder holds ``config.json``, ``metrics.jsonl`` (the curve) and ``model.pt`` (the final
policy's ``state_dict``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import write_text, write_torch
from pokerirl.errors import ConfigError, InputError
from pokerirl.execution import unit_progress
from pokerirl.gym.envs import make_env, require_gym
from pokerirl.gym.episodes import EVAL_SEED, sb3_evaluation
from pokerirl.gym.expert_policies import gym_versions, make_model, policy_kwargs
from pokerirl.gym.manifest import CONFIG_FILE, METRICS_FILE, MODEL_FILE
from pokerirl.gym.presets import RLBackend, RLSettings
from pokerirl.gym.rewards import RewardCallable, learned_reward_env
from pokerirl.gym.tasks import task
from pokerirl.jsonio import read_json_lines
from pokerirl.meanstd import mean_and_std

# How the RL phase trains: SB3, one run per call (train_rl), or R runs of one task in one
# process (pokerirl.gym.lockstep.group.train_rl_group). lockstep is the default since its
# equivalence table with SB3 (docs/lockstep.md) holds on Acrobot, Pendulum and MountainCar.


RL_BACKENDS: tuple[str, ...] = tuple(RLBackend)
DEFAULT_RL_BACKEND = RLBackend.LOCKSTEP


@dataclass(frozen=True, kw_only=True)
class CurvePoint:
    """One evaluation of an RL run: a line of its ``metrics.jsonl``."""

    timesteps: int
    return_mean: float
    return_std: float

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> CurvePoint:
        mean, std = data["return_mean"], data["return_std"]
        return cls(timesteps=data["timesteps"], return_mean=mean, return_std=std)


def read_curve(run: Path) -> list[CurvePoint]:
    """The true-return curve of the RL run folder ``run`` (its ``metrics.jsonl``)."""
    return [CurvePoint.from_json(line) for line in read_json_lines(run / METRICS_FILE)]


@dataclass(frozen=True, kw_only=True)
class RLResult:
    """One RL run: its true-return curve and the final point."""

    env: str
    reward: str
    seed: int
    timesteps: int
    curve: tuple[CurvePoint, ...]
    train_episode_returns: tuple[float, ...]

    @property
    def final_return(self) -> float:
        return self.curve[-1].return_mean


def train_rl(
    env_id: str,
    *,
    reward: RewardCallable | None,
    reward_name: str,
    seed: int,
    settings: RLSettings | None = None,
    timesteps: int | None = None,
    evaluations: int = 10,
    eval_episodes: int = 5,
    out: str | os.PathLike[str] | None = None,
) -> RLResult:
    """Train on ``reward`` (``None``: the env reward) and measure the true return.

    ``evaluations`` periodic evaluations of ``eval_episodes`` deterministic episodes each are
    spread over the budget, the last at its end.
    """
    require_gym()
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import DummyVecEnv

    settings = settings or task(env_id).rl
    budget: int = timesteps or settings.timesteps
    if budget < 1 or evaluations < 1 or eval_episodes < 1:
        raise ConfigError("timesteps, evaluations and eval_episodes must be positive")
    check_reward(env_id, reward, f"the reward of {reward_name}")
    venv: Any = DummyVecEnv([lambda: Monitor(make_env(env_id))])
    if reward is not None:
        venv = learned_reward_env(venv, reward)
    model = make_model(env_id, settings, seed=seed, env=venv)
    every = max(budget // evaluations, 1)
    curve: list[CurvePoint] = []
    train_returns: list[float] = []

    def evaluate_now() -> None:
        model.policy.set_training_mode(False)
        result = sb3_evaluation(model.policy, env_id, episodes=eval_episodes, seed=EVAL_SEED)
        curve.append(CurvePoint(timesteps=model.num_timesteps, return_mean=result.mean,
                                return_std=result.std))  # fmt: skip

    class Curve(BaseCallback):
        def _on_step(self) -> bool:
            for info in self.locals["infos"]:
                if "episode" in info:  # Monitor: the true env return of a training episode
                    train_returns.append(float(info["episode"]["r"]))
            unit_progress(self.num_timesteps, budget)  # the driver's bar, when a unit
            if self.num_timesteps % every == 0 and self.num_timesteps < budget:
                evaluate_now()
            return True

    model.learn(total_timesteps=budget, callback=Curve())
    evaluate_now()
    venv.close()
    result = RLResult(
        env=env_id,
        reward=reward_name,
        seed=seed,
        timesteps=budget,
        curve=tuple(curve),
        train_episode_returns=tuple(train_returns),
    )
    if out is not None:
        _save(Path(out), result, settings, model)
    return result


def check_reward(env_id: str, reward: RewardCallable | None, name: str = "the reward") -> None:
    """Fail in one line, before training, on an unknown env or a reward that does not fit it
    (``name``: where the reward comes from, e.g. its run folder)."""
    env = make_env(env_id)
    try:
        obs, _ = env.reset(seed=0)
        if reward is None:
            return
        obs = np.asarray(obs, dtype=np.float32)[None]
        action = np.asarray(env.action_space.sample())[None]
        try:
            values = np.asarray(reward(obs, action))
        except (ValueError, RuntimeError, IndexError) as error:
            raise InputError(f"{name} does not fit {env_id}: {error}") from None
        if values.shape != (1,):
            raise InputError(f"{name} gives shape {values.shape} on {env_id}, not (1,)")
    finally:
        env.close()


def _save(out: Path, result: RLResult, settings: RLSettings, model: Any) -> None:
    state = {k: v.detach().cpu().clone() for k, v in model.policy.state_dict().items()}
    save_run(out, result, settings, state)


def save_run(
    out: Path,
    result: RLResult,
    settings: RLSettings,
    state: Mapping[str, Any],
    *,
    backend: str = RLBackend.SB3,
) -> None:
    """Write a run folder: ``metrics.jsonl``, ``model.pt`` (``state``, the SB3 policy's
    state_dict) and ``config.json``; a lock-step run's config also says ``"backend"`` (an
    SB3 run's is left as it always was)."""
    if backend not in RL_BACKENDS:
        raise ConfigError(f"unknown RL backend {backend!r}; choose one of {', '.join(RL_BACKENDS)}")
    out.mkdir(parents=True, exist_ok=True)
    record = {
        "env": result.env,
        "algo": settings.algo,
        "reward": result.reward,
        "seed": result.seed,
        "timesteps": result.timesteps,
        "final_return": result.final_return,
        "settings": asdict(settings.own),
        "policy_kwargs": policy_kwargs(settings),
        "train_episode_returns": list(result.train_episode_returns),
        "versions": gym_versions(),
        **({} if backend == RLBackend.SB3 else {"backend": backend}),  # sb3 records stay as before
    }
    write_text(out / METRICS_FILE, "".join(json.dumps(asdict(p)) + "\n" for p in result.curve))
    write_torch(out / MODEL_FILE, state)
    write_text(out / CONFIG_FILE, json.dumps(record, indent=2) + "\n")


def summarize(results: list[RLResult]) -> dict[str, float]:
    """Mean and sample std over runs of the final true return."""
    mean, std = mean_and_std([r.final_return for r in results])
    return {"mean": mean, "std": std, "runs": len(results)}
