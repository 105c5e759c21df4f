"""The game and the encoding travel with the data (issue 42, item 0): ``pokerirl train`` on
Leduc demonstrations trains through the same ``train_runs_into`` as a hold'em table, records
the game in the run, and the commands that read hold'em states refuse that run in one line
naming the game."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.datasets.decisions import read_data
from pokerirl.datasets.toy import toy_expert_table
from pokerirl.errors import InputError
from pokerirl.game.encodings import STRENGTH
from pokerirl.game.leduc import RLCARD, uniform_strategy
from pokerirl.game.leduc.demos import save, synthesize
from pokerirl.game.spec import LEDUC, GameName

EPOCHS = ["--epochs", "1", "--batch-size", "64"]


@pytest.fixture(scope="module")
def demos_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("leduc") / "demos.npz"
    save(synthesize(RLCARD, uniform_strategy(RLCARD), hands=300, seed=0), path)
    return path


@pytest.fixture(scope="module")
def leduc_run(demos_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs") / "leduc-airl"
    result = CliRunner().invoke(
        app, ["train", str(demos_path), "--out", str(out), "--algo", "airl", "--quiet", *EPOCHS]
    )
    assert result.exit_code == 0, result.output
    return out


def test_leduc_demonstrations_read_as_a_table_of_their_game(demos_path: Path) -> None:
    table = read_data(demos_path)
    assert table.spec is LEDUC and table.spec.game is GameName.LEDUC
    assert table.obs.shape[1] == LEDUC.width == 36 and table.num_actions == 4
    assert table.legal_mask.shape == (len(table.obs), 4) and table.dones is not None
    with pytest.raises(InputError, match=r"demos\.npz: Leduc demonstrations are in their one "
                       r"encoding \(leduc-rlcard\), not strength-v2$"):  # fmt: skip
        read_data(demos_path, encoding=STRENGTH)


def test_a_leduc_run_records_its_game_and_its_reward_loads(
    leduc_run: Path, demos_path: Path
) -> None:
    from pokerirl.irl import load_reward

    record = json.loads((leduc_run / "config.json").read_text())
    assert record["data"]["game"] == "leduc" and record["data"]["encoding"] == "leduc-rlcard"
    assert record["data"]["path"] == str(demos_path.resolve())
    assert record["architecture"]["obs_dim"] == 36
    assert record["architecture"]["action_space"] == {"type": "discrete", "num_actions": 4}
    assert not (leduc_run / "reward_card.json").exists()  # a card is of hold'em states
    table = read_data(demos_path)
    values = load_reward(leduc_run)(table.obs[:5], table.action_ids[:5])
    assert values.shape == (5,) and np.isfinite(values).all()


def test_several_leduc_runs_train_as_units_recording_the_game(
    demos_path: Path, tmp_path: Path
) -> None:
    from pokerirl.irl import AIRLConfig
    from pokerirl.poker import train_runs

    config = AIRLConfig.for_algo("gail", epochs=1, batch_size=64)
    summary = train_runs(demos_path, tmp_path / "runs", runs=2, algo="gail", config=config,
                         progress=False)  # fmt: skip
    assert len(summary.results) == 2
    for k in range(2):
        record = json.loads((tmp_path / "runs" / f"run-{k}" / "config.json").read_text())
        assert record["data"]["game"] == "leduc"


def test_a_holdem_run_records_no_game(tmp_path: Path) -> None:
    """Hold'em runs keep their config.json: the game key is only for another game."""
    pq.write_table(toy_expert_table(num_hands=60, seed=5), tmp_path / "t.parquet")
    out = tmp_path / "run"
    result = CliRunner().invoke(
        app, ["train", str(tmp_path / "t.parquet"), "--out", str(out), "--quiet", *EPOCHS]
    )
    assert result.exit_code == 0, result.output
    data = json.loads((out / "config.json").read_text())["data"]
    assert "game" not in data and data["encoding"] == "rlcard"


@pytest.mark.parametrize(
    "command",
    [
        ["reward-card", "{run}"],
        ["agent", "train", "--out", "{tmp}/agent", "--reward", "learned", "--reward-run", "{run}",
         "--hands", "10"],
        ["transfer", "{run}", "--out", "{tmp}/transfer"],
    ],
    ids=["reward-card", "agent-train", "transfer"],
)
def test_holdem_commands_refuse_a_leduc_run_in_one_line(
    command: list[str], leduc_run: Path, tmp_path: Path
) -> None:
    args = [a.format(run=leduc_run, tmp=tmp_path) for a in command]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1 and len(result.stderr.splitlines()) == 1
    assert result.stderr.startswith(  # reward-card goes on to name the Leduc commands
        f"error: {leduc_run}: a reward learned on the game 'leduc', not on heads-up limit "
        "hold'em"
    )


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--encoding", "strength"],
         "Leduc demonstrations are in their one encoding (leduc-rlcard), not strength-v2"),
        (["--em-rounds", "1"],
         "EM re-imputes the hidden cards of a hold'em table, not Leduc demonstrations"),
    ],
    ids=["encoding", "em"],
)  # fmt: skip
def test_train_refuses_what_leduc_demonstrations_cannot_give_in_one_line(
    extra: list[str], says: str, demos_path: Path, tmp_path: Path
) -> None:
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["train", str(demos_path), "--out", str(out), *extra])
    assert (result.exit_code, result.stderr) == (1, f"error: {demos_path}: {says}\n")
    assert not out.exists()
