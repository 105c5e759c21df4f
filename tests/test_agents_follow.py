"""The follow metric: the share of a DQN's decisions that take its reward's best action."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pokerirl.agents.config import DQNConfig, TrainConfig
from pokerirl.agents.train import read_metrics, train_agent
from pokerirl.poker.rewards import ObsReward


def _prefers_raising(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
    return (np.asarray(actions) == 1).astype(np.float32)


def _train(out: Path, payoff_weight: float) -> float:
    run = out.parent / "run"  # a reward given in process is only named and hashed by its run
    run.mkdir(exist_ok=True)
    for name, data in (("reward.pt", b"weights"), ("config.json", b"{}")):
        (run / name).write_bytes(data)
    config = TrainConfig(
        hands=3_000, seed=0, eval_every=3_000, eval_hands=400, reward="learned",
        reward_run=str(run), payoff_weight=payoff_weight,
        dqn=DQNConfig(concurrent_hands=128, epsilon_decay_steps=2_000, learning_rate=1e-3),
    )  # fmt: skip
    reward = ObsReward(_prefers_raising, name="prefers-raise", fingerprint="sha256:test")
    line = train_agent(out, config, reward_fn=reward)
    assert line is not None and line.follows_reward is not None
    # Written where a study reads it: the folder's metrics and its config's final line.
    assert read_metrics(out)[-1].follows_reward == line.follows_reward
    assert json.loads((out / "config.json").read_text())["final"]["follows_reward"] == (
        line.follows_reward
    )
    return line.follows_reward


def test_a_dqn_that_learns_its_reward_follows_it_and_one_that_ignores_it_does_not(
    tmp_path: Path,
) -> None:
    follows = _train(tmp_path / "follows", payoff_weight=0.0)
    # Weight 1: the DQN learns the payoff alone, the reward is ignored.
    ignores = _train(tmp_path / "ignores", payoff_weight=1.0)
    assert follows > 0.9, follows
    assert ignores < follows - 0.3, (ignores, follows)


def test_a_sparse_agent_has_no_follow_metric(tmp_path: Path) -> None:
    config = TrainConfig(hands=256, seed=0, eval_every=256, eval_hands=100,
                         dqn=DQNConfig(concurrent_hands=128))  # fmt: skip
    line = train_agent(tmp_path / "sparse", config)
    assert line is not None and line.follows_reward is None
    assert "follows_reward" not in (tmp_path / "sparse" / "metrics.jsonl").read_text()
