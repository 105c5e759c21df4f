"""The poker side of reward learning (``pokerirl.poker``): the table as ``Transitions`` and
``pokerirl train``'s errors, which name no flag in the library and read as before on the
command line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.datasets.decisions import Table, read_decisions
from pokerirl.datasets.toy import toy_expert_table
from pokerirl.errors import Remedy
from pokerirl.irl import ConfigError, RunError, Transitions, load_config
from pokerirl.poker import read_table, train_runs, train_table


@pytest.fixture(scope="module")
def table_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("data") / "table.parquet"
    pq.write_table(toy_expert_table(num_hands=60, seed=5), path)
    return path


def test_datasets_reads_numpy_and_poker_makes_the_same_transitions(table_path: Path) -> None:
    decisions = read_decisions(table_path)
    assert isinstance(decisions, Table)
    arrays = [decisions.obs, decisions.action_ids, decisions.legal_mask, decisions.next_obs]
    assert all(isinstance(a, np.ndarray) for a in arrays)  # no torch below irl/
    data = read_table(table_path)
    assert isinstance(data, Transitions) and data.num_actions == 4 and data.obs_dim == 72
    rebuilt = Transitions.from_arrays(
        decisions.obs,
        decisions.action_ids,
        groups=decisions.groups,
        next_obs=decisions.next_obs,
        dones=decisions.dones,
        rewards=decisions.rewards,
        legal_mask=decisions.legal_mask,
    )
    assert data.fingerprint() == rebuilt.fingerprint()
    assert not hasattr(Transitions, "from_table")  # the poker constructor left the generic type


def _train(table: Path, out: Path, *extra: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["train", str(table), "--out", str(out), "--quiet", *extra])
    return result.exit_code, result.stderr


def test_a_finished_folder_is_refused_with_a_remedy_and_the_cli_adds_its_flag(
    table_path: Path, tmp_path: Path
) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "config.json").write_text("{}")
    with pytest.raises(RunError) as refused:
        train_table(table_path, out, progress=False)
    assert str(refused.value) == f"{out} already holds files (a finished run?)"
    assert refused.value.remedy is Remedy.REPLACE
    code, stderr = _train(table_path, out, "--epochs", "1")
    assert (code, stderr) == (
        1,
        f"error: {out} already holds files (a finished run?); pass --overwrite to replace\n",
    )
    with pytest.raises(RunError, match=r"holds a single run, not a folder of 2 runs$") as twice:
        train_runs(table_path, out, runs=2, progress=False)
    assert twice.value.remedy is Remedy.ELSEWHERE
    code, stderr = _train(table_path, out, "--runs", "2")
    assert code == 1 and stderr.endswith("not a folder of 2 runs; choose another --out\n")


def test_an_out_that_is_a_file_is_refused_elsewhere(table_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "file"
    out.write_text("precious")
    for runs in (1, 3):
        with pytest.raises(RunError) as refused:
            train_runs(table_path, out, runs=runs, progress=False)
        assert (str(refused.value), refused.value.remedy) == (
            f"{out} exists and is not a folder",
            Remedy.ELSEWHERE,
        )
        code, stderr = _train(table_path, out, "--runs", str(runs))
        assert (code, stderr) == (
            1,
            f"error: {out} exists and is not a folder; choose another --out\n",
        )
    assert out.read_text() == "precious"


def test_library_messages_name_no_flag(tmp_path: Path) -> None:
    config = tmp_path / "c.toml"
    config.write_text('algo = "airl"\n')
    with pytest.raises(ConfigError) as refused:
        load_config("hairl", config_file=config)
    assert "--" not in str(refused.value) and "'algo'" in str(refused.value)
    with pytest.raises(ValueError, match=r"^runs must be at least 1, got 0$"):
        train_runs(tmp_path / "t.parquet", tmp_path / "out", runs=0)
    code, stderr = _train(tmp_path / "t.parquet", tmp_path / "out", "--runs", "2", "--ray", " ")
    assert (code, stderr) == (2, "error: --ray needs an address (HOST:PORT) or 'local'\n")  # usage


def test_the_bar_moves_after_the_last_epoch_while_the_card_is_drawn(
    table_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run unit's progress ends at TRAINED_SHARE with training and saving; the reward card
    (issue 47: the demo's bar sat at 100% for 26 s at load 12 while cards were drawn) brings
    it to 1."""
    from pokerirl.execution import progress
    from pokerirl.irl import AIRLConfig
    from pokerirl.poker.reward_card import CARD_FILE
    from pokerirl.poker.train import TRAINED_SHARE, train_table_into

    fractions: list[float] = []
    monkeypatch.setattr(progress, "_report", fractions.append)  # as inside a unit
    train_table_into(read_decisions(table_path), tmp_path / "run", algo="airl",
                     config=AIRLConfig(epochs=2),
                     table=table_path)  # fmt: skip
    assert (tmp_path / "run" / CARD_FILE).is_file()
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert fractions[-2] == pytest.approx(TRAINED_SHARE)  # training and saving done, not more


def test_the_table_carries_its_game_and_encoding(table_path: Path) -> None:
    from pokerirl.datasets.decisions import read_data
    from pokerirl.game.encodings import RLCARD
    from pokerirl.game.spec import GameName, holdem_spec

    table = read_data(table_path)
    assert table.spec == holdem_spec(RLCARD)
    assert (table.spec.game, table.spec.encoding, table.spec.width) == (GameName.HOLDEM,
                                                                        "rlcard", 72)  # fmt: skip
    assert table.obs.shape[1] == table.spec.width
    assert table.legal_mask.shape[1] == table.num_actions == 4


def test_several_runs_read_and_encode_the_table_once(
    table_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The driver reads the table once; its arrays go to every unit (issue 42: it was read
    and encoded R + 1 times)."""
    from pokerirl.datasets import decisions

    reads: list[str] = []
    read = decisions.decisions_from_arrow

    def counted(*args: object, **kwargs: object) -> object:
        reads.append(str(kwargs.get("source")))
        return read(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(decisions, "decisions_from_arrow", counted)
    config = load_config("airl", overrides={"epochs": 1, "batch_size": 64})
    train_runs(table_path, tmp_path / "runs", runs=2, config=config, progress=False)
    assert reads == [str(table_path)]
