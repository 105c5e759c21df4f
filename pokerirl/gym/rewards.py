"""The RL phase's learned reward: a VecEnv wrapper that replaces the env reward with f(s, a).

A reward is any callable ``f(obs, actions) -> rewards`` on a batch: ``obs`` ``(n, obs_dim)``
float32, ``actions`` ``(n,)`` ints (discrete) or ``(n, act_dim)`` floats (continuous, as the
env executes them), returning ``(n,)`` floats. :func:`pokerirl.irl.load_reward` returns one;
:func:`module_reward` turns a small ``nn.Module`` on ``[obs, action vector]`` into one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import torch

from pokerirl.errors import check_protocol
from pokerirl.irl.reward import RewardFn

if TYPE_CHECKING:
    from stable_baselines3.common.vec_env import VecEnv

RewardCallable = RewardFn  # the IRL core's reward callable, under the gym modules' name
ENV_REWARD_KEY = "env_reward"  # each step's info keeps the environment's own reward here


def module_reward(net: torch.nn.Module, *, num_actions: int | None) -> RewardCallable:
    """``f(obs, actions) = net(cat(obs, action vector))``, one-hot for discrete actions.

    >>> f = module_reward(torch.nn.Linear(3, 1), num_actions=2)
    >>> f(np.zeros((4, 1), np.float32), np.array([0, 1, 1, 0])).shape
    (4,)
    """

    # Built in numpy: at one env per step, torch's per-op overhead (one_hot, cat) would cost
    # more than the net itself.
    one_hot = None if num_actions is None else np.eye(num_actions, dtype=np.float32)

    def reward(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        actions = np.asarray(actions)
        vectors = actions.reshape(len(obs), -1) if one_hot is None else one_hot[actions.reshape(-1)]
        inputs = torch.from_numpy(np.concatenate([obs, vectors], axis=1, dtype=np.float32))
        with torch.inference_mode():
            return net(inputs).reshape(-1).numpy()

    return reward


def learned_reward_env(venv: VecEnv, reward: RewardCallable) -> VecEnv:
    """Wrap ``venv`` so each step's reward is ``reward(obs the action was taken in, action)``.

    Call it on the Monitor-wrapped environments' VecEnv (inside any normalisation wrapper), so
    ``reward`` sees raw observations and Monitor's ``info["episode"]`` still holds the true
    environment return for the learning curve. One batched call of ``reward`` per vector step.
    """
    check_protocol("venv", venv, ("reset", "step_async", "step_wait"),
                   "a stable-baselines3 VecEnv (make_vec_env gives one)")  # fmt: skip
    check_protocol("reward", reward, ("__call__",), "a callable reward(obs, actions)")
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class LearnedRewardVecEnv(VecEnvWrapper):
        def __init__(self) -> None:
            super().__init__(venv)
            self._obs: np.ndarray | None = None
            self._actions: np.ndarray | None = None

        def reset(self) -> np.ndarray:
            obs = np.asarray(self.venv.reset())  # flat Box observations: an array
            self._obs = obs
            return obs

        def step_async(self, actions: np.ndarray) -> None:
            self._actions = np.asarray(actions)
            self.venv.step_async(actions)

        def step_wait(self):
            if self._obs is None:
                raise RuntimeError("step before reset")
            obs, env_rewards, dones, infos = self.venv.step_wait()
            rewards = np.asarray(reward(self._obs, self._actions), dtype=np.float32)
            if rewards.shape != (self.num_envs,):
                raise ValueError(f"reward returned shape {rewards.shape}, not ({self.num_envs},)")
            for info, env_reward in zip(infos, env_rewards, strict=True):
                info[ENV_REWARD_KEY] = float(env_reward)
            # At an episode's end SB3 auto-resets: obs is the next episode's first state, which
            # is where the next action is taken, so it is the right state to keep.
            self._obs = obs
            return obs, rewards, dones, infos

    return LearnedRewardVecEnv()
