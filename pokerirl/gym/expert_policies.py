"""SB3 experts for the paper's tasks: train, save policy-only, load without unpickling.

An expert folder follows the project's run-folder convention:

- ``model.pt``: the SB3 policy's ``state_dict`` (PPO's ``ActorCriticPolicy`` or DQN's
  ``DQNPolicy``), saved with :func:`pokerirl.atomic.write_torch` and loaded with
  ``torch.load(weights_only=True)``; nothing is ever unpickled;
- ``config.json``: the env, the algorithm, the policy's architecture (to rebuild the SB3 policy
  class), the settings and budget it was trained with, and its final evaluation;
- ``metrics.jsonl``: the periodic deterministic evaluations during training.

The best checkpoint by periodic evaluation is kept (as SB3's ``EvalCallback`` does), then
evaluated afresh over ``final_episodes`` episodes on other seeds for the reported return.
"""

from __future__ import annotations

import json
import os
import pickle
import warnings
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from pokerirl.atomic import write_text, write_torch
from pokerirl.errors import ConfigError, InputError, check_argument
from pokerirl.gym.envs import make_env, require_gym
from pokerirl.gym.episodes import sb3_evaluation
from pokerirl.gym.manifest import CONFIG_FILE, METRICS_FILE, MODEL_FILE, shipped_dir
from pokerirl.gym.presets import PPOSettings, RLSettings
from pokerirl.gym.tasks import task
from pokerirl.jsonio import read_json
from pokerirl.serial import Serializable

if TYPE_CHECKING:  # gymnasium and SB3 are imported lazily: a poker-only user never pays.
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.policies import BasePolicy

# Seeds of the final evaluation episodes start here, away from training and periodic-eval seeds.
FINAL_EVAL_SEED = 1_000_000


@dataclass(frozen=True, kw_only=True)
class Expert:
    """A loaded expert: its SB3 policy (eval mode, CPU) and its config record, as read (an
    expert folder needs only ``env``, ``algo`` and ``policy_kwargs`` to load; one written by
    :func:`train_expert_record` reads as an :class:`ExpertRecord`)."""

    env_id: str
    algo: str
    policy: BasePolicy
    record: Mapping[str, Any]

    def act(self, obs: np.ndarray, *, deterministic: bool = True) -> np.ndarray:
        """Actions for a batch of observations ``(n, obs_dim)``."""
        actions, _ = self.policy.predict(obs, deterministic=deterministic)
        return actions


@dataclass(frozen=True, kw_only=True)
class ExpertEvaluation(Serializable):
    """How an expert was chosen and scored: the periodic evaluations during training (the
    best state is kept), then deterministic episodes on fresh seeds."""

    periodic_every: int
    periodic_episodes: int
    best_periodic_return: float
    final_seed: int
    deterministic: bool
    returns: tuple[float, ...]


@dataclass(frozen=True, kw_only=True)
class ExpertRecord(Serializable):
    """An expert folder's ``config.json``, as :func:`train_expert_record` writes it."""

    env: str
    algo: str
    return_mean: float
    return_std: float
    episodes: int
    seed: int
    timesteps: int
    target: float | None  # the authors' expert return (None: a generic task)
    hyper: str
    settings: Mapping[str, Any]
    policy_kwargs: Mapping[str, Any]
    evaluation: ExpertEvaluation
    versions: Mapping[str, str | None]


# --------------------------------------------------------------------------- architecture


def policy_kwargs(settings: RLSettings) -> dict[str, object]:
    """The JSON form of the SB3 ``policy_kwargs`` for these settings (see :func:`_sb3_kwargs`)."""
    if settings.dqn is not None:
        return {"net_arch": list(settings.dqn.net_arch)}
    ppo = settings.ppo
    assert ppo is not None
    if ppo.net_arch is None:
        return {}  # SB3's default MlpPolicy
    return {
        "net_arch": {"pi": list(ppo.net_arch), "vf": list(ppo.net_arch)},
        "activation_fn": ppo.activation,
        "log_std_init": ppo.log_std_init,
        "ortho_init": ppo.ortho_init,
    }


def _sb3_kwargs(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    activations = {"tanh": torch.nn.Tanh, "leaky_relu": torch.nn.LeakyReLU, "relu": torch.nn.ReLU}
    out = dict(kwargs)
    if "activation_fn" in out:
        out["activation_fn"] = activations[out["activation_fn"]]
    return out


def build_policy(env_id: str, algo: str, kwargs: Mapping[str, Any]) -> BasePolicy:
    """A fresh SB3 policy of the class ``algo`` trains, for ``env_id``'s spaces."""
    env = make_env(env_id)
    try:
        spaces = (env.observation_space, env.action_space)
    finally:
        env.close()
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.dqn.policies import DQNPolicy

    classes: dict[str, type[BasePolicy]] = {"dqn": DQNPolicy, "ppo": ActorCriticPolicy}
    if algo not in classes:
        raise InputError(f"unknown expert algorithm {algo!r} (ppo or dqn)")
    policy: BasePolicy = classes[algo](*spaces, lr_schedule=lambda _: 0.0, **_sb3_kwargs(kwargs))
    return policy


def make_model(env_id: str, settings: RLSettings, *, seed: int, env: Any = None) -> BaseAlgorithm:
    """An SB3 PPO or DQN model with ``settings`` on ``env`` (default: a Monitor-wrapped env)."""
    require_gym()
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.monitor import Monitor

    env = env if env is not None else Monitor(make_env(env_id))
    kwargs = _sb3_kwargs(policy_kwargs(settings))
    model: BaseAlgorithm
    if settings.dqn is not None:
        d = asdict(settings.dqn)
        d.pop("net_arch")
        model = DQN("MlpPolicy", env, seed=seed, policy_kwargs=kwargs, device="cpu", **d)
    else:
        assert settings.ppo is not None  # RLSettings holds exactly its algorithm's settings
        ppo = asdict(settings.ppo)
        for key in ("net_arch", "activation", "log_std_init", "ortho_init"):
            ppo.pop(key)
        model = PPO("MlpPolicy", env, seed=seed, policy_kwargs=kwargs, device="cpu", **ppo)
    # SB3's default logger makes an empty /tmp/SB3-<date> folder per learn() call.
    model.set_logger(Logger(folder=None, output_formats=[]))
    return model


# --------------------------------------------------------------------------- training


def expert_settings(env_id: str, *, hyper: str = "paper") -> RLSettings:
    """The settings an expert trains with: the authors' (``paper``; for a task the paper lacks,
    its generic settings, :func:`pokerirl.gym.presets.generic_task`) or a named alternative.

    ``zoo`` uses rl-zoo's tuned PPO settings (see :data:`ZOO_PPO`), for a retry where the
    authors' miss the target; MountainCar's DQN is rl-zoo's either way.
    """
    settings = task(env_id).rl  # the paper's, or a generic task's; refuses an unknown id
    if hyper == "paper":
        return settings
    if hyper == "zoo":
        if env_id not in ZOO_PPO:
            raise ConfigError(f"no rl-zoo settings recorded for {env_id} (only the paper's)")
        return replace(settings, ppo=ZOO_PPO[env_id])
    raise ConfigError(f"unknown hyper-parameter set {hyper!r} (paper or zoo)")


# rl-zoo (rl-baselines3-zoo, hyperparams/ppo.yml) settings for a retry where the authors'
# settings miss the target with one environment (n_envs=1 here; rl-zoo's n_envs differ).
ZOO_PPO: dict[str, PPOSettings] = {
    "Pendulum-v1": PPOSettings(
        n_steps=1024,
        batch_size=64,
        gamma=0.9,
        gae_lambda=0.95,
        clip_range=0.2,
        ent_coef=0.0,
        vf_coef=0.5,
        max_grad_norm=0.5,
        learning_rate=1e-3,
        n_epochs=10,
    ),
}


def train_expert_record(
    out: str | os.PathLike[str],
    env_id: str,
    *,
    seed: int = 0,
    timesteps: int | None = None,
    hyper: str = "paper",
    eval_every: int | None = None,
    eval_episodes: int = 5,
    final_episodes: int = 20,
) -> ExpertRecord:
    """Train an SB3 expert for ``env_id`` into ``out``; return its config record.

    Every ``eval_every`` steps (default: a twentieth of the budget) the policy plays
    ``eval_episodes`` deterministic episodes; the best state is kept and finally evaluated over
    ``final_episodes`` episodes on fresh seeds.
    """
    require_gym()
    from stable_baselines3.common.callbacks import BaseCallback

    settings = expert_settings(env_id, hyper=hyper)
    timesteps = timesteps or settings.timesteps
    if timesteps < 1 or eval_episodes < 1 or final_episodes < 1:
        raise ConfigError("timesteps, eval_episodes and final_episodes must be positive")
    every: int = eval_every or max(timesteps // 20, 1)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    model = make_model(env_id, settings, seed=seed)
    history: list[dict[str, float]] = []
    best: dict[str, torch.Tensor] = {}

    def evaluate_and_keep() -> None:
        # The same episode seeds every time, so checkpoints are compared on the same starts.
        result = sb3_evaluation(model.policy, env_id, episodes=eval_episodes, seed=seed + 10_000)
        if not history or result.mean > max(h["return_mean"] for h in history):
            best.clear()
            best.update({k: v.detach().clone() for k, v in model.policy.state_dict().items()})
        history.append(
            {"timesteps": model.num_timesteps, "return_mean": result.mean, "return_std": result.std}
        )

    class PeriodicEvaluation(BaseCallback):  # one env: num_timesteps counts single steps
        def _on_step(self) -> bool:
            if self.num_timesteps % every == 0:
                evaluate_and_keep()
            return True

    model.learn(total_timesteps=timesteps, callback=PeriodicEvaluation())
    if not history or history[-1]["timesteps"] != model.num_timesteps:
        evaluate_and_keep()  # the final state competes too
    model.policy.load_state_dict(best)
    model.policy.set_training_mode(False)
    final = sb3_evaluation(model.policy, env_id, episodes=final_episodes, seed=FINAL_EVAL_SEED)

    record = ExpertRecord(
        env=env_id,
        algo=settings.algo,
        return_mean=final.mean,
        return_std=final.std,
        episodes=final_episodes,
        seed=seed,
        timesteps=timesteps,
        target=task(env_id).expert_target,
        hyper=hyper,
        settings=asdict(settings.own),
        policy_kwargs=policy_kwargs(settings),
        evaluation=ExpertEvaluation(
            periodic_every=every,
            periodic_episodes=eval_episodes,
            best_periodic_return=max(h["return_mean"] for h in history),
            final_seed=FINAL_EVAL_SEED,
            deterministic=True,
            returns=final.returns,
        ),
        versions=gym_versions(),
    )
    write_text(out / METRICS_FILE, "".join(json.dumps(h) + "\n" for h in history))
    write_torch(out / MODEL_FILE, best)
    write_text(out / CONFIG_FILE, json.dumps(record.to_json(), indent=2) + "\n")
    return record


def gym_versions() -> dict[str, str | None]:
    from importlib import metadata

    from pokerirl.versions import package_versions

    versions = package_versions()
    for package in ("gymnasium", "stable-baselines3", "mujoco"):
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = None
    return versions


# --------------------------------------------------------------------------- loading


def resolve_expert_dir(expert: str | os.PathLike[str], env_id: str) -> Path:
    """``shipped`` means the shipped expert for ``env_id``; anything else is a folder."""
    if str(expert) == "shipped":
        folder = shipped_dir() / env_id
        if not (folder / CONFIG_FILE).is_file():
            raise ConfigError(
                f"no shipped expert for {env_id!r} (only the paper's tasks ship one): train one "
                f"with `pokerirl gym expert {env_id}` and give its folder"
            )
        return folder
    return Path(expert)


EXPERT_KEYS = ("env", "algo", "policy_kwargs")


def read_expert_record(folder: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``config.json`` of the expert folder ``folder``, checked to be an expert's (a poker
    agent's folder also holds a config.json): InputError naming the file otherwise."""
    path = Path(folder) / CONFIG_FILE
    if not path.is_file():
        raise InputError(f"{folder}: not an expert folder ({CONFIG_FILE} missing)")
    record = read_json(path)
    missing = [key for key in EXPERT_KEYS if not isinstance(record, dict) or key not in record]
    if missing:
        raise InputError(
            f"{path}: not a gym expert's config (no {missing[0]!r}; `gym expert` writes one)"
        )
    return record


def load_expert(folder: str | os.PathLike[str]) -> Expert:
    """The expert saved in ``folder``, rebuilt from its JSON architecture and weights only.

    Raises:
        ValueError: one line, if the folder is not an expert folder or its files are bad.
    """
    check_argument("folder", folder, (str, os.PathLike), "an expert folder (a path)")
    folder = Path(folder)
    try:
        record = read_expert_record(folder)
        policy = build_policy(record["env"], record["algo"], record["policy_kwargs"])
        with warnings.catch_warnings():  # torch warns about a pickle it then refuses
            warnings.simplefilter("ignore")
            state = torch.load(folder / MODEL_FILE, weights_only=True, map_location="cpu")
        policy.load_state_dict(state)
    except FileNotFoundError as error:
        raise InputError(
            f"{folder}: not an expert folder ({Path(error.filename).name} missing)"
        ) from None
    except pickle.UnpicklingError as error:
        pickled = (folder / MODEL_FILE).read_bytes()[:1] == b"\x80"  # a pickle's opcode
        refused = "GLOBAL" in str(error) or "Unsupported global" in str(error)
        if not pickled and not refused:
            raise InputError(f"{folder}: bad expert files: {str(error).splitlines()[0]}") from None
        # weights_only refused a pickled object: nothing was executed; torch's advice is
        # several lines about unpickling, which we refuse to do.
        raise InputError(
            f"{folder / MODEL_FILE}: not a state_dict (refusing to unpickle)"
        ) from None
    except (
        json.JSONDecodeError,
        KeyError,
        RuntimeError,
        TypeError,
    ) as error:
        raise InputError(f"{folder}: bad expert files: {str(error).splitlines()[0]}") from None
    policy.set_training_mode(False)
    return Expert(env_id=record["env"], algo=record["algo"], policy=policy, record=record)
