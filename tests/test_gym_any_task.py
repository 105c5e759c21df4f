"""Any registered Gymnasium task (issue 34): generic settings from the action space, the
paper's six unchanged, one line for an id the toolkit cannot take, and CartPole end to end."""

from __future__ import annotations

from pathlib import Path

import pytest
from testkit import Cli

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.errors import ConfigError
from pokerirl.gym.presets import GENERIC_PPO, TASKS
from pokerirl.gym.tasks import task
from pokerirl.studies.gym.config import PRESETS

invoke = Cli()  # the shared in-process command line (tests/testkit.py)


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


def test_without_a_shipped_expert_the_commands_say_how_to_get_one(tmp_path: Path) -> None:
    data, out = tmp_path / "data.parquet", tmp_path / "out"
    for args, needle in (
        (["gym", "collect", "CartPole-v1", "-n", "300", "--out", str(data)], "--expert DIR"),
        (["gym", "irl", "CartPole-v1", "--out", str(out)], "pokerirl gym collect CartPole-v1"),
        (["gym", "study", "CartPole-v1", "--out", str(out)], "--expert DIR"),
    ):
        result = invoke(*args)
        lines = result.output.strip().splitlines()
        assert result.exit_code == 2 and len(lines) == 1, (args, result.output)
        assert "pokerirl gym expert CartPole-v1" in lines[0] and needle in lines[0], lines[0]
    assert not data.exists() and not out.exists()


@pytest.fixture(scope="module")
def cartpole_expert(tmp_path_factory: pytest.TempPathFactory) -> Path:
    # A tiny expert: one PPO update (n_steps 2048), the better of two evaluations kept.
    expert = tmp_path_factory.mktemp("cartpole") / "expert"
    result = invoke(
        "gym", "expert", "CartPole-v1", "--out", str(expert), "--timesteps", "2048",
        "--eval-every", "1024", "--eval-episodes", "1", "--final-episodes", "1",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "CartPole-v1: ppo expert" in result.output and "target" not in result.output
    return expert


def test_cartpole_end_to_end_collect_irl_rl(cartpole_expert: Path, tmp_path: Path) -> None:
    data, irl = tmp_path / "data.parquet", tmp_path / "irl"
    result = invoke("gym", "collect", "CartPole-v1", "--expert", str(cartpole_expert), "-n",
                    "300", "--out", str(data))  # fmt: skip
    assert result.exit_code == 0 and "wrote 300 transitions" in result.output, result.output
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


@pytest.mark.slow  # about 14 s: three PPO runs of one 2048-step rollout each, 2 IRL runs
def test_cartpole_study_with_an_expert_folder(cartpole_expert: Path, tmp_path: Path) -> None:
    import json

    result = invoke(
        "gym", "study", "CartPole-v1", "--out", str(tmp_path), "--expert", str(cartpole_expert),
        "--runs", "1", "--transitions", "300", "--epochs", "1", "--eval-episodes", "1",
        "--timesteps", "64", "--jobs", "1", "--quiet",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["env"] == "CartPole-v1" and summary["paper"] is None
    assert summary["settings"]["authors_budget"] is False and summary["discrete"] is True
    assert "epic" not in summary["algos"]["hairl"]  # no true reward known
    report = (tmp_path / "report.md").read_text()
    assert "not one of the paper's tasks" in report and "| IRL-phase return, AIRL |" in report
    # The finished study reads back and renders the same report.
    assert invoke("report", str(tmp_path)).output == report
    expert = json.loads((tmp_path / "expert.unit.json").read_text())
    assert "folder_sha256" in json.dumps(expert)  # the data names the expert folder it came from
