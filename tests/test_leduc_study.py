"""The Leduc pipeline: the tabular agent (pokerirl/agents/leduc_q.py) learns what its reward
asks against a fixed strategy, and the smoke study (pokerirl/studies/leduc/, DQN agents)
writes its report and reproduces its bytes (the DQN itself: tests/test_leduc_dqn.py)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from pokerirl.agents.leduc_q import QConfig, train_q
from pokerirl.cli import app
from pokerirl.game.leduc import RLCARD, CFRPlus, expected_value
from pokerirl.game.leduc.batch import ACTIONS
from pokerirl.game.leduc.infosets import info_sets, pure
from pokerirl.game.leduc.rules import Action
from pokerirl.game.leduc.strategy import to_json


def test_the_sparse_reward_beats_a_calling_station() -> None:
    # Always call (check when nothing is faced): a best response wins 1.47 chips per hand.
    # Reward sign or seats wrong, and the agent learns to lose.
    caller = pure(RLCARD, {Action.CALL: 2, Action.CHECK: 1})
    agent = train_q(RLCARD, caller, config=QConfig(hands=20_000, seed=0))
    assert expected_value(RLCARD, agent.strategy(), caller).mean > 1.0


def test_a_per_decision_reward_is_followed() -> None:
    # A reward that pays for raising and nothing else: the agent raises wherever it may at
    # the sets it visited (the return is the sum of the rewards from a decision on).
    sets = info_sets(RLCARD)
    reward = np.zeros(sets.legal.shape)
    reward[:, ACTIONS.index(Action.RAISE)] = 1.0
    caller = pure(RLCARD, {Action.CALL: 2, Action.CHECK: 1})
    agent = train_q(RLCARD, caller, config=QConfig(hands=20_000, seed=1), reward=reward)
    visited = agent.visits.sum(axis=1) > 0
    can_raise = sets.legal[:, ACTIONS.index(Action.RAISE)]
    chosen = np.where(sets.legal, np.where(agent.visits > 0, agent.q, 0), -np.inf).argmax(1)
    assert (visited & can_raise).sum() >= 20  # ε explores beyond its own raises
    assert (chosen[visited & can_raise] == ACTIONS.index(Action.RAISE)).all()


@pytest.fixture(scope="module")
def expert(tmp_path_factory: pytest.TempPathFactory) -> Path:
    solver = CFRPlus(RLCARD)
    solver.run(10, every=10)
    path = tmp_path_factory.mktemp("expert") / "strategy.json"
    path.write_text(to_json(RLCARD, solver.average()))
    return path


def test_the_smoke_study_writes_its_report_and_reproduces_it(expert: Path, tmp_path: Path) -> None:
    outs = [tmp_path / "a", tmp_path / "b"]
    for out in outs:
        result = CliRunner().invoke(app, ["leduc", "study", "--preset", "smoke", "--out",
                                          str(out), "--expert", str(expert)])  # fmt: skip
        assert result.exit_code == 0, result.output
        assert "irl: hairl" in result.output
    for name in ("report.md", "report.json", "agreement.png", "demos.npz", "study.json"):
        assert (outs[0] / name).is_file(), name
    first = (outs[0] / "report.json").read_bytes()
    assert first == (outs[1] / "report.json").read_bytes()
    report = json.loads(first)
    assert set(report["learners"]) == {"airl", "hairl", "gail", "bc"}
    assert set(report["rl"]) == {"sparse", "airl", "hairl", "gail"}
    assert report["learners"]["hairl"]["summary"]["policy_agreement.reached"]["n"] == 2
    assert report["rl"]["sparse"]["summary"]["ev_vs_sparse"]["mean"] == 0  # itself
    assert report["settings"]["rl"] == report["rl_agent"]["kind"] == "dqn"  # the default
    assert (outs[0] / "report.md").read_text().startswith("# Leduc study")
    # A rerun resumes: nothing is trained again, the report is the same.
    result = CliRunner().invoke(app, ["leduc", "study", "--preset", "smoke", "--out",
                                      str(outs[0]), "--expert", str(expert)])  # fmt: skip
    assert result.exit_code == 0 and "irl:" not in result.output, result.output
    assert (outs[0] / "report.json").read_bytes() == first
    # The RL agents are a setting of the folder; tabular ones on the same IRL stage files.
    tabular = ["leduc", "study", "--preset", "smoke", "--rl", "tabular", "--expert", str(expert)]
    result = CliRunner().invoke(app, [*tabular, "--out", str(outs[0])])
    assert result.exit_code == 1, result.output
    (tmp_path / "c" / "irl").mkdir(parents=True)
    shutil.copy(outs[0] / "demos.npz", tmp_path / "c")
    for path in (outs[0] / "irl").iterdir():
        shutil.copy(path, tmp_path / "c" / "irl")
    result = CliRunner().invoke(app, [*tabular, "--out", str(tmp_path / "c")])
    assert result.exit_code == 0 and "irl:" not in result.output, result.output
    assert "rl: tabular on the gail reward, seed 1" in result.output
    report = json.loads((tmp_path / "c" / "report.json").read_text())
    assert report["rl_agent"]["kind"] == "tabular" and report["learners"] == json.loads(
        first)["learners"]
