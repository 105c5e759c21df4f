"""What a tournament's test replicates: one agent per side is a claim about those two agents
(deal seeds only); several agents per side, trained with different seeds, are tested across
training seeds, on real tiny DQNs trained here."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from pokerirl.agents.config import DQNConfig, TrainConfig
from pokerirl.agents.train import train_seeds
from pokerirl.cli import app
from pokerirl.tournaments import load_report, run_tournament
from pokerirl.tournaments.lineup import Group
from pokerirl.tournaments.report import (
    REPORT_FILE,
    Design,
    Line,
    MatchupReport,
    Replication,
    SeedLine,
    compare,
)
from pokerirl.tournaments.stats import across_agents

runner = CliRunner()
HANDS = 2_000
SEEDS = "0-3"
ONE_PAIR_CAVEAT = "about these two agents only"


@pytest.fixture(scope="module")
def agents(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two sets of 3 tiny DQNs (seed-0..2), each trained for 512 hands with its own seed: one
    against random, one against always-call, so the sides differ and so do their seeds."""
    root = tmp_path_factory.mktemp("agents")
    for name, opponent in (("dqn", "random"), ("hairl", "call")):
        dqn = DQNConfig(concurrent_hands=128, hidden=(16,))
        config = TrainConfig(hands=512, seed=0, opponent=opponent, eval_every=512,
                             eval_hands=100, dqn=dqn)  # fmt: skip
        train_seeds(root / name, config, [0, 1, 2])
    return root


def _tournament(*args: str) -> tuple[dict, str]:
    result = runner.invoke(app, ["tournament", *args, "--hands", str(HANDS), "--jobs", "1"])
    assert result.exit_code == 0, result.output
    out = Path(args[args.index("--out") + 1])
    return json.loads((out / REPORT_FILE).read_text()), result.output


def test_one_agent_per_side_prints_the_one_pair_caveat(agents: Path, tmp_path: Path) -> None:
    data, printed = _tournament(str(agents / "hairl" / "seed-0"), str(agents / "dqn" / "seed-0"),
                                "--seeds", SEEDS, "--out", str(tmp_path / "r"))  # fmt: skip
    (comparison,) = data["comparisons"]
    assert comparison["replication"] == Replication.DEAL_SEEDS == "deal seeds only"
    assert (comparison["agents_a"], comparison["agents_b"], comparison["pairs"]) == (1, 1, 1)
    # The verdict is the pooled line over the deal seeds, and the report's first lines say so.
    assert comparison["line"]["std_error"] == data["matchups"][0]["pooled"]["std_error"]
    head = printed.split("## Results")[0]
    assert ONE_PAIR_CAVEAT in head and "**deal seeds only**" in head
    assert "seed-0 1 agent, seed-0 1 agent" in head


def test_three_agents_per_side_are_tested_across_training_seeds(
    agents: Path, tmp_path: Path
) -> None:
    data, printed = _tournament("--cross", str(agents / "hairl"), str(agents / "dqn"),
                                "--seeds", SEEDS, "--out", str(tmp_path / "r"))  # fmt: skip
    (comparison,) = data["comparisons"]
    assert comparison["replication"] == Replication.TRAINING_SEEDS
    assert comparison["design"] == Design.CROSSED
    assert (comparison["agents_a"], comparison["agents_b"], comparison["pairs"]) == (3, 3, 9)
    assert (comparison["agent_a"], comparison["agent_b"]) == ("hairl", "dqn")
    # Every pair played the same deals: the same seeds, all 9 pairs in the one comparison.
    assert comparison["matchups"] == list(range(9))
    assert {tuple(s["seed"] for s in m["seeds"]) for m in data["matchups"]} == {(0, 1, 2, 3)}
    assert data["matchups"][1]["agent_a"] == "hairl/seed-0"
    assert data["matchups"][1]["agent_b"] == "dqn/seed-1"
    # The SE across training seeds is at least the deals' alone on the same games; on agents
    # trained with different seeds it is the spread between them that sets it, not the floor.
    line = comparison["line"]
    assert line["std_error"] >= comparison["deal_std_error"] > 0
    assert comparison["between_std_error"] > comparison["deal_std_error"]
    assert line["std_error"] == comparison["between_std_error"]
    cells = np.array([m["pooled"]["mbb_per_hand"] for m in data["matchups"]]).reshape(3, 3)
    assert line["mbb_per_hand"] == pytest.approx(cells.mean())
    # The one-pair SEs of the same games are the deals' noise only: smaller.
    assert max(m["pooled"]["std_error"] for m in data["matchups"]) < line["std_error"] * 3
    head = printed.split("## Results")[0]
    assert "**training seeds** (hairl 3 agents, dqn 3 agents; 9 pairs" in head
    assert ONE_PAIR_CAVEAT not in head
    assert "## Per agent pair (deal seeds only)" in printed


def test_comma_lists_are_the_cross_form(agents: Path, tmp_path: Path) -> None:
    sides = [",".join(str(agents / name / f"seed-{k}") for k in range(3))
             for name in ("hairl", "dqn")]  # fmt: skip
    listed, _ = _tournament(*sides, "--seeds", "0-1", "--out", str(tmp_path / "list"))
    crossed, _ = _tournament("--cross", str(agents / "hairl"), str(agents / "dqn"),
                             "--seeds", "0-1", "--out", str(tmp_path / "cross"))  # fmt: skip
    assert listed["comparisons"] == crossed["comparisons"]


def test_agent_sets_paired_by_seed_are_independent_pairs(agents: Path, tmp_path: Path) -> None:
    report = run_tournament([(str(agents / "hairl"), str(agents / "dqn")), ("raise", "random")],
                            hands=HANDS, seeds=[0, 1, 2], out=tmp_path / "r")  # fmt: skip
    paired, fixed = report.comparisons
    assert (paired.replication, paired.design) == (Replication.TRAINING_SEEDS, Design.PAIRS)
    assert (paired.agents_a, paired.agents_b, paired.pairs, paired.df) == (3, 3, 3, 2.0)
    assert paired.line.std_error >= paired.deal_std_error
    assert fixed.replication is Replication.DEAL_SEEDS
    # Bonferroni over the two comparisons, as over the two pooled lines.
    assert report.family.comparison_tests == 2
    assert paired.line.p_value_bonferroni == pytest.approx(min(1.0, 2 * paired.line.p_value))


def test_a_report_of_format_1_is_still_read(agents: Path, tmp_path: Path) -> None:
    out = tmp_path / "r"
    report = run_tournament([(str(agents / "hairl"), str(agents / "dqn"))], hands=HANDS,
                            seeds=[0, 1, 2], out=out)  # fmt: skip
    data = json.loads((out / REPORT_FILE).read_text())
    del data["comparisons"], data["family"]["comparison_tests"]
    del data["family"]["comparison_threshold"]
    old = tmp_path / "old"
    shutil.copytree(out, old)
    (old / REPORT_FILE).write_text(json.dumps({**data, "format": "pokerirl-tournament/1"}))
    assert load_report(old).comparisons == report.comparisons
    printed = runner.invoke(app, ["report", str(old)])
    assert printed.exit_code == 0, printed.output
    assert "**training seeds** (hairl 3 agents, dqn 3 agents; 3 pairs" in printed.output


@pytest.mark.parametrize(
    ("sides", "message"),
    [
        (["--cross", "raise,raise", "random"], "the same agent is listed twice on one side"),
        (["{a}/hairl,{a}/dqn/seed-0", "random"], "cannot meet several agents"),
    ],
)
def test_bad_sides_are_one_line_errors(
    agents: Path, tmp_path: Path, sides: list[str], message: str
) -> None:
    args = [side.format(a=agents) for side in sides]
    result = runner.invoke(app, ["tournament", *args, "--hands", "100", "--seeds", "0",
                                 "--out", str(tmp_path / "r"), "--quiet"])  # fmt: skip
    assert result.exit_code == 1, result.output
    assert message in result.output and len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "r").exists()


def test_the_crossed_variance_is_unbiased_and_its_ci_covers() -> None:
    """Random-effects tables, A x B = 3 x 4 with agent, interaction and deal noise: the mean
    of the estimated variance of the grand mean is the true one, and the 95% CI covers."""
    rng = np.random.default_rng(0)
    rows, cols, reps = 3, 4, 3000
    sd_a, sd_b, sd_ab, sd_deal = 20.0, 10.0, 5.0, 2.0
    truth = sd_a**2 / rows + sd_b**2 / cols + (sd_ab**2 + sd_deal**2) / (rows * cols)
    variances, covered = [], 0
    for _ in range(reps):
        noise = rng.normal(0, sd_ab, (rows, cols)) + rng.normal(0, sd_deal, (rows, cols))
        table = rng.normal(0, sd_a, (rows, 1)) + rng.normal(0, sd_b, (1, cols)) + noise
        found = across_agents(table, np.full((rows, cols), sd_deal**2))
        variances.append(found.between_std_error**2)
        low, high = found.estimate.ci95
        covered += low <= 0.0 <= high
    assert np.mean(variances) == pytest.approx(truth, rel=0.08)
    assert 0.92 <= covered / reps <= 0.99


def test_a_shipped_report_of_format_1_reads_as_agent_sets_paired_by_seed() -> None:
    """docs/results' quick study wrote its Table 1 tournament in the /1 format: agent sets of
    4 seeds each, seed k against seed k, so training seeds in independent pairs."""
    folder = Path(__file__).resolve().parents[1] / "docs/results/study-quick-strength/tournament"
    data = json.loads((folder / REPORT_FILE).read_text())
    assert data["format"] == "pokerirl-tournament/1" and "comparisons" not in data
    report = load_report(folder)
    assert len(report.comparisons) == len(report.matchups) == report.family.comparison_tests
    for comparison, matchup in zip(report.comparisons, report.matchups, strict=True):
        assert comparison.replication is Replication.TRAINING_SEEDS
        assert comparison.design is Design.PAIRS
        assert comparison.pairs == comparison.agents_a == len(matchup.seeds)
        assert comparison.line.mbb_per_hand == pytest.approx(matchup.pooled.mbb_per_hand)
        assert comparison.line.std_error >= max(matchup.pooled.std_error,
                                                comparison.deal_std_error)  # fmt: skip


def _line(value: float, **seed: object) -> dict:
    return dict(mbb_per_hand=value, std_error=1.0 + value / 7, ci95=(value - 2, value + 2),
                p_value=0.5, n=10, p_value_bonferroni=1.0, p_value_holm=1.0,
                significant_bonferroni=False, significant_holm=False, **seed)  # fmt: skip


def test_a_comparison_reads_the_same_whatever_the_agents_fingerprints() -> None:
    """The test across training seeds adds the agents' means in the order the matchups list
    them, not by fingerprint: an agent's fingerprint covers its config, which names the run
    it was trained from (a path), so the same study in another folder must give the same
    bytes. Values chosen so that adding them in another order changes the last bits."""
    values = np.array([[0.1, 0.7, 0.3], [1e16, 0.2, 3.3], [0.6, -1e16, 0.9]])

    def matchups(names_a: list[str], names_b: list[str]) -> tuple[MatchupReport, ...]:
        found = []
        for i, j in np.ndindex(values.shape):
            seeds = tuple(SeedLine(**_line(values[i, j] + s, seed=s, hands=100,
                                           fingerprint_a=names_a[i], fingerprint_b=names_b[j]))
                          for s in range(2))  # fmt: skip
            found.append(MatchupReport(agent_a="a", agent_b="b", spec_a=f"a/seed-{i}",
                                       spec_b=f"b/seed-{j}", pooled=Line(**_line(values[i, j])),
                                       pooled_over="seeds", seeds=seeds))  # fmt: skip
        return tuple(found)

    group = [Group(agent_a="a", agent_b="b", matchups=tuple(range(values.size)))]
    ascending = compare(matchups(["1", "2", "3"], ["4", "5", "6"]), group, 0.05)
    descending = compare(matchups(["9", "8", "7"], ["6", "5", "4"]), group, 0.05)
    assert ascending[0].design == Design.CROSSED
    assert ascending == descending
