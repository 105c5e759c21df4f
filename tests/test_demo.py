"""The demo pipeline end to end, at toy sizes."""

from __future__ import annotations

import json
from pathlib import Path

from pokerirl.demo import DemoConfig, run_demo


def test_demo_runs_every_step_and_writes_the_report(tmp_path: Path) -> None:
    said: list[str] = []
    config = DemoConfig(
        synthetic_hands=1_500,
        irl_epochs=1,
        agent_hands=1_000,
        agent_seeds=(0, 1),
        tournament_hands=1_000,
        jobs=1,
    )
    result = run_demo(tmp_path, config, say=said.append)
    assert [line[:5] for line in said] == ["[1/5]", "[2/5]"] + ["[3/5]"] * 2 + ["[4/5]"] * 3 + [
        "[5/5]"
    ]
    assert result.ingest_summary["buckets_add_up"] and result.ingest_summary["kept_hands"] > 0
    assert set(result.irl_alignment) == {"hairl", "airl"}
    for run in result.reward_runs.values():
        assert (run / "reward.pt").is_file() and (run / "config.json").is_file()
    for agent_set in result.agent_sets.values():
        assert sorted(p.name for p in agent_set.iterdir()) == ["seed-0", "seed-1"]
    report = json.loads((result.report_dir / "report.json").read_text())
    matchups = [(m["agent_a"], m["agent_b"]) for m in report["matchups"]]
    assert [(Path(a).name, Path(b).name) for a, b in matchups] == [
        ("hairl-dqn", "dqn"),
        ("airl-dqn", "dqn"),
    ]
    assert (result.report_dir / "report.md").is_file()
    assert len(result.report.matchups) == 2
