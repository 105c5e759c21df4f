"""Online IRL on poker (pokerirl/poker/online.py): the generator plays hands on the engine,
the discriminator sees those states, the run folder is offline train's and reproduces its
bytes for a seed, and ``train --mode online`` refuses bad options in one line."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import torch
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.datasets.toy import toy_expert_table
from pokerirl.game.deals import deal_cards
from pokerirl.irl import load_config, load_reward
from pokerirl.irl.adversarial import default_nets
from pokerirl.irl.online import OnlineTrainer
from pokerirl.irl.run import load_policy
from pokerirl.poker.data import read_table
from pokerirl.poker.online import (
    EngineGenerator,
    PokerOnlineSettings,
    hand_returns,
    train_poker_online,
)
from pokerirl.poker.reward_card import read_card

# The toy table's BC is perfect: a tiny online run falls below it, as it may.
pytestmark = pytest.mark.filterwarnings("ignore::pokerirl.poker.train.RewardBelowBC")
SETTINGS = PokerOnlineSettings(rounds=2, generator_steps=128)
BYTES = ("reward.pt", "policy.pt", "metrics.jsonl", "baselines.json", "split.json")


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("online") / "table.parquet"
    pq.write_table(toy_expert_table(num_hands=200, seed=3), path)
    return path


def config(seed: int = 0):  # type: ignore[no-untyped-def]
    return load_config("hairl", overrides={"epochs": 1, "batch_size": 64, "seed": seed})


def online_run(table: Path, out: Path, *, seed: int = 0) -> Path:
    train_poker_online(table, out, config=config(seed), settings=SETTINGS, progress=False)
    return out


@pytest.fixture(scope="module")
def run(table: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return online_run(table, tmp_path_factory.mktemp("online") / "run")


def test_a_run_reproduces_its_bytes_for_a_seed(table: Path, run: Path, tmp_path: Path) -> None:
    again = online_run(table, tmp_path / "again")
    other = online_run(table, tmp_path / "other", seed=1)
    for name in BYTES:
        assert (again / name).read_bytes() == (run / name).read_bytes(), name
    assert (other / "reward.pt").read_bytes() != (run / "reward.pt").read_bytes()


def test_the_folder_is_offline_trains_and_says_online(run: Path) -> None:
    data = json.loads((run / "config.json").read_text())["data"]
    assert data["mode"] == "online" and data["encoding"] == "rlcard"
    assert data["generator"]["opponent"] == "random" and data["generator"]["generator_steps"] == 128
    reward = load_reward(run)
    assert reward(np.zeros((3, 72), np.uint8), np.array([0, 1, 3])).shape == (3,)
    assert load_policy(run)(torch.zeros(2, 72)).shape == (2, 4)
    card = read_card(run)
    assert card is not None and 0 <= card.agree_expert <= 1
    lines = (run / "metrics.jsonl").read_text().splitlines()
    assert len(lines) == SETTINGS.rounds and "generator_bb_per_hand" in json.loads(lines[0])


def test_the_discriminator_sees_the_generators_engine_states(table: Path) -> None:
    data = read_table(table)
    train, val, _ = data.split(val_fraction=0.1, seed=0)
    reward, policy = default_nets(train, config())
    seed = 7
    generator = EngineGenerator(policy=policy, encoding="rlcard", settings=SETTINGS,  # type: ignore[arg-type]
                                lr=1e-3, seed=seed)  # fmt: skip
    rollouts, seen = [], []
    collect = generator.collect

    def recorded_collect(steps: int):  # type: ignore[no-untyped-def]
        rollouts.append(collect(steps))
        return rollouts[-1]

    def recorded_reward(module: torch.nn.Module, args: tuple) -> None:  # type: ignore[type-arg]
        seen.append(args[0].detach().clone())

    generator.collect = recorded_collect  # type: ignore[method-assign]
    reward.register_forward_pre_hook(recorded_reward)
    trainer = OnlineTrainer(demonstrations=train, validation=val, generator=generator,
                            reward=reward, config=replace(config(), seed=seed),
                            generator_steps=128)  # fmt: skip
    trainer.round()
    rollout = rollouts[0].transitions
    assert len(rollout) == 128
    # Each row holds the generator's own hole cards of the engine's deal of its hand (seat
    # hand % 2): states it reached on the engine, not the expert's.
    hands = np.asarray(rollout.groups)
    deals = deal_cards(seed=seed, start=0, count=int(hands.max()) + 1)[hands]
    seat = hands % 2
    holes = np.stack([deals[np.arange(len(hands)), 2 * seat + k] for k in (0, 1)], axis=1)
    obs = rollout.obs.numpy()
    assert (obs[np.arange(len(hands))[:, None], holes] == 1).all()
    # The discriminator's generator side (every second call of a mini-batch) is these rows.
    generated = {row.tobytes() for row in obs}
    fed = torch.cat(seen[1 : 2 * (128 // 64) : 2]).numpy()
    assert all(row.tobytes() in generated for row in fed)
    assert rollout.dones is not None and bool(rollout.dones[-1])
    assert rollout.legal_mask is not None
    assert rollout.legal_mask[torch.arange(128), rollout.actions].all()  # it plays legal actions


def test_hand_returns_sum_the_rest_of_the_hand() -> None:
    rewards = torch.tensor([1.0, 2.0, 4.0, 8.0])
    dones = torch.tensor([False, True, False, True])
    assert hand_returns(rewards, dones).tolist() == [3.0, 2.0, 12.0, 8.0]


@pytest.mark.parametrize("returns", ["hand", "decision"])
def test_the_generator_learns_what_the_reward_pays(table: Path, returns: str) -> None:
    """A reward paying only for raises: a few rounds of its PPO step raise its raise rate."""
    data = read_table(table)
    _, policy = default_nets(data, config())
    settings = replace(SETTINGS, ppo_epochs=8, returns=returns)
    generator = EngineGenerator(policy=policy, encoding="rlcard", settings=settings,  # type: ignore[arg-type]
                                lr=1e-2, seed=0)  # fmt: skip

    def raise_rate() -> float:
        rollout = generator.collect(512)
        return float((rollout.transitions.actions == 1).float().mean())

    before = raise_rate()
    for _ in range(5):
        rollout = generator.collect(256)
        generator.learn(rollout, (rollout.transitions.actions == 1).float())
    assert raise_rate() > before + 0.2


ERRORS = {
    "online option offline": ("--rounds 3", "--rounds"),
    "bad opponent": ("--mode online --opponent nope", "--opponent"),
    "em rounds online": ("--mode online --em-rounds 1", "--em-rounds"),
    "device online": ("--mode online --device cuda", "--device"),
    "jobs online": ("--mode online --jobs 2", "--jobs"),
}


@pytest.mark.parametrize("case", sorted(ERRORS))
def test_bad_online_options_are_one_usage_line(case: str, table: Path, tmp_path: Path) -> None:
    options, named = ERRORS[case]
    result = CliRunner().invoke(app, ["train", str(table), "--out", str(tmp_path / "o"),
                                      *options.split()])  # fmt: skip
    errors = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(errors) == 1, result.stderr
    assert errors[0].startswith("error: ") and named in errors[0]
    assert not (tmp_path / "o").exists()


def test_the_online_command_writes_a_run(table: Path, tmp_path: Path) -> None:
    out = tmp_path / "cli"
    line = f"train {table} --out {out} --mode online --rounds 1 --generator-steps 64 --epochs 1"
    result = CliRunner().invoke(app, [*line.split(), "--opponent", "tight", "--quiet"])
    assert result.exit_code == 0, result.stderr
    assert "round 1/1" in result.stdout and "vs tight" in result.stdout
    generator = json.loads((out / "config.json").read_text())["data"]["generator"]
    assert generator["opponent"] == "tight" and generator["rounds"] == 1


def test_unknown_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="opponent"):
        PokerOnlineSettings(opponent="nobody")
    with pytest.raises(ValueError, match="returns"):
        PokerOnlineSettings(returns="episode")
    with pytest.raises(ValueError, match="round"):
        PokerOnlineSettings(rounds=0)


def _digests(folder: Path) -> dict[str, str]:
    """sha256 of every file under ``folder`` but the wall-clock timings, by relative path."""
    return {
        p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != "timings.json"
    }


@pytest.mark.slow
@pytest.mark.serial  # kills a process once it reports its first round: run alone
def test_a_killed_online_run_reruns_to_the_uninterrupted_bytes(table: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    line = ["train", str(table), "--out", str(out), "--mode", "online", "--rounds", "4",
            "--generator-steps", "64", "--quiet"]  # fmt: skip
    result = CliRunner().invoke(app, line)
    assert result.exit_code == 0, result.stderr
    reference = _digests(out)
    assert "reward.pt" in reference and "metrics.jsonl" in reference
    shutil.rmtree(out)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}  # each round's line as it is said
    process = subprocess.Popen([sys.executable, "-m", "pokerirl", *line], env=env, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        assert process.stdout is not None
        said = next((text for text in process.stdout if "round 1/4" in text), None)
        process.send_signal(signal.SIGKILL)  # on the event, not after a sleep
    finally:
        process.kill()
        process.wait()
    assert said is not None, "the run never reported its first round"
    assert not out.exists()  # killed mid-run: nothing in place, only its staging beside
    result = CliRunner().invoke(app, line)
    assert result.exit_code == 0, result.stderr
    assert _digests(out) == reference
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # what the kill left, removed


def test_an_online_reward_loads_where_an_offline_one_does(
    run: Path, table: Path, tmp_path: Path
) -> None:
    """``reward-card`` and ``agent train --reward-run`` read an online run as an offline one
    (``load_reward``, ``load_policy`` and the card written at training:
    :func:`test_the_folder_is_offline_trains_and_says_online`)."""
    card = tmp_path / "card"
    result = CliRunner().invoke(app, ["reward-card", str(run), "--table", str(table),
                                      "--out", str(card), "--transform", "advantage"])  # fmt: skip
    assert result.exit_code == 0, result.output
    found = json.loads((card / "reward_card.json").read_text())
    assert 0 <= found["agree_expert"] <= 1 and found["states"] > 0
    agent = tmp_path / "agent"
    result = CliRunner().invoke(app, [
        "agent", "train", "--out", str(agent), "--reward", "learned", "--reward-run", str(run),
        "--hands", "256", "--eval-every", "256", "--eval-hands", "100",
        "--concurrent-hands", "64", "--quiet",
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "vs random" in result.output and (agent / "model.pt").is_file()
