"""The typed results of agent training: metrics lines, scores and timings, as JSON and back."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from pokerirl.agents.dqn import DQNConfig
from pokerirl.agents.train import (
    Evaluation,
    MetricsLine,
    Score,
    Timings,
    TrainConfig,
    agent_preset,
    train_agent,
)

torch.set_num_threads(1)

# Lines as main's train_agent wrote them (key order included): ours, and the authors' protocol.
OURS = (
    '{"hands": 512, "transitions": 1890, "updates": 0, "epsilon": 0.9, "loss": null, '
    '"eval": {"random": {"mbb_per_hand": 1234.5, "std_error": 88.25}, '
    '"call": {"mbb_per_hand": -12.0, "std_error": 3.5}}}'
)
AUTHORS = (
    '{"hands": 101, "transitions": 377, "updates": 345, "epsilon": 0.0, "loss": 0.25, '
    '"eval": {"random": {"mbb_per_hand": 500.0, "std_error": 10.0}}, "keep_rule": true}'
)


@pytest.mark.parametrize("line", [OURS, AUTHORS])
def test_a_metrics_line_round_trips_to_the_same_bytes(line: str) -> None:
    typed = MetricsLine.from_json(json.loads(line))
    assert json.dumps(typed.to_json()) == line
    assert MetricsLine.from_json(typed.to_json()) == typed


def test_a_metrics_line_is_typed() -> None:
    typed = MetricsLine.from_json(json.loads(AUTHORS))
    assert typed.eval["random"] == Score(mbb_per_hand=500.0, std_error=10.0)
    assert typed.keep_rule is True and typed.loss == 0.25
    assert MetricsLine.from_json(json.loads(OURS)).keep_rule is None


def test_timings_round_trip() -> None:
    evaluations = [{"hands": 1, "seconds": 0.5}]
    data = {"seconds": 3.5, "hands_per_second": 146.3, "evaluations": evaluations}
    assert Timings.from_json(data).to_json() == data
    assert Timings.from_json(data).evaluations == (Evaluation(hands=1, seconds=0.5),)


@pytest.mark.parametrize("protocol", ["pokerirl", "authors"])
def test_the_files_written_read_back_typed(tmp_path: Path, protocol: str) -> None:
    if protocol == "authors":
        config = agent_preset("authors", hands=250, eval_every=100, eval_hands=50, seed=1)
    else:
        config = TrainConfig(
            hands=256, seed=0, eval_every=128, eval_hands=100, opponent="call",
            dqn=DQNConfig(concurrent_hands=64, hidden=(8,)),
        )  # fmt: skip
    typed = train_agent(tmp_path / "agent", config)
    assert isinstance(typed, MetricsLine)
    text = (tmp_path / "agent" / "metrics.jsonl").read_text()
    lines = [MetricsLine.from_json(json.loads(line)) for line in text.splitlines()]
    assert "".join(json.dumps(line.to_json()) + "\n" for line in lines) == text
    record = json.loads((tmp_path / "agent" / "config.json").read_text())
    assert record["final"] == typed.to_json() == lines[-1].to_json()
    if protocol == "authors":
        assert record["kept"] is not None and MetricsLine.from_json(record["kept"]) in lines
        assert [line.keep_rule for line in lines] == [True, True, True, False]
    timings = json.loads((tmp_path / "agent" / "timings.json").read_text())
    assert Timings.from_json(timings).to_json() == timings
    assert [e.hands for e in Timings.from_json(timings).evaluations] == [m.hands for m in lines]
    # A rerun reuses the agent.
    assert train_agent(tmp_path / "agent", config) is None
