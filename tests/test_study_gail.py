"""GAIL in the poker study (issue 35): an opt-in algorithm beside AIRL and H-AIRL, with its
IRL runs, its DQN agents, its Table 1 row and panel member, and no paper figure invented; a
study of the paper's two algorithms keeps its settings record (and so its bytes)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pokerirl.game.synth import write_synthetic_month
from pokerirl.studies.common import claim_folder
from pokerirl.studies.poker import StudyError, load_study_report, preset, run_study
from pokerirl.studies.poker.config import UNRECORDED_DEFAULTS
from pokerirl.studies.poker.report import render_markdown

TINY = dict(
    runs=1,
    seeds=(0,),
    hands=200,
    panel_hands=100,
    agent_hands=300,
    short_agent_hands=300,
    eval_every=300,
    eval_hands=100,
    irl_epochs=1,
    lbr_hands=0,
    jobs=1,
)


@pytest.mark.slow
def test_a_study_with_gail_reports_it_beside_hairl(tmp_path: Path) -> None:
    month = write_synthetic_month(tmp_path / "irc", hands=400, seed=0)
    out = tmp_path / "out"
    result = run_study([month], out, preset("quick", algos=("gail", "hairl"), **TINY))
    report = result.report
    assert list(report.table1) == ["hairl_dqn_vs_dqn", "gail_dqn_vs_dqn"]
    assert report.table1["gail_dqn_vs_dqn"].paper is None  # the paper has no GAIL
    assert report.table1["hairl_dqn_vs_dqn"].paper is not None
    assert list(report.rl_vs_random.kinds) == ["dqn", "hairl_dqn", "gail_dqn"]
    assert report.rl_vs_random.kinds["gail_dqn"].paper is None
    assert list(report.irl.algos) == ["hairl", "gail"]
    assert report.panel.panel.agents[:3] == ["dqn", "hairl_dqn", "gail_dqn"]
    assert (out / "irl" / "gail" / "reward.pt").is_file()
    assert (out / "agents" / "gail-dqn" / "seed-0").is_dir()
    assert not (out / "irl" / "airl").exists()
    settings = json.loads((out / "study.json").read_text())["settings"]
    assert settings["algos"] == ["hairl", "gail"]  # in one order, whatever order was given
    markdown = (out / "report.md").read_text()
    assert "| GAIL-DQN vs DQN |" in markdown and "| GAIL |" in markdown
    assert "not in the paper" in markdown
    assert render_markdown(load_study_report(out)) == markdown


def test_the_papers_algorithms_keep_the_settings_record_of_before() -> None:
    assert "algos" not in preset("quick").settings()
    assert preset("quick", algos=("hairl", "airl")).settings() == preset("quick").settings()


def test_unknown_or_repeated_algorithms_are_one_line() -> None:
    with pytest.raises(StudyError, match=r"algos among airl, hairl, gail, once each \(got ppo\)"):
        preset("quick", algos=("ppo",))
    with pytest.raises(StudyError, match="once each"):
        preset("quick", algos=("gail", "gail"))
    with pytest.raises(StudyError, match="reward sources for the study's algos"):
        preset("quick", algos=("gail",), reward_sources=(("airl", "authors:x"),))


def test_adding_an_algorithm_to_a_study_folder_is_refused_before_anything_is_written(
    tmp_path: Path,
) -> None:
    """A default study records no ``algos`` (nor ``encoding``, ``folds``): a rerun with GAIL
    is compared with the default all the same, refused in one line before any unit runs (its
    Table 1 would hold another lineup), and taken with ``overwrite``."""
    month = write_synthetic_month(tmp_path / "irc", hands=50, seed=0)
    root = tmp_path / "out"
    claim_folder(root, preset("smoke").settings(), overwrite=False, implied=UNRECORDED_DEFAULTS)
    recorded = (root / "study.json").read_bytes()
    for changed, named in (({"algos": ("airl", "hairl", "gail")}, "algos"),
                           ({"encoding": "strength"}, "encoding")):  # fmt: skip
        with pytest.raises(StudyError, match=rf"other settings \({named} .*nothing was written"):
            run_study([month], root, preset("smoke", **changed))
        assert sorted(p.name for p in root.iterdir()) == ["study.json"]
        assert (root / "study.json").read_bytes() == recorded
    gail = preset("smoke", algos=("airl", "hairl", "gail")).settings()
    claim_folder(root, gail, overwrite=True, implied=UNRECORDED_DEFAULTS)
    assert json.loads((root / "study.json").read_text())["settings"]["algos"][-1] == "gail"
