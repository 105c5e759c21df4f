"""``pokerirl leduc solve | exploit | agreement`` and the agreement measure they print."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.game.leduc import RLCARD
from pokerirl.game.leduc.exact import (
    agreement,
    best_response_values,
    expected_value,
    reach_probabilities,
)
from pokerirl.game.leduc.strategy import read_strategy, to_json, uniform_strategy


def invoke(*args: str) -> str:
    result = CliRunner().invoke(app, ["leduc", *args])
    assert result.exit_code == 0, result.output
    return result.stdout


@pytest.fixture(scope="module")
def solved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("solve") / "rlcard"
    invoke("solve", "--rules", "rlcard", "-n", "30", "--every", "10", "--out", str(out), "-q")
    return out


def test_solve_writes_its_folder_and_the_same_bytes_again(solved: Path, tmp_path: Path) -> None:
    assert sorted(p.name for p in solved.iterdir()) == [
        "curve.csv", "curve.png", "strategy.json", "summary.json",
    ]  # fmt: skip
    curve = solved.joinpath("curve.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in curve] == ["iteration", "10", "20", "30"]
    summary = json.loads(solved.joinpath("summary.json").read_text())
    assert summary["iterations"] == 30
    assert summary["exploitability_chips"] == pytest.approx(float(curve[-1].split(",")[1]))
    again = tmp_path / "again"
    invoke("solve", "--rules", "rlcard", "-n", "30", "--every", "10", "--out", str(again), "-q")
    for name in ("strategy.json", "curve.csv", "summary.json"):
        assert again.joinpath(name).read_bytes() == solved.joinpath(name).read_bytes(), name


def test_solve_refuses_a_folder_that_holds_anything_unless_overwrite(tmp_path: Path) -> None:
    (tmp_path / "kept.txt").write_text("x")
    result = CliRunner().invoke(app, ["leduc", "solve", "-n", "1", "--out", str(tmp_path)])
    assert result.exit_code == 1 and "is not empty" in result.stderr
    assert "--overwrite" in result.stderr
    invoke("solve", "-n", "1", "--out", str(tmp_path), "--overwrite", "-q")
    assert (tmp_path / "strategy.json").is_file()


def test_exploit_prints_the_exact_figures(solved: Path, tmp_path: Path) -> None:
    rules, strategy = read_strategy(solved / "strategy.json")
    uniform = tmp_path / "uniform.json"
    uniform.write_text(to_json(RLCARD, uniform_strategy(RLCARD)))
    text = invoke("exploit", str(solved / "strategy.json"), "--against", str(uniform))
    first, second = best_response_values(rules, strategy)
    assert f"{(first + second) / 2:.9f} chips per hand" in text
    assert f"{expected_value(rules, strategy, uniform_strategy(RLCARD)).mean:+.9f}" in text


def test_exploit_refuses_strategies_of_other_rules(solved: Path, tmp_path: Path) -> None:
    other = tmp_path / "os"
    invoke("solve", "--rules", "openspiel", "-n", "1", "--out", str(other), "-q")
    result = CliRunner().invoke(
        app, ["leduc", "exploit", str(solved / "strategy.json"), "--against",
              str(other / "strategy.json")],
    )  # fmt: skip
    assert result.exit_code == 1 and "openspiel rules, not rlcard" in result.stderr


def test_agreement_counts_argmax_matches_uniformly_and_by_reach(solved: Path) -> None:
    _, strategy = read_strategy(solved / "strategy.json")
    assert agreement(RLCARD, strategy, strategy).uniform == 1.0
    # Flip the argmax at one information set: one of 288 sets, weighted by its reach.
    key = "K:"
    flipped = {**strategy, key: {"fold": 1.0, "call": 0.0, "raise": 0.0}}
    if max(strategy[key], key=strategy[key].__getitem__) == "fold":
        flipped[key] = {"fold": 0.0, "call": 1.0, "raise": 0.0}
    found = agreement(RLCARD, flipped, strategy)
    reach = reach_probabilities(RLCARD, strategy)
    assert found.information_sets == 288
    assert found.uniform == pytest.approx(1 - 1 / 288)
    assert found.reached == pytest.approx(1 - reach[key] / sum(reach.values()))
    assert reach[key] == pytest.approx(1 / 3)  # a king, dealt first: chance alone
    text = invoke("agreement", str(solved / "strategy.json"), str(solved / "strategy.json"))
    assert "1.0000 uniform, 1.0000 weighted by B's reach" in text
