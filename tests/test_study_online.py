"""The studies' IRL stage trained online (issue 43): ``gym study --mode online`` and
``study --mode online`` run end to end at tiny budgets, say so in their reports and IRL run
folders, and refuse a folder made in the other mode."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from testkit import TINY_GYM_STUDY, Cli, folder_bytes

CLI = Cli()  # pokerirl run in this process (tests/testkit.py)
GYM_ONLINE = ["--mode", "online", "--rounds", "1", "--generator-steps", "64",
              "--generator-envs", "2"]  # fmt: skip


def _modes(irl: Path) -> set[str | None]:
    """The ``data.mode`` of every IRL run folder's config.json under ``irl``."""
    return {json.loads(p.read_text())["data"].get("mode") for p in irl.rglob("config.json")}


@pytest.mark.slow
def test_gym_study_online_end_to_end_and_the_offline_folder_refuses_it(
    mountaincar_study: Path, tmp_path: Path
) -> None:
    pytest.importorskip("stable_baselines3")
    out = tmp_path / "mc"
    shutil.copytree(mountaincar_study, out)  # offline, TINY: its expert data is reused
    refused = CLI("gym", "study", "MountainCar-v0", "--out", out, *TINY_GYM_STUDY, *GYM_ONLINE)
    assert refused.exit_code == 1
    last = refused.output.strip().splitlines()[-1]
    assert last.startswith("error: ") and "mode" in last and "--overwrite" in last, last

    fresh = tmp_path / "online"
    fresh.mkdir()
    shutil.copy2(out / "expert.parquet", fresh)  # the data unit, reused with its record
    shutil.copy2(out / "expert.unit.json", fresh)
    output = CLI.ok("gym", "study", "MountainCar-v0", "--out", fresh, *TINY_GYM_STUDY,
                    *GYM_ONLINE)  # fmt: skip
    report = (fresh / "report.md").read_text()
    assert "IRL online" in report and "1 rounds of 64 generator steps over 2 envs" in report
    assert "IRL online" in output
    summary = json.loads((fresh / "summary.json").read_text())
    assert summary["settings"]["mode"] == "online"
    assert _modes(fresh / "irl") == {"online"}
    for reward in ("env", "airl", "hairl"):  # RL on each reward, as offline
        assert (fresh / "rl" / reward / "run-1" / "metrics.jsonl").is_file()
    # Offline is unchanged: no mode in its summary or its runs.
    assert "mode" not in json.loads((mountaincar_study / "summary.json").read_text())["settings"]
    assert _modes(mountaincar_study / "irl") == {None}


@pytest.fixture(scope="module")
def month(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from pokerirl.game.synth import write_synthetic_month

    return write_synthetic_month(tmp_path_factory.mktemp("irc"), hands=600, seed=0)


POKER_ONLINE = ["--mode", "online", "--rounds", "1", "--generator-steps", "64"]


@pytest.mark.slow
def test_poker_study_online_end_to_end_and_refused_offline(month: Path, tmp_path: Path) -> None:
    out = tmp_path / "study"
    smoke = ["study", month, "--out", out, "--preset", "smoke", "--jobs", "1", "--quiet"]
    output = CLI.ok(*smoke, *POKER_ONLINE)
    report = (out / "report.md").read_text()
    assert "online: 1 rounds of 64 decisions on the engine against random" in report
    assert "runs online" in output
    assert _modes(out / "irl") == {"online"} and len(list(out.rglob("irl/*/run-*"))) == 4
    assert json.loads((out / "study.json").read_text())["settings"]["irl_mode"] == "online"
    for kind in ("airl-dqn", "hairl-dqn"):  # DQNs on the online rewards, as offline
        assert list((out / "agents" / kind).rglob("metrics.jsonl")), kind
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    refused = CLI(*smoke)  # the offline study in the online folder
    assert refused.exit_code == 1
    last = refused.output.strip().splitlines()[-1]
    assert last.startswith("error: ") and "irl_mode" in last and "--overwrite" in last, last
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_offline_study_settings_record_no_mode() -> None:
    from pokerirl.studies.poker import preset

    offline = preset("smoke").settings()
    assert not {"irl_mode", "online_rounds", "online_opponent"} & set(offline)
    online = preset("smoke", irl_mode="online", online_rounds=3).settings()
    assert (online["irl_mode"], online["online_rounds"]) == ("online", 3)
    assert (online["online_generator_steps"], online["online_opponent"]) == (2048, "random")


@pytest.mark.slow
def test_study_game_leduc_is_the_leduc_study(tmp_path: Path) -> None:
    """``study --game leduc`` runs what ``leduc study`` runs: the same files, byte for byte."""
    smoke = ["--preset", "smoke", "--rl", "tabular"]
    CLI.ok("study", "--game", "leduc", "--out", tmp_path / "a", *smoke)
    CLI.ok("leduc", "study", "--out", tmp_path / "b", *smoke)
    found = folder_bytes(tmp_path / "a")
    assert json.loads(found["report.json"])["settings"]["preset"] == "smoke"
    assert found == folder_bytes(tmp_path / "b")
