"""The demo: the study on synthetic data, end to end at toy sizes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pokerirl.studies.demo import DemoConfig, run_demo
from pokerirl.studies.poker import preset


@pytest.mark.slow
def test_demo_is_the_study_on_synthetic_data(tmp_path: Path) -> None:
    study = preset(
        "quick", runs=2, seeds=(0, 1), hands=200, panel_hands=100, agent_hands=400,
        short_agent_hands=200, eval_every=200, eval_hands=100, irl_epochs=1,
    )  # fmt: skip
    config = DemoConfig(synthetic_hands=500, jobs=1, study=study)
    said: list[str] = []
    result = run_demo(tmp_path, config, say=said.append)
    assert said[0].startswith("synth: 500 heads-up hands")
    report = json.loads((tmp_path / "report.json").read_text())
    assert report == result.report.to_json() and result.report.preset == "quick"
    assert report["seeds"] == [0, 1]
    assert (tmp_path / "report.md").read_text() == result.markdown
    # A rerun reuses the synthetic month, so every unit is reused: nothing written again.
    units = {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*")
             if p.suffix in (".pt", ".parquet") or p.name.endswith("unit.json")}  # fmt: skip
    said.clear()
    run_demo(tmp_path, config, say=said.append)
    assert "      the table is finished already, reused" in said
    assert {p: p.stat().st_mtime_ns for p in units} == units
