"""``pokerirl transfer``: DQNs on each reward transform, judged against the expert rules."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from pokerirl.datasets.ingest import ingest_table
    from pokerirl.game.synth import write_synthetic_month
    from pokerirl.irl import load_config
    from pokerirl.poker import train_table

    root = tmp_path_factory.mktemp("transfer")
    month = write_synthetic_month(root, hands=300, seed=2)
    ingest_table([month], root / "table.parquet")
    config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
    train_table(root / "table.parquet", root / "run", config=config, progress=False)
    return root / "run"


@pytest.mark.slow
def test_transfer_table_has_every_row_and_the_expert_baselines(
    run_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "transfer"
    args = ["transfer", str(run_dir), "--out", str(out), "--transforms", "raw,centered",
            "--payoff-weights", "0,0.5", "--seeds", "0-1", "--hands", "256",
            "--eval-hands", "400", "--jobs", "1", "-q"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    found = json.loads((out / "transfer.json").read_text())
    labels = [row["label"] for row in found["rows"]]
    learned = ["raw", "raw, payoff weight 0.5", "centered", "centered, payoff weight 0.5"]
    fixed = ["tightbot", "loosebot", "always-call", "always-raise"]
    assert labels == ["f argmax", "π greedy", *learned, "sparse DQN", *fixed]
    rows = {row["label"]: row for row in found["rows"]}
    assert found["best"] in learned  # the best transform is a DQN's
    assert [rows[label]["kind"] for label in ("f argmax", "π greedy", "raw", "tightbot")] == [
        "argmax", "policy", "dqn", "fixed"]  # fmt: skip
    # Every row plays each expert bot head to head; a bot against itself is near 0.
    for row in found["rows"]:
        assert set(row["mean_vs_experts"]) == {"tightbot", "loosebot"}
    assert abs(rows["tightbot"]["mean_vs_experts"]["tightbot"]) < 500
    for label in labels[2:7]:
        assert len(rows[label]["vs_random"]) == 2  # one per seed
        shares = rows[label]["mean_action_shares"]
        assert sum(shares.values()) == pytest.approx(1.0)
    # The bots follow their own rule except for their noise; always-call never raises.
    assert 0.9 < rows["tightbot"]["mean_agreement"]["tightbot"] < 1.0
    assert (
        rows["loosebot"]["mean_agreement"]["tightbot"]
        < rows["loosebot"]["mean_agreement"]["loosebot"]
    )
    assert rows["always-call"]["mean_action_shares"]["raise"] == 0.0
    assert rows["always-call"]["mean_agreement"]["legal_majority"] == 1.0
    assert rows["always-raise"]["mean_vs_random"] > rows["always-call"]["mean_vs_random"]
    assert "| sparse DQN |" in (out / "transfer.md").read_text()
    # A rerun reuses the agents (same numbers).
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 0 and json.loads((out / "transfer.json").read_text()) == found
