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
from testkit import Cli

from pokerirl.datasets.toy import toy_expert_table
from pokerirl.irl import RunError, load_config, load_policy, load_reward, load_run_config
from pokerirl.irl.adversarial import LOSS_KEYS
from pokerirl.poker import read_table

torch.set_num_threads(1)
REPO = Path(__file__).resolve().parents[1]

CLI = Cli()  # pokerirl run in this process (tests/testkit.py)


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
    result = CLI.invoke([*args, "--config", str(config), "--seed", "11", "--quiet"])
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
        *LOSS_KEYS,
        "val_alignment",
        "val_reward_alignment",
        "disc_acc_expert",
        "disc_acc_policy",
        "val_policy_dist",
        "val_expert_dist",
    ):
        assert key in metrics[-1]
    baselines = json.loads((run_dir / "baselines.json").read_text())
    assert set(baselines) == {"majority", "legal_majority", "bc"}
    assert all(0 <= v <= 1 for v in baselines.values())
    split = json.loads((run_dir / "split.json").read_text())
    hands = set(pq.read_table(table_path, columns=["hand_id"]).column(0).to_pylist())
    assert split["validation_groups"] and set(split["validation_groups"]) <= hands
    for png in ("alignment.png", "losses.png", "disc_accuracy.png"):
        assert (run_dir / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    config = load_run_config(run_dir)
    hyper = config["hyperparameters"]
    assert (hyper["batch_size"], hyper["sigma_end"], hyper["epochs"]) == (64, 0.2, 3)
    assert (hyper["seed"], hyper["alpha"], hyper["reward_hidden"]) == (11, 0.33, [64])
    assert config["architecture"]["action_space"] == {"type": "discrete", "num_actions": 4}
    assert config["data"]["sha256"] == read_table(table_path).fingerprint()
    assert config["data"]["train_rows"] + config["data"]["val_rows"] == config["data"]["rows"]
    assert {"torch", "numpy", "pyarrow", "pokerirl", "python"} <= set(config["versions"])
    assert config["result"]["final_metrics"] == metrics[-1]
    assert config["result"]["baselines"] == baselines
    # Wall-clock timings live apart from what the fingerprints hash.
    text = (run_dir / "config.json").read_text()
    assert "seconds" not in text and "samples_per_second" not in text
    assert json.loads((run_dir / "timings.json").read_text())["samples_per_second"] > 0
    assert not [p for p in run_dir.parent.iterdir() if p.name.startswith(".")]


def test_checkpoints_are_state_dicts_and_round_trip(run_dir: Path, table_path: Path) -> None:
    state = torch.load(run_dir / "policy.pt", weights_only=True)
    assert all(isinstance(v, torch.Tensor) for v in state.values())
    policy = load_policy(run_dir)
    data = read_table(table_path)
    held_out = set(json.loads((run_dir / "split.json").read_text())["validation_groups"])
    val = data.subset(np.array([g in held_out for g in data.groups]))
    with torch.inference_mode():
        predicted = policy(val.obs, val.legal_mask).argmax(1)
    alignment = (predicted == val.actions).float().mean().item()
    final = load_run_config(run_dir)["result"]["final_metrics"]
    assert alignment == pytest.approx(final["val_alignment"])


@pytest.mark.slow
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
        ("out_is_file", "exists and is not a folder"),
        ("out_is_a_run", "--overwrite"),
        ("toml_float_epochs", "epochs must be an integer, got 1.5"),
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
        args["algo"] = "sqil"
    elif case == "cuda":
        if torch.cuda.is_available():
            pytest.skip("CUDA is available here")
        args["extra"] = ["--device", "cuda"]
    elif case == "bad_hidden":
        args["extra"] = ["--hidden", "64,x"]
    elif case == "out_is_file":
        (tmp_path / "run").write_text("precious")
    elif case == "out_is_a_run":
        (tmp_path / "run").mkdir()
        (tmp_path / "run" / "config.json").write_text("{}")
    elif case == "toml_float_epochs":
        (tmp_path / "c.toml").write_text("epochs = 1.5\n")
        args["extra"] = ["--config", str(tmp_path / "c.toml")]
    command = ["train", args["table"], "--out", str(tmp_path / "run"), "--algo", args["algo"]]
    epochs = [] if case == "toml_float_epochs" else ["--epochs", "1"]
    result = CLI.invoke([*command, *epochs, *args["extra"]])
    _assert_one_line_error(result.exit_code, result.stderr, needle)
    if case == "out_is_file":
        assert (tmp_path / "run").read_text() == "precious"


@pytest.mark.slow
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
    with pytest.raises(RunError, match=r"config.json"):
        load_reward(tmp_path)


def _corrupt(run_dir: Path, tmp_path: Path, case: str) -> tuple[Path, str]:
    """A copy of ``run_dir`` broken in one way, and the file the error must name."""
    import shutil

    bad = tmp_path / f"bad-{case}"
    shutil.copytree(run_dir, bad)
    reward, config = bad / "reward.pt", bad / "config.json"
    record = json.loads(config.read_text())
    if case == "random_bytes":
        reward.write_bytes(np.random.default_rng(0).bytes(4096))
    elif case == "empty":
        reward.write_bytes(b"")
    elif case == "truncated":
        reward.write_bytes(reward.read_bytes()[:1000])
    elif case == "config_list":
        config.write_text("[]")
    elif case == "no_architecture":
        del record["architecture"]
        config.write_text(json.dumps(record))
    elif case == "string_hidden":
        record["architecture"]["reward_hidden"] = "64"
        config.write_text(json.dumps(record))
    return bad, str(config if case.startswith(("config", "no_", "string")) else reward)


BAD_RUNS = [
    "random_bytes",
    "empty",
    "truncated",
    "config_list",
    "no_architecture",
    "string_hidden",
]


@pytest.mark.parametrize("case", BAD_RUNS)
def test_bad_reward_runs_give_one_line_errors_naming_the_file(
    run_dir: Path, tmp_path: Path, case: str
) -> None:
    bad, named = _corrupt(run_dir, tmp_path, case)
    with pytest.raises(RunError) as info:
        load_reward(bad)
    text = str(info.value)
    assert isinstance(info.value, ValueError) and "\n" not in text
    assert named in text and "weights_only" not in text
    # Through the agent trainer's command line, which calls load_reward.
    command = ["agent", "train", "--reward", "learned", "--reward-run", str(bad)]
    result = CLI.invoke([*command, "--out", str(tmp_path / "agent"), "-q"])
    _assert_one_line_error(result.exit_code, result.stderr, named)
    assert "weights_only" not in result.output + result.stderr


def test_format_version_1_runs_still_load(run_dir: Path, tmp_path: Path) -> None:
    """A run as the first trainer wrote it (ReLU, no layer norm, fewer keys) loads as is."""
    import shutil

    old = tmp_path / "v1"
    shutil.copytree(run_dir, old)
    record = json.loads((old / "config.json").read_text())
    record["format_version"] = 1
    for key in ("reward_family", "layer_norm", "gamma"):
        del record["architecture"][key]
    (old / "config.json").write_text(json.dumps(record))
    obs, actions = np.zeros((3, 72), np.uint8), np.array([0, 1, 3])
    assert np.array_equal(load_reward(old)(obs, actions), load_reward(run_dir)(obs, actions))


@pytest.mark.slow
def test_same_seed_same_bytes(table_path: Path, tmp_path: Path) -> None:
    for name in ("a", "b"):
        args = ["train", str(table_path), "--out", str(tmp_path / name), "--epochs", "1"]
        result = CLI.invoke([*args, "--batch-size", "64", "--quiet"])
        assert result.exit_code == 0, result.output
    for file in ("reward.pt", "policy.pt", "config.json", "metrics.jsonl", "split.json"):
        assert (tmp_path / "a" / file).read_bytes() == (tmp_path / "b" / file).read_bytes(), file


@pytest.mark.slow
def test_several_runs_write_run_folders_a_summary_and_a_band_plot(
    table_path: Path, tmp_path: Path
) -> None:
    out = tmp_path / "runs"
    args = ["train", str(table_path), "--out", str(out), "--runs", "2", "--epochs", "2"]
    result = CLI.invoke([*args, "--batch-size", "64", "--seed", "5", "--quiet"])
    assert result.exit_code == 0, result.output
    assert "run-0" in result.output and "run-1" in result.output
    configs = [load_run_config(out / f"run-{k}") for k in (0, 1)]
    assert [c["hyperparameters"]["seed"] for c in configs] == [5, 6]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 2 and summary["seeds"] == [5, 6] and summary["epochs"] == [1, 2]
    per_run = [
        [json.loads(line)["val_alignment"] for line in (out / f"run-{k}" / "metrics.jsonl").open()]
        for k in (0, 1)
    ]
    band = summary["metrics"]["val_alignment"]
    assert band["mean"] == pytest.approx(np.mean(per_run, axis=0).tolist())
    assert band["std"] == pytest.approx(np.std(per_run, axis=0, ddof=1).tolist())
    assert set(summary["baselines"]) == {"majority", "legal_majority", "bc"}
    assert (out / "alignment_bands.png").read_bytes()[:4] == b"\x89PNG"
    load_reward(out / "run-1")  # each run loads like a single run
    with pytest.raises(RunError, match="several runs"):
        load_reward(out)


@pytest.mark.slow
def test_several_runs_are_resumable_units_whatever_the_job_count(
    table_path: Path, tmp_path: Path
) -> None:
    base = ["train", str(table_path), "--epochs", "1", "--batch-size", "64", "--quiet"]
    weights = ("reward.pt", "policy.pt", "config.json", "metrics.jsonl", "split.json")
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}"
        result = CLI.invoke([*base, "--out", str(out), "--runs", "2", "-j", jobs])
        assert result.exit_code == 0, result.output
    for k in (0, 1):
        for name in weights:
            one, two = (tmp_path / f"jobs{j}" / f"run-{k}" / name for j in (1, 2))
            assert one.read_bytes() == two.read_bytes(), (k, name)
    out = tmp_path / "jobs1"
    finished = (out / "run-0" / "reward.pt").stat().st_mtime_ns
    (out / "run-1" / "reward.pt").write_bytes(b"corrupt")  # recomputed, not trusted
    result = CLI.invoke([*base, "--out", str(out), "--runs", "2"])
    assert result.exit_code == 0, result.output
    assert (out / "run-0" / "reward.pt").stat().st_mtime_ns == finished  # reused
    twin = tmp_path / "jobs2" / "run-1" / "reward.pt"
    assert (out / "run-1" / "reward.pt").read_bytes() == twin.read_bytes()
    changed = [*base[:3], "2", *base[4:], "--out", str(out), "--runs", "2"]
    result = CLI.invoke(changed)
    assert result.exit_code == 1 and "another configuration" in result.output
    assert (out / "run-0" / "reward.pt").stat().st_mtime_ns == finished


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.slow
def test_a_killed_overwrite_leaves_the_finished_run_byte_for_byte(
    run_dir: Path, table_path: Path, tmp_path: Path
) -> None:
    import shutil
    import signal
    import time

    target = tmp_path / "run"
    shutil.copytree(run_dir, target)
    before = _snapshot(target)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    command = [sys.executable, "-m", "pokerirl", "train", str(table_path), "--out", str(target)]
    process = subprocess.Popen(
        [*command, "--overwrite", "--epochs", "500", "--batch-size", "64", "--quiet"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:  # wait until the new run is writing epochs
            staged = list(tmp_path.glob(".run.new-*/new/run/metrics.jsonl"))  # the store's
            if staged and staged[0].read_text().count("\n") >= 2:
                break
            assert process.poll() is None, "the run ended before it could be killed"
            time.sleep(0.1)
        else:
            pytest.fail("the new run never started writing")
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert _snapshot(target) == before
    load_reward(target)  # still a consistent, loadable run
    from pokerirl.store import tidy

    tidy(tmp_path, key="run")  # what the next writer does first: the dead write is gone
    assert not list(tmp_path.glob(".run.*"))
