"""Lock-step PPO against SB3 2.9's PPO (issue 19): same update, per-run independence, learning."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.logger import Logger

from pokerirl.gym.lockstep import LockstepPPO
from pokerirl.gym.lockstep.ppo import gae
from pokerirl.gym.presets import TASKS, PPOSettings

ACROBOT = dataclasses.replace(TASKS["Acrobot-v1"].rl.ppo, n_epochs=3)  # type: ignore[arg-type]
PENDULUM = PPOSettings(n_steps=128, batch_size=32, gamma=0.9, gae_lambda=0.95, clip_range=0.2,
                       ent_coef=0.01, vf_coef=0.5, max_grad_norm=0.5, learning_rate=1e-3,
                       n_epochs=2, net_arch=(32, 32), activation="leaky_relu",
                       log_std_init=-1.0, ortho_init=False)


def _sb3(env_id: str, s: PPOSettings, seed: int = 0) -> PPO:
    hidden = list(s.net_arch or (64, 64))
    act = torch.nn.Tanh if s.activation == "tanh" else torch.nn.LeakyReLU
    model = PPO("MlpPolicy", env_id, n_steps=s.n_steps, batch_size=s.batch_size, gamma=s.gamma,
                gae_lambda=s.gae_lambda, clip_range=s.clip_range, ent_coef=s.ent_coef,
                vf_coef=s.vf_coef, max_grad_norm=s.max_grad_norm, learning_rate=s.learning_rate,
                n_epochs=s.n_epochs, seed=seed, device="cpu",
                policy_kwargs={"net_arch": {"pi": hidden, "vf": hidden}, "activation_fn": act,
                               "log_std_init": s.log_std_init, "ortho_init": s.ortho_init})
    model.set_logger(Logger(folder=None, output_formats=[]))
    return model


@pytest.mark.parametrize(("env_id", "settings"), [("Acrobot-v1", ACROBOT),
                                                  ("Pendulum-v1", PENDULUM)])
def test_first_update_matches_sb3(env_id: str, settings: PPOSettings) -> None:
    """Same initial weights, same batch, same minibatch order: same losses and parameters."""
    model = _sb3(env_id, settings)
    ours = LockstepPPO(env_id, settings, seeds=[0], weights=[model.policy.state_dict()])
    batch = ours.collect()
    T = settings.n_steps
    buf: RolloutBuffer = model.rollout_buffer
    buf.reset()
    buf.observations[:] = batch["obs"][0].numpy().reshape(buf.observations.shape)
    buf.actions[:] = batch["actions"][0].numpy().reshape(buf.actions.shape)
    for key in ("values", "log_prob", "advantages", "returns"):
        name = {"log_prob": "log_probs"}.get(key, key)
        getattr(buf, name)[:] = batch[key][0].numpy().reshape(T, 1)
    buf.pos, buf.full = T, True
    np.random.seed(123)
    perms = [[np.random.permutation(T)] for _ in range(settings.n_epochs)]
    np.random.seed(123)
    model.train()
    losses = ours.train(batch, permutations=perms)
    assert losses["loss"][0] == pytest.approx(model.logger.name_to_value["train/loss"], abs=1e-5)
    theirs = model.policy.state_dict()
    for key, value in ours.policy.run_state_dict(0).items():
        torch.testing.assert_close(value, theirs[key], atol=1e-5, rtol=0, msg=key)


def test_gae_matches_sb3_buffer() -> None:
    rng = np.random.default_rng(0)
    T, n = 50, 3
    rewards, values = rng.normal(size=(T, n)).astype(np.float32), rng.normal(size=(T, n))
    starts = (rng.random((T, n)) < 0.1).astype(np.float32)
    last, dones = rng.normal(size=n).astype(np.float32), rng.random(n) < 0.5
    import gymnasium as gym

    buf = RolloutBuffer(T, gym.spaces.Box(-1, 1, (1,)), gym.spaces.Discrete(2), n_envs=n,
                        gamma=0.9, gae_lambda=0.8)
    buf.rewards[:], buf.values[:], buf.episode_starts[:] = rewards, values, starts
    buf.compute_returns_and_advantage(torch.from_numpy(last), dones)
    ours = gae(rewards, values.astype(np.float32), starts, last, dones, 0.9, 0.8)
    np.testing.assert_allclose(ours, buf.advantages, atol=1e-5)


def test_run_of_group_equals_group_of_one() -> None:
    s = dataclasses.replace(ACROBOT, n_steps=256, n_epochs=2)
    group = LockstepPPO("Acrobot-v1", s, seeds=[0, 1, 2]).learn(512)
    alone = LockstepPPO("Acrobot-v1", s, seeds=[2]).learn(512)
    for key, value in alone.state_dicts[0].items():
        torch.testing.assert_close(group.state_dicts[2][key], value, atol=1e-5, rtol=0)
    assert group.episode_returns[2] == alone.episode_returns[0]
    key = "action_net.weight"  # seeds do differ
    assert not torch.allclose(group.state_dicts[0][key], group.state_dicts[2][key])


@pytest.mark.parametrize(("env_id", "settings"), [("Acrobot-v1", ACROBOT),
                                                  ("Pendulum-v1", PENDULUM)])
def test_state_dict_loads_into_sb3(env_id: str, settings: PPOSettings) -> None:
    result = LockstepPPO(env_id, settings, seeds=[4, 5]).learn(settings.n_steps)
    model = _sb3(env_id, settings, seed=9)
    model.policy.load_state_dict(result.state_dicts[1], strict=True)
    obs = np.stack([model.observation_space.sample() for _ in range(32)]).astype(np.float32)
    ours = LockstepPPO(env_id, settings, seeds=[0], weights=[result.state_dicts[1]])
    with torch.no_grad():
        head, values = ours.policy(torch.from_numpy(obs)[None])
        sb3_values = model.policy.predict_values(torch.from_numpy(obs)).squeeze(-1)
    sb3_actions, _ = model.predict(obs, deterministic=True)
    expected = head[0].argmax(-1).numpy() if ours.discrete else np.clip(
        head[0].numpy(), ours.low, ours.high)
    np.testing.assert_allclose(sb3_actions, expected, atol=1e-5)
    torch.testing.assert_close(values[0], sb3_values, atol=1e-5, rtol=0)


@pytest.mark.slow
def test_learns_cartpole() -> None:
    """A tiny budget lifts CartPole well above random (about 22)."""
    s = PPOSettings(n_steps=512, batch_size=64, gamma=0.99, gae_lambda=0.95, clip_range=0.2,
                    ent_coef=0.0, vf_coef=0.5, max_grad_norm=0.5, learning_rate=1e-3, n_epochs=10)
    result = LockstepPPO("CartPole-v1", s, seeds=[0, 1]).learn(15_000)
    for returns in result.episode_returns:
        assert np.mean(returns[-10:]) > 100, returns[-10:]
