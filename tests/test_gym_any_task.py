"""Any registered Gymnasium task (issue 34): generic settings from the action space, the
paper's six unchanged, one line for an id the toolkit cannot take, and CartPole end to end."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.cli import app
from pokerirl.errors import ConfigError
from pokerirl.gym.presets import GENERIC_PPO, PRESETS, TASKS
from pokerirl.gym.tasks import task


def invoke(*args: str):
    return CliRunner().invoke(app, list(args))


def test_a_task_the_paper_lacks_gets_generic_settings_by_its_action_space() -> None:
    for env_id, paper in TASKS.items():
        assert task(env_id) is paper  # the six keep their presets exactly
    cartpole, car = task("CartPole-v1"), task("MountainCarContinuous-v0")
    assert cartpole.generic and car.generic and not TASKS["Acrobot-v1"].generic
    assert cartpole.discrete and not car.discrete
    assert cartpole.irl.policy_hidden == (64,) and car.irl.policy_hidden == (64, 64)
    assert cartpole.rl.ppo == car.rl.ppo == GENERIC_PPO
    assert cartpole.expert_target is None and cartpole.paper is None
    # The study presets' budget overrides apply to it as to the paper's tasks.
    assert PRESETS["quick"].irl("CartPole-v1").transitions == PRESETS["quick"].transitions
    assert PRESETS["paper"].irl("CartPole-v1") == cartpole.irl


def test_an_id_the_toolkit_cannot_take_is_one_line_naming_what_is_accepted(
    tmp_path: Path,
) -> None:
    out = tmp_path / "x.parquet"
    for env_id, needle in (
        ("NoSuchEnv-v0", "unknown task 'NoSuchEnv-v0'; choose one of Acrobot-v1"),
        ("FrozenLake-v1", "observation space Discrete(16)"),  # registered, not a flat Box
    ):
        result = invoke("gym", "collect", env_id, "-n", "10", "--out", str(out))
        lines = result.output.strip().splitlines()
        assert result.exit_code == 2 and len(lines) == 1, result.output
        assert needle in lines[0] and "CartPole-v1" in lines[0], lines[0]
        assert all(paper in lines[0] for paper in TASKS), lines[0]
    with pytest.raises(ConfigError, match="unknown task"):
        task("NoSuchEnv-v0")
    assert not out.exists()


def test_cartpole_end_to_end_expert_collect_irl_rl(tmp_path: Path) -> None:
    expert, data = tmp_path / "expert", tmp_path / "data.parquet"
    # No shipped expert: one line that says how to get one.
    result = invoke("gym", "collect", "CartPole-v1", "-n", "300", "--out", str(data))
    assert result.exit_code == 2 and "pokerirl gym expert CartPole-v1" in result.output
    result = invoke("gym", "irl", "CartPole-v1", "--out", str(tmp_path / "nothing"))
    assert result.exit_code == 2 and "pokerirl gym collect CartPole-v1" in result.output
    assert not data.exists() and not (tmp_path / "nothing").exists()
    result = invoke(
        "gym", "expert", "CartPole-v1", "--out", str(expert), "--timesteps", "2048",
        "--eval-every", "1024", "--eval-episodes", "1", "--final-episodes", "1",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "CartPole-v1: ppo expert" in result.output and "target" not in result.output
    result = invoke("gym", "collect", "CartPole-v1", "--expert", str(expert), "-n", "300",
                    "--out", str(data))  # fmt: skip
    assert result.exit_code == 0 and "wrote 300 transitions" in result.output, result.output
    irl = tmp_path / "irl"
    result = invoke("gym", "irl", "CartPole-v1", "--data", str(data), "--runs", "1",
                    "--epochs", "1", "--out", str(irl))  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "CartPole-v1 hairl: final return" in result.output
    # No true reward is known for it: no reward_quality.json, the rest of a run folder.
    assert (irl / "run-0" / "reward.pt").is_file()
    assert not (irl / "run-0" / "reward_quality.json").exists()
    result = invoke("gym", "rl", "CartPole-v1", "--reward-run", str(irl / "run-0"), "--runs",
                    "1", "--timesteps", "64", "--evaluations", "1", "--eval-episodes", "1",
                    "--out", str(tmp_path / "rl"))  # fmt: skip
    assert result.exit_code == 0 and "CartPole-v1: final true return" in result.output
