"""``--log-dir``: every run's scalars as TensorBoard events (read back with TensorBoard's own
reader) and SB3's progress.csv, mirroring the run folders; metrics.jsonl stays the record."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.errors import MissingExtra
from pokerirl.scalars import CSV_FILE, export_scalars


def _events(folder: Path) -> dict[str, list[tuple[int, float]]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(folder))
    events.Reload()
    return {tag: [(e.step, e.value) for e in events.Scalars(tag)]
            for tag in events.Tags()["scalars"]}  # fmt: skip


def _write_run(folder: Path, lines: list[dict[str, object]]) -> None:
    folder.mkdir(parents=True)
    (folder / "metrics.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))


def test_every_run_under_out_is_copied_and_a_rerun_replaces_its_copy(tmp_path: Path) -> None:
    out, logs = tmp_path / "out", tmp_path / "logs"
    epochs = [{"epoch": k, "disc_loss": 1.0 / k, "val_alignment": 0.5 + k / 10} for k in (1, 2)]
    _write_run(out / "run-0", epochs)
    _write_run(out / "run-1", epochs[:1])
    _write_run(out / ".run-2.new-x", epochs)  # a staging folder: not a run
    assert export_scalars(out, logs) == [logs / "run-0", logs / "run-1"]
    rows = list(csv.DictReader((logs / "run-0" / CSV_FILE).open()))
    assert [(r["step"], float(r["disc_loss"])) for r in rows] == [("1", 1.0), ("2", 0.5)]
    assert _events(logs / "run-0")["val_alignment"] == [(1, pytest.approx(0.6)),
                                                        (2, pytest.approx(0.7))]  # fmt: skip
    export_scalars(out, logs)  # again: one copy of each point, not two
    assert len(_events(logs / "run-0")["disc_loss"]) == 2


def test_agent_train_writes_each_seeds_evaluations(tmp_path: Path) -> None:
    args = ["agent", "train", "--out", str(tmp_path / "set"), "--seeds", "0-1", "--hands", "256",
            "--eval-every", "128", "--eval-hands", "50", "--replay-init", "64", "-q",
            "--log-dir", str(tmp_path / "logs")]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "scalars of 2 runs" in result.output
    for seed in (0, 1):
        lines = (tmp_path / "set" / f"seed-{seed}" / "metrics.jsonl").read_text().splitlines()
        found = _events(tmp_path / "logs" / f"seed-{seed}")["eval/random/mbb_per_hand"]
        recorded = [(json.loads(t)["hands"], json.loads(t)["eval"]["random"]["mbb_per_hand"])
                    for t in lines]  # fmt: skip
        assert found == [(hands, pytest.approx(value)) for hands, value in recorded]


def test_without_tensorboard_it_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _write_run(tmp_path / "out", [{"epoch": 1, "loss": 1.0}])
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", None)  # as if not installed
    with pytest.raises(MissingExtra, match=r"pip install 'pokerirl\[logs\]'"):
        export_scalars(tmp_path / "out", tmp_path / "logs")


def test_train_runs_write_their_epochs(tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from pokerirl.datasets.toy import toy_expert_table

    table = tmp_path / "toy.parquet"
    pq.write_table(toy_expert_table(num_hands=100, seed=1, slip=0.1), table)
    args = ["train", str(table), "--algo", "airl", "--runs", "2", "--epochs", "2", "--out",
            str(tmp_path / "runs"), "--quiet", "--log-dir", str(tmp_path / "logs")]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    for run in ("run-0", "run-1"):
        found = _events(tmp_path / "logs" / run)
        assert [step for step, _ in found["val_alignment"]] == [1, 2]
        assert "disc_loss" in found
