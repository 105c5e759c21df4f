"""The RL phase's reward wrapper on real environments, and an RL run on a learned reward."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

from pokerirl.gym.envs import make_env
from pokerirl.gym.rewards import ENV_REWARD_KEY, learned_reward_env, module_reward
from pokerirl.gym.rl import train_rl

torch.set_num_threads(1)


def test_reward_sees_the_state_the_action_was_taken_in_across_auto_resets() -> None:
    # MountainCar's physics give the pre-step position independently of the wrapper:
    # position_before = position_after - velocity_after (away from the left wall). With
    # f(s, a) = position(s) + 10 a, each reward must be that position plus 10 a, also on the
    # first step of each new episode after SB3's auto-reset.
    calls: list[int] = []

    def f(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        calls.append(len(obs))
        return obs[:, 0] + 10.0 * actions

    venv = DummyVecEnv([lambda: Monitor(make_env("MountainCar-v0")) for _ in range(3)])
    venv.seed(4)
    env = learned_reward_env(venv, f)
    env.reset()
    rng = np.random.default_rng(0)
    checked, episodes, restarts = 0, [], 0
    for _ in range(450):  # 200-step episodes: every env auto-resets twice
        actions = rng.integers(0, 3, size=3)
        obs, rewards, dones, infos = env.step(actions)
        assert rewards.dtype == np.float32
        for i in range(3):
            after = infos[i]["terminal_observation"] if dones[i] else obs[i]
            assert infos[i][ENV_REWARD_KEY] == -1.0
            if after[0] > -1.2 + 1e-6:
                before = np.float32(after[0] - after[1])
                assert rewards[i] == pytest.approx(before + 10.0 * actions[i], abs=1e-5)
                checked += 1
            restarts += dones[i]
            if "episode" in infos[i]:  # Monitor still reports the true env return
                episodes.append(infos[i]["episode"]["r"])
    assert calls == [3] * 450  # one batched call per vector step
    assert checked > 1200 and restarts == 6
    assert episodes == [-200.0] * 6


def test_a_wrong_reward_shape_is_refused() -> None:
    venv = DummyVecEnv([lambda: Monitor(make_env("Acrobot-v1")) for _ in range(2)])
    env = learned_reward_env(venv, lambda obs, actions: np.zeros((len(obs), 1)))
    env.reset()
    with pytest.raises(ValueError, match="shape"):
        env.step(np.array([0, 1]))


@pytest.mark.slow
def test_rl_on_a_learned_reward_records_the_true_return(tmp_path: Path) -> None:
    # A small MLP reward (as the IRL phase learns) drives PPO on Pendulum's continuous actions;
    # the curve and the training episodes are measured with the env's own reward.
    torch.manual_seed(0)
    net = torch.nn.Sequential(torch.nn.Linear(4, 16), torch.nn.ReLU(), torch.nn.Linear(16, 1))
    seen: list[np.ndarray] = []

    def reward(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        seen.append(actions)
        return module_reward(net, num_actions=None)(obs, actions)

    result = train_rl(
        "Pendulum-v1", reward=reward, reward_name="mlp", seed=1, timesteps=512,
        evaluations=2, eval_episodes=1, out=tmp_path / "run",
    )  # fmt: skip
    assert [p.timesteps for p in result.curve] == [256, 512]
    assert all(-2000 < p.return_mean < 0 for p in result.curve)  # Pendulum's true scale
    assert len(result.train_episode_returns) == 2 and all(
        r < 0 for r in result.train_episode_returns
    )
    # One call to check that the reward fits the env, then one per step.
    assert len(seen) == 1 + 512 and all(a.shape == (1, 1) and np.abs(a).max() <= 2 for a in seen)
    record = json.loads((tmp_path / "run" / "config.json").read_text())
    assert record["final_return"] == result.final_return and record["reward"] == "mlp"
    metrics = (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(m)["timesteps"] for m in metrics] == [256, 512]


@pytest.mark.slow
def test_rl_command_trains_on_the_env_reward_and_refuses_a_reward_that_does_not_fit(
    tmp_path: Path,
) -> None:
    from typer.testing import CliRunner

    from pokerirl.cli import app

    args = ["gym", "rl", "MountainCar-v0", "--out", str(tmp_path / "env")]
    small = ["--runs", "2", "--timesteps", "1100", "--evaluations", "1", "--eval-episodes", "1"]
    result = CliRunner().invoke(app, [*args, "--env-reward", *small])
    assert result.exit_code == 0, result.output
    assert "final true return -200.0 +- 0.0 over 2 runs" in result.output
    for k in range(2):
        record = json.loads((tmp_path / "env" / f"run-{k}" / "config.json").read_text())
        assert (record["algo"], record["reward"], record["seed"]) == ("dqn", "env", k)
    assert CliRunner().invoke(app, [*args, *small]).exit_code != 0  # neither reward given

    def poker_reward(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        if obs.shape[1] != 72:
            raise ValueError(f"obs must be (B, 72), got {obs.shape}")
        return np.zeros(len(obs))

    with pytest.raises(ValueError, match="does not fit MountainCar-v0: obs must be"):
        train_rl("MountainCar-v0", reward=poker_reward, reward_name="poker", seed=0, timesteps=10)


def test_rl_training_leaves_no_logger_folders_in_the_temp_dir(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.delenv("SB3_LOGDIR", raising=False)
    train_rl("Acrobot-v1", reward=None, reward_name="env", seed=0, timesteps=64, eval_episodes=1,
             evaluations=1)  # fmt: skip
    assert not list(tmp_path.glob("SB3-*"))
