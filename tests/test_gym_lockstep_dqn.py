"""Lock-step DQN against SB3 2.9's DQN (issue 19): same update, schedule, streams; learning."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import stable_baselines3.dqn.dqn as sb3_dqn
import torch
from stable_baselines3 import DQN
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.utils import polyak_update

from pokerirl.gym.expert_policies import make_model
from pokerirl.gym.lockstep.dqn import LockstepDQN, exploration_rate
from pokerirl.gym.presets import TASKS, DQNSettings, RLSettings

_PRESET = TASKS["MountainCar-v0"].rl.dqn
assert _PRESET is not None
MOUNTAIN: DQNSettings = _PRESET
CARTPOLE = dataclasses.replace(DQNSettings(), learning_rate=2.3e-3, batch_size=64,
                               buffer_size=20_000, learning_starts=1000, gamma=0.99,
                               target_update_interval=10, train_freq=256, gradient_steps=128,
                               exploration_fraction=0.16, exploration_final_eps=0.04,
                               net_arch=(64, 64))  # rl-zoo's CartPole DQN, smaller net


def _sb3(env_id: str, s: DQNSettings, seed: int) -> DQN:
    model = make_model(env_id, RLSettings(algo="dqn", timesteps=1, dqn=s), seed=seed)
    assert isinstance(model, DQN)
    return model


def _assert_params(ours: dict[str, torch.Tensor], theirs: dict[str, torch.Tensor],
                   atol: float) -> None:
    assert ours.keys() == theirs.keys()
    for key, value in ours.items():
        torch.testing.assert_close(value, theirs[key], atol=atol, rtol=0, msg=key)


def _assert_same_buffer(ours: LockstepDQN, model: DQN, n: int) -> None:
    rb = model.replay_buffer
    assert rb is not None
    np.testing.assert_array_equal(ours.buf_obs[0, :n], rb.observations[:n, 0])
    np.testing.assert_array_equal(ours.buf_next_obs[0, :n], rb.next_observations[:n, 0])
    np.testing.assert_array_equal(ours.buf_actions[0, :n], rb.actions[:n, 0, 0])
    np.testing.assert_array_equal(ours.buf_rewards[0, :n], rb.rewards[:n, 0])
    np.testing.assert_array_equal(ours.buf_dones[0, :n],
                                  rb.dones[:n, 0] * (1 - rb.timeouts[:n, 0]))


@pytest.mark.parametrize(("env_id", "settings"), [("MountainCar-v0", MOUNTAIN),
                                                  ("CartPole-v1", CARTPOLE)])
def test_first_update_matches_sb3(env_id: str, settings: DQNSettings) -> None:
    """Same weights, same buffer, same minibatch rows: same losses, parameters and targets."""
    # No training while the buffers fill: MountainCar 400 steps (two truncated episodes),
    # CartPole 512 (two rollouts of 256, many terminations).
    s = dataclasses.replace(settings, learning_starts=10_000)
    model = _sb3(env_id, s, seed=0)
    ours = LockstepDQN(env_id, s, seeds=[0], weights=[model.policy.state_dict()])
    model.learn(400)
    n = ours.learn(400).timesteps
    assert n == model.num_timesteps == (400 if env_id == "MountainCar-v0" else 512)
    _assert_same_buffer(ours, model, n)  # the warm-up phase's streams are SB3's
    assert ours.buf_dones[0, :n].any() == (env_id == "CartPole-v1")
    for step, seed in enumerate((123, 124)):
        if step == 1:  # a target update between the two steps: the second loss uses it
            polyak_update(model.q_net.parameters(), model.q_net_target.parameters(), 1.0)
            ours.update_target()
        np.random.seed(seed)
        idx = np.random.randint(0, n, size=s.batch_size)
        np.random.seed(seed)  # SB3's ReplayBuffer.sample draws the same rows
        model.train(gradient_steps=1, batch_size=s.batch_size)
        losses = ours.train(1, indices=idx[None, None])
        assert losses[0, 0] == pytest.approx(model.logger.name_to_value["train/loss"], abs=1e-5)
        _assert_params(ours.run_state_dict(0), model.policy.state_dict(), atol=1e-5)


def test_exploration_and_target_updates_match_sb3(monkeypatch: pytest.MonkeyPatch) -> None:
    s = dataclasses.replace(MOUNTAIN, learning_starts=300, target_update_interval=250,
                            gradient_steps=1, exploration_fraction=0.3, net_arch=(16, 16))
    total = 2010  # not a multiple of train_freq: both round up to 2016
    model = _sb3("MountainCar-v0", s, seed=0)
    updates: list[int] = []
    original = sb3_dqn.polyak_update

    def recording_update(params, target_params, tau):
        if not updates or updates[-1] != model.num_timesteps:  # params and batch-norm stats
            updates.append(model.num_timesteps)
        original(params, target_params, tau)

    monkeypatch.setattr(sb3_dqn, "polyak_update", recording_update)

    class Record(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.seen: list[tuple[int, float]] = []

        def _on_step(self) -> bool:
            self.seen.append((model.num_timesteps, model.exploration_rate))
            return True

    record = Record()
    model.learn(total, callback=record)
    ours = LockstepDQN("MountainCar-v0", s, seeds=[0])
    seen: list[tuple[int, float]] = []
    result = ours.learn(total, callback=lambda t: seen.append((t, ours.exploration)))
    assert seen == record.seen  # the callback's steps, and epsilon as SB3 holds it there
    assert result.timesteps == model.num_timesteps == 2016
    assert ours.target_update_steps == updates == list(range(250, 2016, 250))
    assert ours.n_updates == model._n_updates == (2016 - 304) // 16 + 1
    assert model.exploration_rate == ours.exploration == s.exploration_final_eps
    # the schedule by hand: 1.0 at the start, halfway at 15% of the budget, final after 30%
    assert exploration_rate(s, 1.0) == 1.0
    assert exploration_rate(s, 0.85) == pytest.approx((1.0 + 0.07) / 2)
    assert exploration_rate(s, 0.69) == 0.07


def test_trajectory_matches_sb3_same_seed() -> None:
    """Seed s draws SB3's random numbers: the same transitions, weights up to rounding."""
    s = dataclasses.replace(MOUNTAIN, learning_starts=500)
    n = 660  # 10 train calls of 8 gradient steps, one target update, greedy and random actions
    model = _sb3("MountainCar-v0", s, seed=3)
    model.learn(n)
    ours = LockstepDQN("MountainCar-v0", s, seeds=[3])
    result = ours.learn(n)
    _assert_same_buffer(ours, model, result.timesteps)
    _assert_params(result.state_dicts[0], model.policy.state_dict(), atol=1e-4)


@pytest.mark.slow
def test_run_of_group_equals_group_of_one() -> None:
    s = dataclasses.replace(MOUNTAIN, learning_starts=500)

    def shaped(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        return obs[:, 0] + 0.1 * actions

    group = LockstepDQN("MountainCar-v0", s, seeds=[0, 1, 2], rewards=[None, shaped, None])
    result = group.learn(2000)
    for seed, reward in ((1, shaped), (2, None)):
        alone = LockstepDQN("MountainCar-v0", s, seeds=[seed], rewards=[reward]).learn(2000)
        _assert_params(result.state_dicts[seed], alone.state_dicts[0], atol=1e-5)
        assert result.episode_returns[seed] == alone.episode_returns[0]
    n = result.timesteps
    np.testing.assert_allclose(group.buf_rewards[1, :n], shaped(group.buf_obs[1, :n],
                                                                group.buf_actions[1, :n]),
                               rtol=1e-6)
    assert (group.buf_rewards[2, :n] == -1).all()
    assert result.episode_returns[1] == (-200.0,) * 10  # env returns, not the shaped reward
    key = "q_net.q_net.4.weight"  # seeds do differ
    assert not torch.allclose(result.state_dicts[0][key], result.state_dicts[2][key])


def test_state_dict_loads_into_sb3() -> None:
    s = dataclasses.replace(MOUNTAIN, learning_starts=200, target_update_interval=100)
    group = LockstepDQN("MountainCar-v0", s, seeds=[4, 5])
    result = group.learn(400)
    model = _sb3("MountainCar-v0", s, seed=9)
    model.policy.load_state_dict(result.state_dicts[1], strict=True)
    rng = np.random.default_rng(0)
    obs = rng.uniform([-1.2, -0.07], [0.6, 0.07], size=(2, 64, 2)).astype(np.float32)
    sb3_actions, _ = model.predict(obs[1], deterministic=True)
    np.testing.assert_array_equal(group.predict(obs)[1], sb3_actions)
    with torch.no_grad():
        sb3_q = model.q_net(torch.from_numpy(obs[1]))
    torch.testing.assert_close(group.q_values(obs)[1], sb3_q, atol=1e-5, rtol=0)
    with pytest.raises(ValueError, match="predict: obs shape"):
        group.predict(obs[0])


@pytest.mark.slow
def test_learns_cartpole() -> None:
    """12k steps lift CartPole well above random (about 22)."""
    result = LockstepDQN("CartPole-v1", CARTPOLE, seeds=[0, 1]).learn(12_000)
    for returns in result.episode_returns:
        assert np.mean(returns[-10:]) > 50, returns[-10:]


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="Discrete actions"):
        LockstepDQN("Pendulum-v1", MOUNTAIN, seeds=[0])
    with pytest.raises(ValueError, match="rewards: 1 for 2 runs"):
        LockstepDQN("CartPole-v1", MOUNTAIN, seeds=[0, 1], rewards=[None])
    with pytest.raises(ValueError, match=r"missing q_net.q_net.0.bias, q_net.q_net.2.weight"):
        LockstepDQN("CartPole-v1", dataclasses.replace(MOUNTAIN, net_arch=(8,)), seeds=[0],
                    weights=[{"q_net.q_net.0.weight": torch.zeros(8, 4)}])
