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


def test_the_demo_defaults_are_the_demo_presets_smaller_than_quick() -> None:
    from pokerirl.studies.gym.config import PRESETS as GYM_PRESETS
    from pokerirl.studies.poker import PRESETS

    config = DemoConfig()
    assert config.study == PRESETS["demo"] and config.gym == GYM_PRESETS["demo"]
    demo, quick = PRESETS["demo"], PRESETS["quick"]
    # The quick preset's IRL and training length; fewer seeds and hands played.
    assert (demo.runs, demo.irl_epochs, demo.agent_hands) == (
        quick.runs, quick.irl_epochs, quick.agent_hands)  # fmt: skip
    assert len(demo.seeds) < len(quick.seeds) and demo.hands < quick.hands
    assert demo.panel_hands < quick.panel_hands and 0 < demo.lbr_hands < quick.lbr_hands
    gym, gym_quick = GYM_PRESETS["demo"], GYM_PRESETS["quick"]
    env = "MountainCar-v0"
    assert gym.tasks == (env,) and gym.irl(env) == gym_quick.irl(env)
    assert gym.rl(env).dqn == gym_quick.rl(env).dqn
    assert gym.rl(env).timesteps < gym_quick.rl(env).timesteps and gym.runs < gym_quick.runs


def test_the_demo_command_prints_the_poker_report_before_the_gym_half_starts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("gymnasium")
    pytest.importorskip("stable_baselines3")
    from types import SimpleNamespace

    import typer
    from typer.testing import CliRunner

    from pokerirl.cli import app
    from pokerirl.studies import demo

    seen: list[DemoConfig] = []

    def poker(out: Path, config: DemoConfig, **options: object) -> SimpleNamespace:
        seen.append(config)
        below = SimpleNamespace(below_bc=2)  # the reward cards of a demo that saw the warning
        report = SimpleNamespace(reward_cards={"airl": below, "hairl": None})
        return SimpleNamespace(markdown="# THE POKER REPORT", report=report)

    def gym(out: Path, config: DemoConfig, **options: object) -> SimpleNamespace:
        seen.append(config)
        typer.echo("THE GYM HALF STARTS")
        return SimpleNamespace(markdown="# THE GYM REPORT")

    monkeypatch.setattr(demo, "run_demo", poker)
    monkeypatch.setattr(demo, "run_gym_demo", gym)
    result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path), "-q"])
    assert result.exit_code == 0, result.output
    text = result.output
    order = ["# THE POKER REPORT", "gym: the demo study on MountainCar-v0",
             "THE GYM HALF STARTS", "# THE GYM REPORT", "demo: done"]  # fmt: skip
    assert [text.index(line) for line in order] == sorted(text.index(line) for line in order)
    # The closing lines: both reports, the expected warning explained, real hands next.
    last = text.rstrip().splitlines()[-3:]
    assert last[0] == f"demo: done; the reports are {tmp_path / 'report.md'} and " + str(
        tmp_path / "gym" / "report.md")
    assert last[1].startswith("note: 2 learned rewards agree with the expert less than "
                              "behaviour cloning: expected on the demo's synthetic month")
    assert "irc-199504" in last[2]
    assert seen == [DemoConfig(), DemoConfig()]  # the command's defaults are the demo presets


def test_the_demo_explains_the_warning_it_expects_and_keeps_the_others(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import warnings
    from types import SimpleNamespace

    from pokerirl.poker.train import RewardBelowBC
    from pokerirl.studies import demo

    def study(*args: object, **options: object) -> SimpleNamespace:
        for run in ("run-0", "run-1"):
            warnings.warn(RewardBelowBC(f"{run}: below BC"), stacklevel=1)
        warnings.warn("something else", UserWarning, stacklevel=1)
        return SimpleNamespace(markdown="# R")

    monkeypatch.setattr(demo, "run_study", study)
    said: list[str] = []
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        demo.run_demo(tmp_path, DemoConfig(synthetic_hands=50), say=said.append)
    assert [str(w.message) for w in shown] == ["something else"]  # not the expected ones
    assert said[-1] == f"note: {demo.below_bc_line(2, tmp_path)}"
    assert "2 learned rewards agree with the expert less than behaviour cloning" in said[-1]
