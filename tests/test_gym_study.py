"""The Gymnasium study and the ablation sweep on real environments at tiny budgets: Acrobot and
MountainCar IRL, then a few thousand RL steps; resume, refusal and the report's numbers."""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest
from click.testing import Result
from testkit import TINY_GYM_STUDY, Cli

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.execution import Backend
from pokerirl.irl import load_reward
from pokerirl.studies.common import StudyError
from pokerirl.studies.gym.config import authors_budget, parse_algos, parse_tasks, study_preset
from pokerirl.studies.gym.pipeline import run_gym_study
from pokerirl.studies.gym.results import TaskSummary
from pokerirl.studies.gym.sweep import CSV_COLUMNS, SweepRow, parse_param, sweep_points
from pokerirl.studies.gym.units import DATA_FILE

TINY = TINY_GYM_STUDY  # the session's MountainCar study (conftest) has these settings
MEAN_STD = {"mean", "std"}

CLI = Cli()  # pokerirl run in this process (tests/testkit.py)


def jsonl(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line]


def study(out: Path, *extra: str, task: str = "MountainCar-v0") -> Result:
    return CLI("gym", "study", task, "--out", out, *TINY, *extra)


@pytest.fixture
def mountaincar(mountaincar_study: Path) -> Path:
    """The session's MountainCar study (conftest), built with ``TINY``."""
    return mountaincar_study


@pytest.mark.slow
def test_summary_has_the_issue_names_and_the_runs_numbers(mountaincar: Path) -> None:
    summary = json.loads((mountaincar / "summary.json").read_text())
    assert summary["env"] == "MountainCar-v0" and summary["runs"] == 2
    assert set(summary["algos"]) == {"airl", "hairl"}
    for algo, entry in summary["algos"].items():
        for key in ("irl_final_return", "rl_final_return", "final_alignment"):
            assert set(entry[key]) == MEAN_STD, (algo, key)
        assert {"majority", "legal_majority", "bc", "random", "expert"} <= set(entry["baselines"])
        # The finals are the run folders' last points, mean and sample std over the runs.
        irl = [jsonl(mountaincar / "irl" / algo / f"run-{k}" / "metrics.jsonl") for k in (0, 1)]
        last = [run[-1]["eval_return"] for run in irl]
        assert entry["irl_final_return"]["mean"] == pytest.approx(np.mean(last))
        assert entry["irl_final_return"]["std"] == pytest.approx(np.std(last, ddof=1))
        alignment = [run[-1]["val_alignment"] for run in irl]
        assert entry["final_alignment"]["mean"] == pytest.approx(np.mean(alignment))
        rl = [jsonl(mountaincar / "rl" / algo / f"run-{k}" / "metrics.jsonl") for k in (0, 1)]
        assert entry["rl_final_return"]["mean"] == pytest.approx(
            np.mean([run[-1]["return_mean"] for run in rl])
        )
        assert all(run[-1]["timesteps"] == 2000 and -200 <= run[-1]["return_mean"] for run in rl)
    assert set(summary["env_reward"]["rl_final_return"]) == MEAN_STD
    # EPIC per algorithm: mean and sample std of the runs' reward_quality.json (issue 20).
    for algo, entry in summary["algos"].items():
        runs = [
            json.loads(
                (mountaincar / "irl" / algo / f"run-{k}" / "reward_quality.json").read_text()
            )
            for k in (0, 1)
        ]
        for key in ("epic", "epic_random_baseline", "epic_g"):
            assert set(entry[key]) == MEAN_STD, (algo, key)
            assert entry[key]["mean"] == pytest.approx(np.mean([q[key] for q in runs]), abs=1e-6)
            assert entry[key]["std"] == pytest.approx(
                np.std([q[key] for q in runs], ddof=1), abs=1e-6
            )
            assert 0 <= entry[key]["mean"] <= 1
        assert runs[0]["gamma"] == 0.98  # MountainCar's DQN discount
    # The expert's return is measured once, from the data's complete episodes.
    assert -200 < summary["expert_return"] < -80
    assert summary["paper"]["irl_final_return"]["hairl"] == {"mean": -123.3, "std": 8.0}


@pytest.mark.slow
def test_rl_runs_learn_from_their_own_irl_runs_reward(mountaincar: Path) -> None:
    for k in (0, 1):
        record = json.loads((mountaincar / "rl" / "hairl" / f"run-{k}" / "config.json").read_text())
        assert record["reward"] == f"hairl:run-{k}" and record["seed"] == k
        unit = json.loads((mountaincar / "rl" / "hairl" / f"run-{k}" / "unit.json").read_text())
        reward_pt = mountaincar / "irl" / "hairl" / f"run-{k}" / "reward.pt"
        digest = "sha256:" + hashlib.sha256(reward_pt.read_bytes()).hexdigest()
        assert unit["inputs"]["reward_run"]["reward.pt"] == digest
    env_record = json.loads((mountaincar / "rl" / "env" / "run-0" / "config.json").read_text())
    assert env_record["reward"] == "env"
    # Same seed, same settings: only the reward differs, and it changes what DQN learns.
    rewards = ("env", "airl", "hairl")
    models = {r: (mountaincar / "rl" / r / "run-0" / "model.pt").read_bytes() for r in rewards}
    assert len(set(models.values())) == 3
    # The two H-AIRL runs learned different rewards (other seeds), and both are usable.
    obs = np.array([[-0.5, 0.0], [-0.9, 0.03]], dtype=np.float32)
    f0 = load_reward(mountaincar / "irl" / "hairl" / "run-0")(obs, np.array([0, 2]))
    f1 = load_reward(mountaincar / "irl" / "hairl" / "run-1")(obs, np.array([0, 2]))
    assert f0.shape == (2,) and not np.allclose(f0, f1)


@pytest.mark.slow
def test_a_run_without_reward_quality_gets_it_at_the_report(mountaincar: Path) -> None:
    # An IRL run folder from before reward_quality.json: the study computes it there.
    path = mountaincar / "irl" / "airl" / "run-1" / "reward_quality.json"
    before = path.read_bytes()
    path.unlink()
    summary = json.loads((mountaincar / "summary.json").read_text())
    result = study(mountaincar)
    assert result.exit_code == 0, result.output
    assert path.read_bytes() == before  # the same bytes again
    assert json.loads((mountaincar / "summary.json").read_text())["algos"] == summary["algos"]


@pytest.mark.slow
def test_gail_beside_airl_and_hairl_when_named_reusing_their_units(
    mountaincar: Path, tmp_path: Path
) -> None:
    # A copy of the default study, rerun with GAIL: the paper's units are reused, GAIL's IRL
    # and its RL runs are added, and GAIL gets its rows, curves and reward-map panel.
    out = tmp_path / "mc"
    shutil.copytree(mountaincar, out)
    result = study(out, "--algos", "gail,airl,hairl")
    assert result.exit_code == 0, result.output
    assert "IRL: AIRL, H-AIRL and GAIL, 2 runs each" in result.output
    assert "2 of 3 finished already, reused" in result.output  # the IRL units
    assert "6 of 8 finished already, reused" in result.output  # the RL runs
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary["algos"]) == ["airl", "hairl", "gail"]
    gail = summary["algos"]["gail"]
    assert len(gail["rl_per_run_final"]) == 2 and len(gail["curves"]["rl"]["mean"]) >= 2
    assert set(summary["reward_map"]["agreement"]) == {"airl", "hairl", "gail"}
    for k in (0, 1):
        irl = json.loads((out / "irl" / "gail" / f"run-{k}" / "config.json").read_text())
        assert irl["algo"] == "gail"
        rl = json.loads((out / "rl" / "gail" / f"run-{k}" / "config.json").read_text())
        assert rl["reward"] == f"gail:run-{k}"
    report = (out / "report.md").read_text()
    for row in ("IRL-phase return, GAIL", "RL-phase return, GAIL reward",
                "alignment, GAIL policy", "EPIC distance to the true reward / on the expert's"):
        assert f"| {row}" in report, row
    assert CLI.invoke(["report", str(out)]).output == report
    # The paper's algorithms only: the default study's summary again, GAIL's folders ignored.
    again = study(out)
    assert again.exit_code == 0, again.output
    assert (out / "summary.json").read_bytes() == (mountaincar / "summary.json").read_bytes()
    assert (out / "report.md").read_bytes() == (mountaincar / "report.md").read_bytes()


def test_parse_algos_keeps_the_paper_s_two_and_adds_gail_only_when_named() -> None:
    assert study_preset("quick").algos == ("airl", "hairl") == parse_algos("hairl,airl")
    assert parse_algos(" gail , hairl,airl") == ("airl", "hairl", "gail")
    for bad in ("airl,gail", "airl,hairl,bc", ""):
        with pytest.raises(StudyError, match="airl and hairl"):
            parse_algos(bad)
    with pytest.raises(StudyError, match="algos: airl, hairl, then optionally gail"):
        study_preset("quick", algos=("hairl", "airl"))


@pytest.mark.slow
def test_figures_and_report_beside_the_authors(mountaincar: Path) -> None:
    for name in ("irl_returns", "alignment", "rl_returns", "reward_map"):
        data = (mountaincar / "figures" / f"{name}.png").read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 10_000
    report = (mountaincar / "report.md").read_text()
    summary = json.loads((mountaincar / "summary.json").read_text())
    hairl = summary["algos"]["hairl"]["irl_final_return"]
    assert f"| IRL-phase return, H-AIRL | {hairl['mean']:,.1f} ± {hairl['std']:,.1f} | " in report
    assert "-123.3 ± 8.0" in report and "-149.5 ± 36.7" in report  # the authors' finals
    assert "**Not the authors' budget or number of runs**" in report
    assert summary["settings"]["authors_budget"] is False
    assert "![rl_returns](figures/rl_returns.png)" in report
    found = summary["reward_map"]
    assert found["grid"] == 101 and 0 < found["constant_agreement"] < 1
    assert len(found["agreement"]["hairl"]["runs"]) == 2
    assert f"{100 * found['agreement']['hairl']['mean_f']:.1f}%" in report
    epic = summary["algos"]["hairl"]["epic"]
    assert f"{epic['mean']:,.3f} ± {epic['std']:,.3f} |" in report
    assert "EPIC of a random reward net" in report and "γ 0.98" in report
    # pokerirl report renders the same report again, or prints summary.json
    again = CLI.invoke(["report", str(mountaincar)])
    assert again.exit_code == 0 and again.output == report
    as_json = CLI.invoke(["report", str(mountaincar), "--format", "json"])
    assert json.loads(as_json.output) == summary
    # The typed summary reads it and writes it back to the same bytes (names and their order).
    text = (mountaincar / "summary.json").read_text()
    assert json.dumps(TaskSummary.from_json(summary).to_json(), indent=2) + "\n" == text


@pytest.mark.slow
def test_rerun_reuses_every_unit_and_changed_settings_are_refused(mountaincar: Path) -> None:
    before = {p: p.read_bytes() for p in mountaincar.rglob("*") if p.is_file()}
    result = study(mountaincar)
    assert result.exit_code == 0, result.output
    assert result.output.count("finished already, reused") == 3
    after = {p: p.read_bytes() for p in mountaincar.rglob("*") if p.is_file()}
    assert after == before  # same inputs, same bytes (the figures and report included)

    refused = study(mountaincar, "--epochs", "3")
    assert refused.exit_code == 1
    lines = refused.output.strip().splitlines()
    assert lines[-1].startswith("error: ") and "settings.epochs 2 -> 3" in lines[-1]
    assert "--overwrite" in lines[-1]
    assert {p: p.read_bytes() for p in mountaincar.rglob("*") if p.is_file()} == before


@pytest.mark.slow
def test_a_corrupt_rl_run_is_recomputed_to_the_same_bytes(mountaincar: Path) -> None:
    run = mountaincar / "rl" / "airl" / "run-1"
    model = (run / "model.pt").read_bytes()
    (run / "model.pt").write_bytes(b"truncated")
    result = study(mountaincar)
    assert result.exit_code == 0, result.output
    assert "5 of 6 finished already, reused" in result.output  # only that run was recomputed
    assert (run / "model.pt").read_bytes() == model


@pytest.mark.slow
def test_two_tasks_acrobot_and_mountaincar_each_get_a_folder(tmp_path: Path) -> None:
    preset = study_preset(
        "quick",
        tasks=("Acrobot-v1", "MountainCar-v0"),
        runs=2,
        transitions=1200,
        epochs=2,
        eval_episodes=1,
        rl_timesteps=1024,
        rl_evaluations=2,
    )
    said: list[str] = []
    result = run_gym_study(tmp_path, preset, backend=Backend(jobs=2), say=said.append)
    assert said[0] == "[1/4] expert data: Acrobot-v1, MountainCar-v0"
    overall = json.loads((tmp_path / "summary.json").read_text())
    assert set(overall["tasks"]) == {"Acrobot-v1", "MountainCar-v0"}
    for env in overall["tasks"]:
        folder = tmp_path / env
        assert (folder / DATA_FILE).is_file() and (folder / "report.md").is_file()
        summary = json.loads((folder / "summary.json").read_text())
        assert summary == overall["tasks"][env] == result.summaries[env].to_json()
        assert summary["env_reward"]["curves"]["rl"]["timesteps"][-1] == 1024
    acrobot = overall["tasks"]["Acrobot-v1"]
    assert acrobot["reward_map"] is None  # 6-d observations: no map
    assert not (tmp_path / "Acrobot-v1" / "figures" / "reward_map.png").exists()
    assert -500 <= acrobot["algos"]["hairl"]["irl_final_return"]["mean"] <= 0
    assert acrobot["random_return"] == pytest.approx(-500, abs=50)
    report = (tmp_path / "report.md").read_text()
    assert CLI.invoke(["report", str(tmp_path)]).output == report
    assert "## Acrobot-v1" in report and "## MountainCar-v0" in report
    assert "(Acrobot-v1/figures/irl_returns.png)" in report


def test_bad_inputs_are_one_line(tmp_path: Path) -> None:
    runner = CLI
    cases = [
        (["gym", "study", "Pong-v5", "--out", str(tmp_path / "a")], "unknown task 'Pong-v5'"),
        (["gym", "study", "MountainCar-v0", "--preset", "huge", "--out", str(tmp_path / "b")],
         "unknown preset 'huge'"),
        (["gym", "sweep", "MountainCar-v0", "--param", "gamma=0.9", "--out", str(tmp_path / "c")],
         "bad sweep parameter 'gamma=0.9'"),
        (["gym", "sweep", "MountainCar-v0", "--param", "alpha=0,2", "--out", str(tmp_path / "d")],
         "alpha must be in [0, 1], got 2"),
        (["gym", "sweep", "MountainCar-v0", "--param", "beta=0", "--param", "beta=1", "--out",
          str(tmp_path / "e")], "given twice"),
        (["gym", "sweep", "MountainCar-v0", "--param", "sigma_end=0.04,2", "--out",
          str(tmp_path / "f")],
         "point alpha=0.1_beta=0.25_sigma_start=1_sigma_end=2: invalid AIRL config"),
    ]  # fmt: skip
    for args, message in cases:
        result = runner.invoke(args)
        usage = "--preset" in args  # the preset's settings: a usage error
        assert result.exit_code == (2 if usage else 1), (args, result.output)
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), result.output
        assert message in result.output, result.output
    assert not (tmp_path / "f").exists()  # refused before anything was written
    afile = tmp_path / "file"
    afile.write_text("x")
    result = runner.invoke(["gym", "study", "MountainCar-v0", "--out", str(afile)])
    assert result.exit_code == 1 and "is not a folder" in result.output
    assert afile.read_text() == "x"


def test_sweep_is_a_gym_command_and_the_old_name_now_the_poker_sweep_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import pokerirl.studies.gym.sweep as sweep
    from pokerirl.studies.gym.sweep import SweepResult

    calls: list[tuple[tuple, dict]] = []

    def fake_sweep(*args: object, **kwargs: object) -> SweepResult:
        calls.append((args, kwargs))
        return SweepResult(out=tmp_path, env="MountainCar-v0", rows=(), figures=())

    monkeypatch.setattr(sweep, "run_sweep", fake_sweep)
    runner = CLI
    args = ["MountainCar-v0", "--param", "alpha=0,1", "--out", str(tmp_path), "--runs", "3",
            "--seed", "7", "--epochs", "2", "--jobs", "1", "-q", "--rl-backend", "sb3"]  # fmt: skip
    new = runner.invoke(["gym", "sweep", *args])
    assert new.exit_code == 0, new.output
    assert new.stderr == ""
    (new_args, new_kwargs), = calls
    assert new_args[1] == {"alpha": (0.0, 1.0)} and new_args[2].runs == 3
    assert new_args[2].seed == 7 and new_kwargs["rl_backend"] == "sb3"
    # 'pokerirl sweep' (the gym sweep's old, deprecated name) is the poker sweep now: a
    # Gymnasium id there is one usage line naming the gym command.
    moved = runner.invoke(["sweep", "MountainCar-v0", "--out", str(tmp_path / "m")])
    assert moved.exit_code == 2
    assert moved.stderr.strip().splitlines() == [
        "error: 'pokerirl sweep' is the poker sweep now; the Gymnasium one is "
        "'pokerirl gym sweep MountainCar-v0'"
    ]
    assert len(calls) == 1
    assert " sweep " in runner.invoke(["gym", "--help"]).output


def test_parse_tasks_and_points() -> None:
    assert len(parse_tasks("all")) == 6
    paper = study_preset("paper")
    assert all(authors_budget(env, paper) for env in paper.tasks)
    assert not authors_budget("Acrobot-v1", study_preset("paper", runs=3))
    assert not authors_budget("Acrobot-v1", study_preset("paper", rl_timesteps=1000))
    assert parse_tasks("CartPole-v1") == ("CartPole-v1",)  # any Gymnasium task (issue 34)
    with pytest.raises(StudyError, match=r"unknown task 'NoSuchEnv-v0'; choose one of .* or all"):
        parse_tasks("NoSuchEnv-v0")
    assert parse_param("sigma_end=0.5, 0.04") == ("sigma_end", (0.5, 0.04))
    # A sweep row's fields are sweep.csv's columns, in order (and sweep.json's row names).
    assert tuple(f.name for f in fields(SweepRow)) == CSV_COLUMNS
    points = sweep_points("MountainCar-v0", {"alpha": (0.1, 1.0)}, study_preset("quick"))
    assert [p.name for p in points] == [
        "alpha=0.1_beta=0.25_sigma_start=1_sigma_end=0.04",
        "alpha=1_beta=0.25_sigma_start=1_sigma_end=0.04",
    ]


@pytest.mark.slow
def test_sweep_runs_irl_then_rl_per_point_and_shares_the_preset_point(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    args = ["gym", "sweep", "MountainCar-v0", "--param", "alpha=0.1,1"]
    args += ["--param", "sigma_end=0.04,0.5"]
    args += ["--out", str(out), "--runs", "2", "--transitions", "1500", "--epochs", "2"]
    args += ["--eval-episodes", "2", "--timesteps", "1000", "--jobs", "2", "-q"]
    result = CLI.invoke(args)
    assert result.exit_code == 0, result.output
    assert "alpha=1: IRL return" in result.output
    # alpha=0.1 and sigma_end=0.04 are both the preset's point: three points, not four.
    points = sorted(p.name for p in (out / "points").iterdir())
    assert len(points) == 3
    rows = (out / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("param,value,point,runs,irl_final_return_mean")
    assert len(rows) == 5
    record = json.loads((out / "sweep.json").read_text())
    by_value = {(r["param"], r["value"]): r for r in record["rows"]}
    assert by_value[("alpha", 0.1)]["point"] == by_value[("sigma_end", 0.04)]["point"]
    one = by_value[("alpha", 1.0)]
    run = out / "points" / one["point"] / "irl" / "hairl" / "run-0"
    hyper = json.loads((run / "config.json").read_text())["hyperparameters"]
    assert hyper["alpha"] == 1.0 and hyper["sigma_end"] == 0.04
    irl = [jsonl(run.parent / f"run-{k}" / "metrics.jsonl")[-1]["eval_return"] for k in (0, 1)]
    assert one["irl_final_return_mean"] == pytest.approx(np.mean(irl))
    rl_record = json.loads((run.parents[2] / "rl" / "hairl" / "run-1" / "config.json").read_text())
    assert rl_record["reward"] == "hairl:run-1" and rl_record["timesteps"] == 1000
    for name in ("alpha.png", "sigma_end.png"):
        assert (out / name).read_bytes().startswith(b"\x89PNG")
    again = CLI.invoke(args)
    assert again.exit_code == 0 and (out / "sweep.csv").read_text().splitlines() == rows


@pytest.mark.slow
def test_every_json_file_of_a_gym_study_is_strict_json(mountaincar: Path) -> None:
    from test_study import strict_json_files

    assert strict_json_files(mountaincar) > 10
