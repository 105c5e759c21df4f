"""``pokerirl agent train`` and ``pokerirl match`` with agent folders, through the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from pokerirl.agents.dqn import DQNConfig, train_dqn
from pokerirl.agents.train import TrainConfig, reward_run_fingerprint, train_agent
from pokerirl.cli import app
from pokerirl.game import make_agent
from pokerirl.seeds import parse_seeds

torch.set_num_threads(1)
FAST = ["--hands", "512", "--eval-every", "512", "--eval-hands", "200", "--concurrent-hands", "128"]


def invoke(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.output


def stdout_of(*args: str) -> str:
    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.stdout


def test_train_then_match_the_folder(tmp_path: Path) -> None:
    out = tmp_path / "agent"
    code, output = invoke("agent", "train", "--out", str(out), "--seed", "3", "--quiet", *FAST)
    assert code == 0, output
    assert "vs random" in output and json.loads((out / "config.json").read_text())["seed"] == 3
    output = stdout_of("match", str(out), "random", "--hands", "2000", "--format", "json")
    assert json.loads(output)["hands"] == 2000


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.mark.slow
def test_seeds_resume_reuse_retrain_corrupt_and_refuse_other_settings(tmp_path: Path) -> None:
    out = tmp_path / "many"
    code, output = invoke("agent", "train", "--out", str(out), "--seeds", "0-1", "-q", *FAST)
    assert code == 0, output
    weights = {k: (out / f"seed-{k}" / "model.pt").read_bytes() for k in (0, 1)}
    assert weights[0] != weights[1]
    (out / "seed-1" / "model.pt").write_bytes(b"\0" * 100)  # corrupt: retrained, not reused
    code, output = invoke(
        "agent", "train", "--out", str(out), "--seeds", "0-2", "--jobs", "2", "-q", *FAST
    )
    assert code == 0, output
    assert "seed-0: already finished with these settings, reused" in output
    assert "seed-1: 512 hands" in output and "seed-2: 512 hands" in output
    # The same bytes as the first run: jobs, processes and resuming do not change weights.
    assert {k: (out / f"seed-{k}" / "model.pt").read_bytes() for k in (0, 1)} == weights
    seeds = [json.loads((out / f"seed-{k}" / "config.json").read_text())["seed"] for k in range(3)]
    assert seeds == [0, 1, 2]
    before = _tree(out)
    # A set never mixes settings: other settings are refused in one line, nothing changes.
    code, output = invoke(
        "agent", "train", "--out", str(out), "--seeds", "0-3", "-q", *FAST[:-2],
        "--concurrent-hands", "64",
    )  # fmt: skip
    assert code == 1 and output.count("\n") == 1
    assert "seed-0 was made with another configuration (dqn.concurrent_hands 128 -> 64)" in output
    assert _tree(out) == before and not (out / "seed-3").exists()


def test_a_finished_agent_is_reused_refused_or_overwritten_never_damaged(tmp_path: Path) -> None:
    out = tmp_path / "agent"
    assert invoke("agent", "train", "--out", str(out), "-q", *FAST)[0] == 0
    before = _tree(out)
    timings = json.loads((out / "timings.json").read_text())
    assert timings["seconds"] > 0 and "seconds" not in (out / "config.json").read_text()
    code, output = invoke("agent", "train", "--out", str(out), "-q", *FAST)
    assert code == 0 and "already finished with these settings, reused" in output
    code, output = invoke("agent", "train", "--out", str(out), "--seed", "1", "-q", *FAST)
    assert code == 1 and "seed 0 -> 1" in output and "--overwrite" in output
    assert _tree(out) == before
    code, output = invoke(
        "agent", "train", "--out", str(out), "--seed", "1", "--overwrite", "-q", *FAST
    )
    assert code == 0, output
    assert json.loads((out / "config.json").read_text())["seed"] == 1
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no leftovers
    # A folder of someone else's files is never replaced without --overwrite.
    mine = tmp_path / "notes"
    mine.mkdir()
    (mine / "todo.txt").write_text("keep me")
    code, output = invoke("agent", "train", "--out", str(mine), "-q", *FAST)
    assert code == 1 and "no unit.json" in output and (mine / "todo.txt").exists()


def test_same_seed_same_bytes_and_threads_are_explicit(tmp_path: Path) -> None:
    torch.set_num_threads(2)  # the caller's setting must not leak into the weights
    try:
        code, output = invoke("agent", "train", "--out", str(tmp_path / "a"), "-q", *FAST)
    finally:
        torch.set_num_threads(1)
    assert code == 0, output
    assert invoke("agent", "train", "--out", str(tmp_path / "b"), "-q", *FAST)[0] == 0
    for name in ("model.pt", "config.json", "metrics.jsonl", "unit.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    from pokerirl.agents.checkpoint import folder_fingerprint

    assert folder_fingerprint(tmp_path / "a") == folder_fingerprint(tmp_path / "b")
    assert json.loads((tmp_path / "a" / "config.json").read_text())["threads"] == 1
    code, output = invoke(
        "agent", "train", "--out", str(tmp_path / "a"), "--threads", "2", "-q", *FAST
    )
    assert code == 1 and "threads 1 -> 2" in output
    assert invoke("agent", "train", "--out", str(tmp_path / "x"), "--threads", "0")[0] == 2


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["--reward", "learned"], 1, "reward 'learned' needs a reward_run"),
        (["--reward", "shaped"], 2, "reward must be one of sparse, learned"),
        (["--reward-run", "."], 2, "reward_run needs reward 'learned'"),
        (["--reward", "learned", "--reward-run", "."], 1, "not a reward run"),
        (["--seeds", "5-2"], 2, "empty seed range"),
        (["--opponent", "nobody"], 1, "unknown agent 'nobody'"),
        (["--eval-hands", "3"], 2, "eval_hands must be even"),
        (["--train-every", "0"], 2, "train_every must be at least 1"),
    ],
)
def test_bad_input_is_a_one_line_error(
    tmp_path: Path, args: list[str], code: int, message: str
) -> None:
    found, output = invoke("agent", "train", "--out", str(tmp_path / "x"), "-q", *args)
    assert found == code  # 2: settings that cannot run (usage); 1: inputs that cannot be used
    assert message in output and output.count("\n") == 1 and "Traceback" not in output


def test_parse_seeds_and_reward_run_fingerprint(tmp_path: Path) -> None:
    assert parse_seeds("0-2,7") == (0, 1, 2, 7)
    for name, data in (("reward.pt", b"weights"), ("config.json", b"{}")):
        (tmp_path / name).write_bytes(data)
    before = reward_run_fingerprint(tmp_path)
    (tmp_path / "config.json").write_bytes(b'{"x": 1}')
    assert reward_run_fingerprint(tmp_path) != before and before.startswith("sha256:")


def test_learned_reward_training_records_the_run(tmp_path: Path) -> None:
    for name, data in (("reward.pt", b"weights"), ("config.json", b"{}")):
        (tmp_path / name).write_bytes(data)
    calls = []

    def reward_fn(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        calls.append(len(actions))
        return obs[:, :52].sum(axis=1).astype(np.float32) - actions

    config = TrainConfig(
        hands=256,
        seed=1,
        reward="learned",
        reward_run=str(tmp_path),
        payoff_weight=0.5,
        eval_every=256,
        eval_hands=100,
        dqn=DQNConfig(concurrent_hands=128),
    )
    train_agent(tmp_path / "agent", config, reward_fn=reward_fn)
    record = json.loads((tmp_path / "agent" / "config.json").read_text())
    assert record["reward"] == {
        "mode": "learned",
        "run": str(tmp_path),
        "fingerprint": reward_run_fingerprint(tmp_path),
        "payoff_weight": 0.5,
        "transform": "raw",
        "raise_counts": "decision",
    }
    # f once per stored transition in training, then one call on the four actions of every
    # decision of the final evaluation against random (the follow metric).
    assert sum(calls[:-1]) == record["final"]["transitions"]
    assert calls[-1] % 4 == 0 and record["final"]["follows_reward"] is not None


def test_learned_reward_from_a_real_irl_run_end_to_end(
    tmp_path: Path, small_table_path: Path
) -> None:
    from pokerirl.irl import load_config, load_reward
    from pokerirl.poker import train_table

    settings = load_config("hairl", overrides={"epochs": 1, "batch_size": 64})
    train_table(small_table_path, tmp_path / "run", algo="hairl", config=settings)
    out = tmp_path / "agent"
    code, output = invoke(
        "agent", "train", "--reward", "learned", "--reward-run", str(tmp_path / "run"),
        "--payoff-weight", "0.3", "--out", str(out), "-q", *FAST,
    )  # fmt: skip
    assert code == 0, output
    record = json.loads((out / "config.json").read_text())
    assert record["reward"]["fingerprint"] == reward_run_fingerprint(tmp_path / "run")
    assert record["reward"]["payoff_weight"] == 0.3
    # The run's real f_theta in the trainer: non-terminal rewards are (1 - w) f(s, a).
    f = load_reward(tmp_path / "run")
    learner = train_dqn(
        DQNConfig(concurrent_hands=64), hands=128, seed=0, opponent=make_agent("random"),
        reward_fn=f, payoff_weight=0.3,
    )  # fmt: skip
    replay, n = learner.replay, learner.replay.size
    steps = ~replay.done[:n]
    expected = 0.7 * f(replay.obs[:n][steps], replay.actions[:n][steps])
    np.testing.assert_allclose(replay.rewards[:n][steps], expected, rtol=1e-5, atol=1e-6)
    assert steps.sum() > 20 and np.unique(expected).size > 1


DQN_FLAGS = (
    "--hidden", "--replay-size", "--replay-init", "--batch-size", "--lr", "--gamma",
    "--epsilon-start", "--epsilon-end", "--epsilon-decay-steps", "--target-update-every",
    "--train-every", "--concurrent-hands", "--self-play-every",
)  # fmt: skip


def test_every_dqn_field_is_a_flag_and_a_toml_key(tmp_path: Path) -> None:
    import dataclasses
    import re

    result = CliRunner().invoke(app, ["agent", "train", "--help"], env={"COLUMNS": "200"})
    plain = re.sub(r"\x1b\[[0-9;]*m", "", result.output)
    assert all(flag in plain for flag in DQN_FLAGS)
    assert len(DQN_FLAGS) == len(dataclasses.fields(DQNConfig))
    toml = tmp_path / "dqn.toml"
    toml.write_text("epsilon_end = 0.05\nhidden = [16, 8]\ntrain_every = 4\nhands = 256\n")
    out = tmp_path / "agent"
    flags = ["--train-every", "2", "--eval-every", "256", "--eval-hands", "100"]
    code, output = invoke("agent", "train", "--config", str(toml), *flags, "--out", str(out), "-q")
    assert code == 0, output
    record = json.loads((out / "config.json").read_text())
    assert record["hidden"] == [16, 8] and record["hands"] == 256
    assert record["dqn"]["epsilon_end"] == 0.05 and record["dqn"]["train_every"] == 2  # flag wins
    toml.write_text("learning_rat = 1e-3\n")
    code, output = invoke("agent", "train", "--config", str(toml), "--out", str(out), "-q")
    assert (
        code == 2 and "unknown setting 'learning_rat'" in output and len(output.splitlines()) == 1
    )
    toml.write_text('train_every = "often"\n')
    code, output = invoke("agent", "train", "--config", str(toml), "--out", str(out), "-q")
    assert code == 2 and "train_every must be an integer" in output


def test_the_authors_preset_keeps_and_plays_the_best_checkpoint(tmp_path: Path) -> None:
    from pokerirl.agents import resolve_agent
    from pokerirl.agents.checkpoint import QNetwork

    out = tmp_path / "authors"
    flags = ["--hands", "300", "--eval-hands", "200", "--concurrent-hands", "4"]
    code, output = invoke("agent", "train", "--preset", "authors", *flags, "--out", str(out))
    assert code == 0, output
    assert "plays kept.pt" in output
    record = json.loads((out / "config.json").read_text())
    assert record["dqn"]["learning_rate"] == 5e-4 and record["dqn"]["train_every"] == 1
    assert record["dqn"]["epsilon_end"] == 0.0 and record["dqn"]["epsilon_decay_steps"] == 5_000
    assert record["plays"] == "kept" and record["evaluation"]["protocol"] == "authors"
    lines = [json.loads(x) for x in (out / "metrics.jsonl").read_text().splitlines()]
    assert [line["hands"] for line in lines] == [4, 104, 204, 300]  # after hands 1, 101, 201
    assert [line["keep_rule"] for line in lines] == [True, True, True, False]
    # The rule: keep a model whose payoff beats 0.8 x the best so far (the best starts at -inf).
    best, kept = float("-inf"), None
    for line in lines[:-1]:
        payoff = line["eval"]["random"]["mbb_per_hand"]
        if payoff > 0.8 * best:
            kept, best = line, max(best, payoff)
    assert record["kept"] == kept
    network = QNetwork()
    network.load_state_dict(torch.load(out / "kept.pt", weights_only=True))
    agent = resolve_agent(str(out))
    obs = np.random.default_rng(0).integers(0, 2, (5, 72)).astype(np.uint8)
    with torch.no_grad():
        expected = network.eval()(torch.from_numpy(obs).float()).numpy()
    np.testing.assert_allclose(agent.q_values(obs), expected, rtol=1e-6)
    code, output = invoke("agent", "train", "--play", "kept", "--out", str(tmp_path / "x"), "-q")
    assert code == 2 and "play 'kept' needs protocol 'authors'" in output
