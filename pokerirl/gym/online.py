"""Online IRL on a Gymnasium task (``gym irl --mode online``): SB3 PPO as the generator of
:mod:`pokerirl.irl.online`, rolling out in vectorized copies of the env on the current
learned reward.

:class:`PPOGenerator` is the :class:`~pokerirl.irl.online.Generator`:

* its envs are SB3's ``make_vec_env`` (``DummyVecEnv`` of Monitor-wrapped envs), their
  observations standardized with the expert data's mean and std (as the offline nets see
  them), and their reward replaced by the learned f
  (:func:`pokerirl.gym.rewards.learned_reward_env`, imitation's ``RewardVecEnvWrapper``);
* ``collect`` is PPO's own ``collect_rollouts`` into its rollout buffer; ``learn`` replaces
  each buffered f of collection time by the relabelled one (a time limit's bootstrap
  γ·V(s_T) that SB3 added stays), recomputes returns and advantages, and runs PPO's
  ``train``; ``log_prob`` is ``evaluate_actions``'s distribution;
* its actor has the IRL policy's form (``policy_hidden`` and ``activation``; for a box, the
  mean squashed into the box by tanh and a free log σ), so :meth:`PPOGenerator.policy_net`
  copies it exactly into a :mod:`pokerirl.irl.nets` policy, and the run folder's
  ``policy.pt`` is the generator itself.

:func:`train_gym_online` writes the folder :func:`pokerirl.gym.irl.train_gym_irl` writes
(``run-<k>`` through :func:`~pokerirl.irl.run.begin_run` and
:func:`~pokerirl.irl.run.save_run`, ``summary.json``, figures, reward quality), each run's
``config.json`` recording ``data.mode = "online"`` and the generator's settings. Runs train
one after another (each its own PPO). Like the offline command, a killed run leaves the
earlier outputs or the new ones, never a mix, and starts over when run again.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.atomic import make_shareable
from pokerirl.errors import ConfigError
from pokerirl.execution import progress_share, unit_progress
from pokerirl.gym.envs import make_env, require_gym
from pokerirl.gym.episodes import random_return
from pokerirl.gym.irl import (
    STAGE_KEY,
    EnvReturns,
    GymIRLResult,
    check_destination,
    expert_return,
    irl_config,
    load_env_transitions,
    obs_standardization,
    standardized,
    write_summary,
)
from pokerirl.gym.presets import GENERIC_PPO, IRLSettings, PPOSettings
from pokerirl.gym.quality import has_true_reward, write_reward_quality
from pokerirl.gym.rewards import learned_reward_env
from pokerirl.gym.tasks import task
from pokerirl.irl.config import IRLMode
from pokerirl.irl.metrics import Metric
from pokerirl.irl.nets import ACTIVATIONS, fold_obs_standardization
from pokerirl.irl.online import Rollout, train_online_run
from pokerirl.irl.plots import plot_curves
from pokerirl.irl.records import EpochMetrics
from pokerirl.irl.run import (
    BASELINE_SHARE,
    ObsMap,
    RunResult,
    data_record,
    drawn_baselines,
    run_baselines,
    save_run,
)
from pokerirl.irl.transitions import Transitions
from pokerirl.store import staged_files

if TYPE_CHECKING:
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecEnv

TRAINED_SHARE = 0.9  # of a unit's progress, as offline: saving and reward quality take the rest


@dataclass(frozen=True, kw_only=True)
class OnlineSettings:
    """The generator's budget: ``rounds`` of ``generator_steps`` env steps over ``envs``
    vectorized envs (PPO's n_steps = generator_steps / envs), with ``ppo``'s settings (the
    task's RL PPO, else SB3's defaults; n_steps, the net and log σ's start are the online
    loop's own)."""

    rounds: int = 20
    generator_steps: int = 2048
    envs: int = 4
    ppo: PPOSettings | None = None
    log_std_init: float = field(default=-0.5)  # pokerirl's GaussianPolicy starts there

    def __post_init__(self) -> None:
        if self.rounds < 1 or self.envs < 1:
            raise ConfigError("online IRL needs at least 1 round and 1 env")
        if self.generator_steps < self.envs or self.generator_steps % self.envs:
            raise ConfigError(
                f"generator steps ({self.generator_steps}) must be a positive multiple of "
                f"the envs ({self.envs})"
            )

    def ppo_for(self, env_id: str) -> PPOSettings:
        """The PPO settings of ``env_id``'s generator: ``ppo``, the task's RL PPO, or SB3's."""
        rl = task(env_id).rl
        base = self.ppo or rl.ppo or GENERIC_PPO
        return replace(base, n_steps=self.generator_steps // self.envs)


# --------------------------------------------------------------------------- the generator


class PPOGenerator:
    """SB3 PPO on ``env_id`` as an online IRL :class:`~pokerirl.irl.online.Generator`.

    ``reward`` is the learned f on standardized observations (``shift``, ``scale``), read at
    every env step; ``policy`` a :mod:`pokerirl.irl.nets` policy of the run's form, which
    :meth:`policy_net` fills with the generator's actor.
    """

    def __init__(
        self,
        *,
        env_id: str,
        reward: nn.Module,
        policy: nn.Module,
        config_activation: str,
        policy_hidden: tuple[int, ...],
        shift: Tensor,
        scale: Tensor,
        settings: OnlineSettings,
        seed: int,
    ) -> None:
        self.reward, self.policy = reward, policy
        space = make_env_space(env_id)
        self.discrete = hasattr(space, "n")
        self.num_actions = int(space.n) if self.discrete else 0
        self.recorded: list[np.ndarray] = []  # f of each vector step while collecting
        venv = standardized_env(vec_env(env_id, settings, seed=seed), shift.numpy(), scale.numpy())
        self.venv = learned_reward_env(venv, self.learned_reward)
        self.model = generator_model(
            env_id,
            self.venv,
            settings=settings,
            seed=seed,
            policy_hidden=policy_hidden,
            activation=config_activation,
        )
        total = settings.rounds * settings.generator_steps
        _, self.callback = self.model._setup_learn(total, None, True, "online", False)
        self.total = total

    def learned_reward(self, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """f(s, a) of one vector step (what the env wrapper asks), recorded for relabelling."""
        with torch.no_grad():
            f = self.reward(torch.as_tensor(obs, dtype=torch.float32), self.vectors(actions))
        rewards = f.numpy().astype(np.float32)
        self.recorded.append(rewards)
        return rewards

    def vectors(self, actions: np.ndarray | Tensor) -> Tensor:
        """Action vectors (B, k) of env actions: one-hots, or box values."""
        actions = torch.as_tensor(np.asarray(actions))
        if self.discrete:
            return torch.nn.functional.one_hot(actions.reshape(-1).long(), self.num_actions).float()
        return actions.reshape(len(actions), -1).float()

    # ------------------------------------------------------------------ the protocol

    def collect(self, steps: int) -> Rollout:
        model = self.model
        assert steps == model.n_steps * model.n_envs  # OnlineSettings fixes n_steps
        self.recorded = []
        model.collect_rollouts(model.env, self.callback, model.rollout_buffer,  # type: ignore[arg-type]
                               n_rollout_steps=model.n_steps)  # fmt: skip
        buffer = model.rollout_buffer
        obs = torch.as_tensor(buffer.observations.reshape(steps, -1), dtype=torch.float32)
        if self.discrete:
            actions = torch.as_tensor(buffer.actions.reshape(-1)).long()
            extra: dict[str, Any] = {"num_actions": self.num_actions}
        else:
            low, high = model.action_space.low, model.action_space.high  # type: ignore[attr-defined]
            clipped = np.clip(buffer.actions, low, high)  # what the envs executed
            actions = torch.as_tensor(clipped.reshape(steps, -1), dtype=torch.float32)
            extra = {"action_low": tuple(map(float, low)), "action_high": tuple(map(float, high))}
        transitions = Transitions(obs=obs, actions=actions, groups=np.arange(steps), **extra)
        log_probs = torch.as_tensor(buffer.log_probs.reshape(-1), dtype=torch.float32)
        return Rollout(transitions=transitions, log_probs=log_probs)

    def log_prob(self, obs: Tensor, actions: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        # Gymnasium's actions are all legal: a mask, if any, is all True.
        distribution: Any = self.model.policy.get_distribution(obs).distribution
        if self.discrete:
            return (actions * torch.log_softmax(distribution.logits, -1)).sum(-1)
        return distribution.log_prob(actions).sum(-1)

    def learn(self, rollout: Rollout, rewards: Tensor) -> Mapping[str, float]:
        model, buffer = self.model, self.model.rollout_buffer
        collected = np.stack(self.recorded)  # (n_steps, n_envs), the order of the buffer's rows
        relabelled = rewards.numpy().reshape(collected.shape)
        buffer.rewards += relabelled - collected  # keeps SB3's time-limit bootstrap
        with torch.no_grad():
            last_obs = torch.as_tensor(model._last_obs, dtype=torch.float32)  # type: ignore[arg-type]
            last_values = model.policy.predict_values(last_obs)
        assert model._last_episode_starts is not None  # set by collect_rollouts
        buffer.compute_returns_and_advantage(last_values=last_values,
                                             dones=model._last_episode_starts)  # fmt: skip
        model._update_current_progress_remaining(model.num_timesteps, self.total)
        model.train()
        logged = model.logger.name_to_value
        return {
            Metric.POLICY_LOSS: float(logged["train/loss"]),
            "policy_entropy": float(-logged["train/entropy_loss"]),
            "generator_steps": float(model.num_timesteps),
        }

    def imitate(
        self, obs: Tensor, actions: Tensor, *, weight: float, legal_mask: Tensor | None = None
    ) -> float:
        policy = self.model.policy
        loss = -weight * self.log_prob(obs, actions).mean()
        policy.optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(policy.parameters(), self.model.max_grad_norm)
        policy.optimizer.step()
        return float(loss.detach())

    def policy_net(self) -> nn.Module:
        """The actor's Linear layers, in order, into the policy's MLP (log σ too)."""
        sb3 = self.model.policy
        source: list[Any] = [m for m in sb3.mlp_extractor.policy_net if isinstance(m, nn.Linear)]
        source.append(sb3.action_net)
        target = [m for m in self.policy.mlp if isinstance(m, nn.Linear)]  # type: ignore[union-attr]
        with torch.no_grad():
            for into, of in zip(target, source, strict=True):
                into.weight.copy_(of.weight)
                into.bias.copy_(of.bias)
            if not self.discrete:
                self.policy.log_std.copy_(sb3.log_std)  # type: ignore[union-attr, operator]
        return self.policy


def vec_env(env_id: str, settings: OnlineSettings, *, seed: int) -> VecEnv:
    """SB3's ``make_vec_env``: ``settings.envs`` Monitor-wrapped copies in a ``DummyVecEnv``."""
    require_gym()
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv

    return make_vec_env(functools.partial(make_env, env_id), n_envs=settings.envs, seed=seed,
                        vec_env_cls=DummyVecEnv)  # fmt: skip


def generator_model(
    env_id: str,
    venv: VecEnv,
    *,
    settings: OnlineSettings,
    seed: int,
    policy_hidden: tuple[int, ...],
    activation: str,
) -> PPO:
    """The generator's SB3 PPO on ``venv``: ``settings``' PPO, its actor of the IRL policy's
    form (hidden widths, activation; a box's mean squashed into the box)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger

    discrete = hasattr(venv.action_space, "n")
    kwargs: dict[str, Any] = {
        "net_arch": {"pi": list(policy_hidden), "vf": list(policy_hidden)},
        "activation_fn": ACTIVATIONS[activation],
    }
    if not discrete:
        kwargs["log_std_init"] = settings.log_std_init
    policy_class = "MlpPolicy" if discrete else box_mean_policy()
    model = PPO(policy_class, venv, seed=seed, policy_kwargs=kwargs, device="cpu",
                **ppo_kwargs(settings.ppo_for(env_id)))  # fmt: skip
    model.set_logger(Logger(folder=None, output_formats=[]))  # no /tmp/SB3-<date> folders
    return model


def ppo_kwargs(ppo: PPOSettings) -> dict[str, Any]:
    """SB3 PPO's keyword arguments of ``ppo`` (its net is the IRL policy's: not among them)."""
    kwargs = asdict(ppo)
    for key in ("net_arch", "activation", "log_std_init", "ortho_init"):
        kwargs.pop(key)
    return kwargs


def make_env_space(env_id: str) -> Any:
    """``env_id``'s action space."""
    env = make_env(env_id)
    try:
        return env.action_space
    finally:
        env.close()


def standardized_env(venv: VecEnv, shift: np.ndarray, scale: np.ndarray) -> VecEnv:
    """``venv`` whose observations are ``(obs - shift) / scale`` (the expert data's)."""
    from stable_baselines3.common.vec_env import VecEnvWrapper

    def convert(obs: np.ndarray) -> np.ndarray:
        return ((obs - shift) / scale).astype(np.float32)

    class StandardizedObs(VecEnvWrapper):
        def reset(self) -> np.ndarray:
            return convert(np.asarray(self.venv.reset()))

        def step_wait(self):  # type: ignore[no-untyped-def]
            obs, rewards, dones, infos = self.venv.step_wait()
            for info in infos:  # SB3 bootstraps a time limit from the terminal observation
                if "terminal_observation" in info:
                    info["terminal_observation"] = convert(info["terminal_observation"])
            return convert(obs), rewards, dones, infos

    return StandardizedObs(venv)


@functools.cache
def box_mean_policy() -> type:
    """SB3's ``ActorCriticPolicy`` with the mean squashed into the action box by tanh, the
    form of :class:`pokerirl.irl.nets.GaussianPolicy` (SB3 clips actions instead)."""
    from stable_baselines3.common.distributions import DiagGaussianDistribution
    from stable_baselines3.common.policies import ActorCriticPolicy

    class BoxMeanPolicy(ActorCriticPolicy):
        def _get_action_dist_from_latent(self, latent_pi: Tensor) -> Any:
            assert isinstance(self.action_dist, DiagGaussianDistribution)
            low = torch.as_tensor(self.action_space.low, dtype=torch.float32)  # type: ignore[attr-defined]
            high = torch.as_tensor(self.action_space.high, dtype=torch.float32)  # type: ignore[attr-defined]
            mean = low + (high - low) / 2 * (torch.tanh(self.action_net(latent_pi)) + 1)
            return self.action_dist.proba_distribution(mean, self.log_std)

    return BoxMeanPolicy


# --------------------------------------------------------------------------- the command


def train_gym_online(
    env_id: str,
    data_path: str | os.PathLike[str],
    *,
    algo: str,
    runs: int,
    settings: IRLSettings | None = None,
    online: OnlineSettings | None = None,
    seed: int = 0,
    out: str | os.PathLike[str],
    overwrite: bool = False,
    progress: bool = True,
    on_round: Callable[[int, EpochMetrics], None] | None = None,
    data_label: str | os.PathLike[str] | None = None,
) -> GymIRLResult:
    """``runs`` online IRL runs (seeds ``seed + k``) of ``algo`` on ``data_path``, one after
    another, into ``out`` as :func:`~pokerirl.gym.irl.train_gym_irl` writes it; ``on_round``
    gets each run's index and round line; ``data_label`` as offline (the path the configs
    record)."""
    if runs < 1:
        raise ConfigError("runs must be at least 1")
    settings = settings or task(env_id).irl
    online = online or OnlineSettings()
    out = Path(out)
    check_destination(out, runs=runs, overwrite=overwrite)
    config = irl_config(algo, settings, seed=seed)
    data = load_env_transitions(env_id, data_path)
    train_data, val_data, val_groups = data.split(val_fraction=config.val_fraction, seed=seed)
    shift, scale = obs_standardization(train_data, enabled=settings.standardize_obs)
    train_data = standardized(train_data, shift, scale)
    val_data = standardized(val_data, shift, scale)
    with progress_share(0.0, BASELINE_SHARE):
        core = run_baselines(train_data, val_data, config=config, progress=progress)
    found = {
        **core,
        "random": random_return(env_id, episodes=settings.eval_episodes),
        "expert": expert_return(env_id, data_path),
    }
    generator_record = {
        "rounds": online.rounds,
        "generator_steps": online.generator_steps,
        "envs": online.envs,
        "ppo": ppo_kwargs(online.ppo_for(env_id)),
        "log_std_init": online.log_std_init,
    }
    data_info = {
        "env": env_id,
        **data_record(data, train_data, val_data, path=data_label or data_path),
        "obs_standardization": {"shift": shift.tolist(), "scale": scale.tolist()}
        if settings.standardize_obs
        else None,
        "mode": IRLMode.ONLINE.value,
        "generator": generator_record,
    }

    # The offline command's per-epoch return, its observations mapped as the policy was trained.
    env_returns = EnvReturns(
        obs_map=ObsMap(shift=shift, scale=scale),
        env_id=env_id,
        discrete=data.discrete,
        episodes=settings.eval_episodes,
    )

    with staged_files(out, key=STAGE_KEY) as stage:
        make_shareable(stage)
        results = []
        for k in range(runs):
            run_seed = seed + k
            folder = stage / f"run-{k}"
            make_generator = functools.partial(
                PPOGenerator, env_id=env_id, config_activation=config.activation,
                policy_hidden=tuple(config.policy_hidden), shift=shift, scale=scale,
                settings=online, seed=run_seed,
            )  # fmt: skip
            start, end = BASELINE_SHARE, TRAINED_SHARE
            with progress_share(start + (end - start) * k / runs,
                                start + (end - start) * (k + 1) / runs):  # fmt: skip
                result = train_online_run(
                    folder, demonstrations=train_data, validation=val_data,
                    val_groups=val_groups, baselines=found,
                    config=replace(config, seed=run_seed),
                    make_generator=make_generator,
                    rounds=online.rounds, generator_steps=online.generator_steps,
                    on_round=None if on_round is None else functools.partial(on_round, k),
                    callback=env_returns,
                )  # fmt: skip
            fold_obs_standardization(result.reward, shift, scale)
            fold_obs_standardization(result.policy, shift, scale)
            save_run(result, folder, algo=algo, data=data_info, baselines=found)
            plot_curves(result.metrics, folder, baselines=drawn_baselines(core, data))
            if has_true_reward(env_id):
                write_reward_quality(folder, env_id=env_id, data_path=data_path)
            results.append(
                RunResult(
                    out=str(out / folder.name), seed=run_seed, metrics=tuple(result.metrics),
                    baselines=found, samples_per_second=result.samples_per_second,
                    train_rows=len(train_data), val_rows=len(val_data),
                )
            )  # fmt: skip
            with progress_share(TRAINED_SHARE, 1.0):
                unit_progress(k + 1, runs)
        summary = write_summary(
            stage, env_id=env_id, algo=algo, results=results, expert=found["expert"],
            drawn=drawn_baselines(core, data) if data.discrete else None,
        )  # fmt: skip
    return GymIRLResult(out=out, runs=runs, summary=summary, baselines=found)
