"""Running tournaments: agreement with play_match, duplicate mirrors, the pooled test and the
correction families, reproducibility across processes, resuming, and bad input."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from pokerirl.errors import Remedy
from pokerirl.game import make_agent, play_match
from pokerirl.tournaments import (
    TournamentError,
    TournamentReport,
    bonferroni,
    holm,
    load_report,
    run_tournament,
)
from pokerirl.tournaments.report import FamilySizes, TournamentSettings

HANDS = 2_000


def _numbers(report: TournamentReport) -> list[tuple[float, float, float]]:
    return [(s.mbb_per_hand, s.std_error, s.p_value) for m in report.matchups for s in m.seeds]


@pytest.mark.parametrize("duplicate", [True, False])
def test_each_seed_is_play_match_with_that_seed(tmp_path: Path, duplicate: bool) -> None:
    report = run_tournament(
        [("raise", "random")], hands=HANDS, seeds=[3, 5], out=tmp_path, duplicate=duplicate
    )
    for line in report.matchups[0].seeds:
        match = play_match(
            make_agent("raise"),
            make_agent("random"),
            hands=HANDS,
            seed=line.seed,
            duplicate=duplicate,
        )
        assert line.mbb_per_hand == pytest.approx(match.mbb_per_hand, rel=1e-12)
        assert line.std_error == pytest.approx(match.std_error, rel=1e-9)
        assert line.n == (HANDS // 2 if duplicate else HANDS)
        assert line.fingerprint_a == "builtin:raise"


def test_a_deterministic_agent_against_itself_is_exactly_even(tmp_path: Path) -> None:
    report = run_tournament(
        [("raise", "raise"), ("call", "call")], hands=HANDS, seeds=range(3), out=tmp_path
    )
    for m in report.matchups:
        assert [s.mbb_per_hand for s in m.seeds] == [0.0, 0.0, 0.0]
        assert (m.pooled.mbb_per_hand, m.pooled.std_error, m.pooled.p_value) == (0.0, 0.0, 1.0)
    # Without duplicate the deals differ between seats, so the result is not zero.
    alternating = run_tournament(
        [("raise", "raise")], hands=HANDS, seeds=[0], out=tmp_path / "alt", duplicate=False
    )
    assert alternating.matchups[0].seeds[0].mbb_per_hand != 0.0


def test_pooled_test_is_over_seed_means_and_families_are_corrected(tmp_path: Path) -> None:
    seeds = [0, 1, 2, 3]
    report = run_tournament(
        [("call", "random"), ("random", "random")], hands=HANDS, seeds=seeds, out=tmp_path
    )
    for m in report.matchups:
        means = np.array([s.mbb_per_hand for s in m.seeds])
        reference = stats.ttest_1samp(means, 0.0)
        assert m.pooled.n == len(seeds) and m.pooled_over == "seeds"
        assert m.pooled.mbb_per_hand == pytest.approx(means.mean(), rel=1e-12)
        assert m.pooled.std_error == pytest.approx(means.std(ddof=1) / 2, rel=1e-12)
        assert m.pooled.p_value == pytest.approx(reference.pvalue, rel=1e-9)
    lines = [s for m in report.matchups for s in m.seeds]
    p = [s.p_value for s in lines]
    assert report.family.per_seed_tests == len(lines) == 8
    assert report.family.per_seed_threshold == pytest.approx(0.05 / 8)
    np.testing.assert_allclose([s.p_value_bonferroni for s in lines], bonferroni(p))
    np.testing.assert_allclose([s.p_value_holm for s in lines], holm(p))
    assert [s.significant_bonferroni for s in lines] == [x < 0.05 / 8 for x in p]
    pooled = [m.pooled for m in report.matchups]
    assert report.family.pooled_tests == 2
    np.testing.assert_allclose(
        [x.p_value_bonferroni for x in pooled], bonferroni([x.p_value for x in pooled])
    )
    assert load_report(tmp_path) == report  # report.json holds every number exactly
    # call beats random by about 1.2 bb/h, 80 standard errors on every seed.
    assert report.matchups[0].pooled.significant_bonferroni
    assert report.matchups[0].seeds_significant_bonferroni == 4


def test_one_seed_pools_over_its_own_units(tmp_path: Path) -> None:
    m = run_tournament([("call", "random")], hands=HANDS, seeds=[2], out=tmp_path).matchups[0]
    assert m.pooled_over == "units of the only seed"
    assert (m.pooled.mbb_per_hand, m.pooled.p_value, m.pooled.n) == (
        m.seeds[0].mbb_per_hand,
        m.seeds[0].p_value,
        HANDS // 2,
    )


def test_same_seeds_same_numbers_whatever_the_number_of_processes(tmp_path: Path) -> None:
    matchups = [("random", "call"), ("random", "raise")]
    one = run_tournament(matchups, hands=HANDS, seeds=range(3), out=tmp_path / "one", jobs=1)
    two = run_tournament(matchups, hands=HANDS, seeds=range(3), out=tmp_path / "two", jobs=2)
    assert _numbers(one) == _numbers(two)
    assert one.family == two.family
    assert len(set(_numbers(one))) == 6  # every seed and matchup is different


def test_rerun_reuses_saved_seeds(tmp_path: Path) -> None:
    first = run_tournament([("call", "random")], hands=HANDS, seeds=[0, 1], out=tmp_path)
    saved = tmp_path / "seeds" / "call-vs-random" / "seed-1.json"
    data = json.loads(saved.read_text())
    # Proof that a rerun reads the file rather than replaying: it reports what the file says.
    data["result"]["estimate"]["mbb_per_hand"] = 123.25
    saved.write_text(json.dumps(data))
    again = run_tournament([("call", "random")], hands=HANDS, seeds=[0, 1, 2], out=tmp_path)
    assert again.timing["seeds_reused"] == 2 and again.timing["hands_played"] == HANDS
    assert _numbers(again)[0] == _numbers(first)[0]
    assert again.matchups[0].seeds[1].mbb_per_hand == 123.25
    assert not list(tmp_path.rglob("*.tmp"))  # atomic writes leave no temp files


def test_rerun_with_another_config_refuses_unless_overwrite(tmp_path: Path) -> None:
    run_tournament([("call", "random")], hands=HANDS, seeds=[0], out=tmp_path)
    # The library names the change and how to get past it (a Remedy), never a flag: the
    # command line adds its own words.
    with pytest.raises(TournamentError, match=r"\(hands 2000 -> 4000\)$") as refused:
        run_tournament([("call", "random")], hands=2 * HANDS, seeds=[0], out=tmp_path)
    assert refused.value.remedy is Remedy.RECOMPUTE
    with pytest.raises(TournamentError, match="duplicate True -> False"):
        run_tournament([("call", "random")], hands=HANDS, seeds=[0], out=tmp_path, duplicate=False)
    redone = run_tournament(
        [("call", "random")], hands=2 * HANDS, seeds=[0], out=tmp_path, overwrite=True
    )
    assert redone.timing["seeds_reused"] == 0 and redone.matchups[0].seeds[0].n == HANDS


@pytest.mark.parametrize("damage", ["{not json", "[]", '"a string"', '{"format": 1}', ""])
def test_a_corrupt_saved_seed_is_recomputed(tmp_path: Path, damage: str) -> None:
    first = run_tournament([("call", "random")], hands=HANDS, seeds=[0, 1], out=tmp_path)
    saved = tmp_path / "seeds" / "call-vs-random" / "seed-0.json"

    intact = saved.read_bytes()  # no timings in it: a recomputed seed has the same bytes
    saved.write_text(damage)  # an atomic write never leaves this: damage, so recompute
    again = run_tournament([("call", "random")], hands=HANDS, seeds=[0, 1], out=tmp_path)
    assert again.timing["seeds_reused"] == 1 and _numbers(again) == _numbers(first)
    assert saved.read_bytes() == intact


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"hands": 0}, "hands must be at least 4"),
        ({"hands": 1001}, "hands must be even"),
        ({"hands": 1, "duplicate": False}, "hands must be at least 2"),
        ({"seeds": []}, "seed range is empty"),
        ({"seeds": [-1]}, "non-negative"),
        ({"matchups": [("nobody", "call")]}, "nobody: no such agent folder"),
        ({"matchups": [("call", "raise"), ("call", "raise")]}, "listed twice"),
        ({"jobs": 0}, "jobs must be at least 1"),
        ({"alpha": 1.5}, "alpha must be between 0 and 1"),
    ],
)
def test_bad_input_is_one_clear_error(tmp_path: Path, kwargs: dict, message: str) -> None:
    arguments = {"matchups": [("call", "raise")], "hands": 100, "seeds": [0], "out": tmp_path}
    with pytest.raises(TournamentError, match=message) as error:
        run_tournament(**{**arguments, **kwargs})
    assert "\n" not in str(error.value)
    assert not (tmp_path / "report.json").exists()


def test_agent_set_missing_a_seed_is_refused_before_anything_loads(tmp_path: Path) -> None:
    agent_set = tmp_path / "dqn"
    for k in (0, 1, 3):
        (agent_set / f"seed-{k}").mkdir(parents=True)
    with pytest.raises(TournamentError, match=r"agent set .*dqn has no seed-2 folder.*0-1,3"):
        run_tournament([(str(agent_set), "call")], hands=100, seeds=range(4), out=tmp_path / "r")
    a_file = tmp_path / "weights.pt"
    a_file.write_bytes(b"")
    with pytest.raises(TournamentError, match="not an agent folder"):
        run_tournament([(str(a_file), "call")], hands=100, seeds=[0], out=tmp_path / "r")


@pytest.mark.slow
def test_a_killed_run_leaves_whole_seed_files_and_resumes(tmp_path: Path) -> None:
    args = ["call", "random", "--hands", "100000", "--seeds", "0-39", "--jobs", "1"]
    command = [sys.executable, "-m", "pokerirl", "tournament", *args, "--out", str(tmp_path), "-q"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    folder = tmp_path / "seeds" / "call-vs-random"
    deadline = time.monotonic() + 60
    while not (folder.exists() and list(folder.glob("seed-*.json"))):
        assert process.poll() is None and time.monotonic() < deadline
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    saved = {
        int(path.stem.removeprefix("seed-")): json.loads(path.read_text())  # whole JSON files
        for path in folder.glob("seed-*.json")
    }
    assert 1 <= len(saved) < 40 and not (tmp_path / "report.json").exists()
    seeds = range(max(saved) + 2)  # the saved seeds, any gaps, and one more
    resumed = run_tournament([("call", "random")], hands=100_000, seeds=seeds, out=tmp_path)
    assert resumed.timing["seeds_reused"] == len(saved)
    for line in resumed.matchups[0].seeds:
        if line.seed in saved:
            assert saved[line.seed]["result"]["estimate"]["mbb_per_hand"] == line.mbb_per_hand


def test_the_report_reads_back_typed_and_writes_the_same_bytes(tmp_path: Path) -> None:
    report = run_tournament([("raise", "random")], hands=200, seeds=[1, 2], out=tmp_path)
    assert report.config == TournamentSettings(
        hands=200, seeds=(1, 2), duplicate=True, batch_size=report.config.batch_size, alpha=0.05
    )
    assert report.family == FamilySizes(
        per_seed_tests=2, per_seed_threshold=0.025, pooled_tests=1, pooled_threshold=0.05,
        comparison_tests=1, comparison_threshold=0.05,
    )  # fmt: skip
    text = (tmp_path / "report.json").read_text()
    data = json.loads(text)
    assert list(data["config"]) == ["hands", "seeds", "duplicate", "batch_size", "alpha"]
    assert TournamentSettings.from_json(data["config"]).to_json() == data["config"]
    assert FamilySizes.from_json(data["family"]).to_json() == data["family"]
    loaded = load_report(tmp_path)
    assert (loaded.config, loaded.family) == (report.config, report.family)
    assert json.dumps(loaded.to_json(), indent=2) + "\n" == text
