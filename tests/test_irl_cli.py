"""`pokerirl train` end to end: run directory contents, checkpoints, load_reward, bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import torch
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.irl import load_config, load_policy, load_reward, load_run_config
from pokerirl.irl.table import read_expert_table, split_by_hand
from pokerirl.irl.toy import toy_expert_table

torch.set_num_threads(1)
REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def table_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("data") / "table.parquet"
    pq.write_table(toy_expert_table(num_hands=400, seed=2), path)
    return path


@pytest.fixture(scope="module")
def run_dir(table_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs") / "hairl"
    config = tmp_path_factory.mktemp("cfg") / "train.toml"
    config.write_text("batch_size = 64\nepochs = 9\nsigma_end = 0.2\n")
    args = ["train", str(table_path), "--out", str(out), "--algo", "hairl", "--epochs", "3"]
    result = CliRunner().invoke(app, [*args, "--config", str(config), "--seed", "11", "--quiet"])
    assert result.exit_code == 0, result.output
    assert "validation alignment" in result.output
    return out


def test_run_directory_has_metrics_plots_checkpoints_and_config(
    run_dir: Path, table_path: Path
) -> None:
    lines = (run_dir / "metrics.jsonl").read_text().splitlines()
    metrics = [json.loads(line) for line in lines]
    assert [m["epoch"] for m in metrics] == [1, 2, 3]  # --epochs beats the TOML file
    for key in (
        "disc_loss",
        "policy_adv_loss",
        "policy_sup_loss",
        "val_alignment",
        "majority_alignment",
        "disc_acc_expert",
        "disc_acc_policy",
        "val_policy_dist",
        "val_expert_dist",
    ):
        assert key in metrics[-1]
    for png in ("alignment.png", "losses.png", "disc_accuracy.png"):
        assert (run_dir / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    config = load_run_config(run_dir)
    hyper = config["hyperparameters"]
    assert (hyper["batch_size"], hyper["sigma_end"], hyper["epochs"]) == (64, 0.2, 3)
    assert (hyper["seed"], hyper["alpha"], hyper["reward_hidden"]) == (11, 0.33, [64])
    assert config["architecture"]["action_space"] == {"type": "discrete", "num_actions": 4}
    assert config["data"]["sha256"] == read_expert_table(table_path).fingerprint()
    assert config["data"]["train_rows"] + config["data"]["val_rows"] == config["data"]["rows"]
    assert {"torch", "numpy", "pyarrow", "pokerirl", "python"} <= set(config["versions"])
    assert config["result"]["final_metrics"] == metrics[-1]
    assert not [p for p in run_dir.iterdir() if p.name.endswith(".tmp")]


def test_checkpoints_are_state_dicts_and_round_trip(run_dir: Path, table_path: Path) -> None:
    state = torch.load(run_dir / "policy.pt", weights_only=True)
    assert all(isinstance(v, torch.Tensor) for v in state.values())
    policy = load_policy(run_dir)
    expert = read_expert_table(table_path)
    _, val_rows = split_by_hand(expert.hand_index, expert.num_hands, val_fraction=0.1, seed=11)
    val = expert.to_expert_data(val_rows)
    with torch.inference_mode():
        predicted = policy(val.obs.float(), val.legal_mask).argmax(1)
    alignment = (predicted == val.actions.argmax(1)).float().mean().item()
    final = load_run_config(run_dir)["result"]["final_metrics"]
    assert alignment == pytest.approx(final["val_alignment"])


def test_load_reward_numpy_and_torch_and_in_a_fresh_process(run_dir: Path) -> None:
    reward = load_reward(run_dir)
    rng = np.random.default_rng(0)
    obs = (rng.random((5, 72)) < 0.1).astype(np.uint8)
    actions = np.array([0, 1, 3, 1, 0])
    values = reward(obs, actions)
    assert values.dtype == np.float32 and values.shape == (5,)
    tensor_values = reward(torch.from_numpy(obs), torch.from_numpy(actions))
    assert isinstance(tensor_values, torch.Tensor)
    assert np.array_equal(tensor_values.numpy(), values)
    assert len(set(values.round(6).tolist())) > 1  # depends on its inputs
    with pytest.raises(ValueError, match="obs must be"):
        reward(obs[:, :70], actions)

    script = (
        "import sys, numpy as np; from pokerirl.irl import load_reward; "
        "obs = np.frombuffer(bytes.fromhex(sys.argv[2]), np.uint8).reshape(5, 72); "
        "print(load_reward(sys.argv[1])(obs, np.array([0, 1, 3, 1, 0])).tobytes().hex())"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run(
        [sys.executable, "-c", script, str(run_dir), obs.tobytes().hex()],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    fresh = np.frombuffer(bytes.fromhex(done.stdout.strip()), np.float32)
    # Another process may use other thread counts, hence other summation orders: allclose.
    assert np.allclose(fresh, values, rtol=1e-5, atol=1e-6)


def test_config_precedence_and_bad_config(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text("alpha = 0.5\nepochs = 7\n")
    config = load_config("airl", config_file=path, overrides={"epochs": 2, "seed": None})
    assert (config.alpha, config.epochs, config.sigma_start) == (0.5, 2, 0.0)
    path.write_text("alpah = 0.5\n")
    with pytest.raises(ValueError, match="unknown setting"):
        load_config("hairl", config_file=path)
    path.write_text("alpha = [\n")
    with pytest.raises(ValueError, match="TOML"):
        load_config("hairl", config_file=path)


def _assert_one_line_error(exit_code: int, stderr: str, needle: str) -> None:
    assert exit_code != 0
    assert "Traceback" not in stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and needle in lines[0], stderr


@pytest.mark.parametrize(
    ("case", "needle"),
    [
        ("missing", "not found"),
        ("no_columns", "lacks required column"),
        ("empty", "empty"),
        ("bad_algo", "unknown algo"),
        ("cuda", "cuda"),
        ("bad_hidden", "--hidden"),
    ],
)
def test_bad_input_gives_one_line_errors(
    case: str, needle: str, table_path: Path, tmp_path: Path
) -> None:
    table = toy_expert_table(num_hands=5)
    args = {"algo": "hairl", "table": str(table_path), "extra": []}
    if case == "missing":
        args["table"] = str(tmp_path / "missing.parquet")
    elif case == "no_columns":
        pq.write_table(table.drop_columns(["obs"]), tmp_path / "t.parquet")
        args["table"] = str(tmp_path / "t.parquet")
    elif case == "empty":
        pq.write_table(table.slice(0, 0), tmp_path / "t.parquet")
        args["table"] = str(tmp_path / "t.parquet")
    elif case == "bad_algo":
        args["algo"] = "gail"
    elif case == "cuda":
        if torch.cuda.is_available():
            pytest.skip("CUDA is available here")
        args["extra"] = ["--device", "cuda"]
    elif case == "bad_hidden":
        args["extra"] = ["--hidden", "64,x"]
    command = ["train", args["table"], "--out", str(tmp_path / "run"), "--algo", args["algo"]]
    result = CliRunner().invoke(app, [*command, "--epochs", "1", *args["extra"]])
    _assert_one_line_error(result.exit_code, result.stderr, needle)


def test_bad_input_in_a_real_process(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    command = [sys.executable, "-m", "pokerirl", "train", str(tmp_path / "none.parquet")]
    done = subprocess.run(
        [*command, "--out", str(tmp_path / "run"), "--algo", "nope"],
        capture_output=True,
        text=True,
        env=env,
    )
    _assert_one_line_error(done.returncode, done.stderr, "unknown algo")


def test_mismatched_checkpoint_is_a_clear_error(run_dir: Path, tmp_path: Path) -> None:
    import shutil

    broken = tmp_path / "broken"
    shutil.copytree(run_dir, broken)
    torch.save({"mlp.0.weight": torch.zeros(2, 2)}, broken / "reward.pt")
    with pytest.raises(ValueError, match="does not match"):
        load_reward(broken)
    with pytest.raises(FileNotFoundError, match="config.json"):
        load_reward(tmp_path)
