"""Expert data: the exact Parquet schema, same seed same bytes, and transitions true to the env."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

import pyarrow as pa
import pyarrow.parquet as pq

from pokerirl.cli import app
from pokerirl.gym.collect import collect, read_transitions
from pokerirl.gym.envs import make_env
from pokerirl.gym.expert_policies import Expert, build_policy, load_expert, resolve_expert_dir

torch.set_num_threads(1)


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def untrained(env_id: str) -> Expert:
    torch.manual_seed(0)
    policy = build_policy(env_id, "ppo", {})
    return Expert(env_id=env_id, algo="ppo", policy=policy, record={})


def test_collect_writes_the_exact_schema_and_the_same_bytes_for_the_same_seed(
    tmp_path: Path,
) -> None:
    args = ["gym", "collect", "Acrobot-v1", "--expert", "shipped", "-n", "700"]
    paths = [tmp_path / f"{name}.parquet" for name in ("a", "b", "c")]
    for path, seed in zip(paths, (5, 5, 6), strict=True):
        result = CliRunner().invoke(app, [*args, "--seed", str(seed), "--out", str(path)])
        assert result.exit_code == 0, result.output
    assert digest(paths[0]) == digest(paths[1]) != digest(paths[2])
    schema = pq.read_schema(paths[0])
    assert schema.names == ["obs", "action", "reward", "next_obs", "done", "truncated", "episode"]
    assert schema.field("obs").type == pa.list_(pa.float32(), 6)
    assert schema.field("next_obs").type == pa.list_(pa.float32(), 6)
    assert schema.field("action").type == pa.int64()
    assert schema.field("reward").type == pa.float32()
    assert schema.field("done").type == schema.field("truncated").type == pa.bool_()
    assert schema.field("episode").type == pa.int64()
    assert pq.read_metadata(paths[0]).num_rows == 700


def test_transitions_replay_in_the_environment(tmp_path: Path) -> None:
    # Every row is a real step: episode k replays from reset(seed + k) with its actions, giving
    # its next_obs and rewards; done marks terminations only, and rows chain within an episode.
    expert = load_expert(resolve_expert_dir("shipped", "Acrobot-v1"))
    path = tmp_path / "acrobot.parquet"
    summary = collect(expert, path, transitions=600, seed=11)
    data = read_transitions(path)
    episodes = data["episode"]
    assert episodes[0] == 0 and set(np.diff(episodes)) <= {0, 1}
    assert summary.episodes == episodes[-1] + 1 >= 2
    env = make_env("Acrobot-v1")
    for k in range(summary.episodes):
        rows = np.flatnonzero(episodes == k)
        obs, _ = env.reset(seed=11 + k)
        np.testing.assert_allclose(data["obs"][rows[0]], obs, rtol=1e-6)
        for row in rows:
            next_obs, reward, terminated, truncated, _ = env.step(int(data["action"][row]))
            np.testing.assert_allclose(data["next_obs"][row], next_obs, rtol=1e-6, atol=1e-7)
            assert data["reward"][row] == reward
            assert (data["done"][row], data["truncated"][row]) == (terminated, truncated)
        np.testing.assert_array_equal(data["obs"][rows[1:]], data["next_obs"][rows[:-1]])
    # A good Acrobot expert terminates (done), never times out, except the cut last episode.
    assert data["done"][:-1].sum() == summary.episodes - 1 and not data["truncated"].any()


def test_continuous_actions_are_fixed_size_float32_lists_and_truncation_is_not_done(
    tmp_path: Path,
) -> None:
    path = tmp_path / "pendulum.parquet"
    collect(untrained("Pendulum-v1"), path, transitions=450, seed=0)
    schema = pq.read_schema(path)
    assert schema.field("action").type == pa.list_(pa.float32(), 1)
    data = read_transitions(path)
    assert data["action"].shape == (450, 1) and np.abs(data["action"]).max() <= 2.0
    # Pendulum never terminates: its 200-step episodes end truncated, with done False.
    assert not data["done"].any()
    np.testing.assert_array_equal(np.flatnonzero(data["truncated"]), [199, 399])


def test_collect_with_a_bad_expert_fails_in_one_line(tmp_path: Path) -> None:
    out = tmp_path / "x.parquet"
    args = ["gym", "collect", "Acrobot-v1", "-n", "10", "--out", str(out)]
    result = CliRunner().invoke(app, [*args, "--expert", str(tmp_path)])
    assert result.exit_code != 0 and "not an expert folder" in result.output
    result = CliRunner().invoke(app, ["gym", "collect", "Foo-v0", "-n", "10", "--out", str(out)])
    assert result.exit_code == 2 and "unknown task 'Foo-v0'; choose one of" in result.output
    assert not out.exists()


def test_continuous_tasks_collect_sampled_actions_by_default_and_record_it(
    tmp_path: Path,
) -> None:
    # Issue 20: deterministic Pendulum demos make log σ collapse and AIRL's reward invert;
    # the authors record SB3's sampled actions. Discrete tasks keep the greedy action.
    from pokerirl.gym.collect import default_deterministic

    assert default_deterministic("Pendulum-v1") is False
    assert default_deterministic("Acrobot-v1") is True
    expert = load_expert(resolve_expert_dir("shipped", "Pendulum-v1"))
    paths = {k: tmp_path / f"{k}.parquet" for k in ("default", "sampled", "mean")}
    summary = collect(expert, paths["default"], transitions=200, seed=0)
    collect(expert, paths["sampled"], transitions=200, seed=0, deterministic=False)
    collect(expert, paths["mean"], transitions=200, seed=0, deterministic=True)
    assert summary.deterministic is False
    meta = pq.read_schema(paths["default"]).metadata[b"pokerirl.gym"]
    assert b'"deterministic": false' in meta
    assert digest(paths["default"]) == digest(paths["sampled"]) != digest(paths["mean"])
    # Same first state, but the sampled actions are not the mean's (the expert's σ > 0).
    sampled, mean = (read_transitions(paths[k]) for k in ("sampled", "mean"))
    assert np.array_equal(sampled["obs"][0], mean["obs"][0])
    assert not np.allclose(sampled["action"], mean["action"])
