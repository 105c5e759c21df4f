"""Issue 21, the gym commands: bad values are usage errors before any work, a pickled expert
is refused in one line, non-UTF-8 data paths are read, the report checks a gym summary once
on reading, and ``gym rl`` / ``gym expert`` reruns resume or refuse, never mix."""

from __future__ import annotations

import copy
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from test_reliability import one_error_line, run_cli
from testkit import folder_bytes, folder_snapshot

from pokerirl.cli.seeds import MAX_SEED

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

ODD = os.fsdecode(b"\xff")
RL_FAST = ["--timesteps", "300", "--evaluations", "1", "--eval-episodes", "1"]
EXPERT_FAST = ["--timesteps", "300", "--eval-episodes", "1", "--final-episodes", "1"]


# --- usage errors: exit 2, one line, before any work -------------------------------------------


def _bad_values(out: Path, afile: Path) -> list[tuple[list[str], str]]:
    rl = ["gym", "rl", "MountainCar-v0", "--env-reward", "--out", str(out)]
    expert = ["gym", "expert", "MountainCar-v0", "--out", str(out)]
    collect = ["gym", "collect", "MountainCar-v0", "--out", str(out / "t.parquet")]
    irl = ["gym", "irl", "MountainCar-v0", "--out", str(out), "--preset", "quick"]
    study = ["gym", "study", "MountainCar-v0", "--out", str(out)]
    return [
        ([*rl, "--threads", "0"], "'--threads'"),
        ([*irl, "--threads", "0"], "'--threads'"),
        ([*expert, "--threads", "0"], "'--threads'"),
        ([*collect, "-n", "10", "--seed", "-1"], "'--seed'"),
        ([*collect, "-n", "10", "--seed", str(MAX_SEED + 1)], "'--seed'"),
        ([*collect, "-n", str(10**14)], "less than or equal to 10000000"),
        ([*study, "--seed", str(MAX_SEED + 1)], "'--seed'"),
        ([*study, "--seed", str(MAX_SEED), "--runs", "2"], "run seeds must be at most"),
        (["gym", "sweep", "MountainCar-v0", "--param", "alpha=1", "--out", str(out),
          "--seed", "-1"],
         "'--seed'"),
        ([*study, "--transitions", str(10**14)], "'--transitions'"),
        ([*rl, "--timesteps", "0"], "'--timesteps'"),
        ([*expert, "--timesteps", "0"], "'--timesteps'"),
        ([*rl, "--evaluations", "0"], "'--evaluations'"),
        (["gym", "rl", "Foo-v0", "--env-reward", "--out", str(out)],
         "unknown task 'Foo-v0'; choose one of Acrobot-v1, MountainCar-v0"),
        (["gym", "expert", "Foo-v0", "--out", str(out)], "unknown task 'Foo-v0'"),
        (["gym", "collect", "Foo-v0", "-n", "10", "--out", str(out)], "unknown task 'Foo-v0'"),
        (["gym", "rl", "MountainCar-v0", "--env-reward", "--out", str(afile)],
         "exists and is not a folder"),
        (["gym", "expert", "MountainCar-v0", "--out", str(afile)], "exists and is not a folder"),
    ]  # fmt: skip


def test_bad_values_of_the_gym_commands_are_usage_errors_before_any_work(tmp_path: Path) -> None:
    out, afile = tmp_path / "out", tmp_path / "afile"
    afile.write_text("mine")
    for args, needle in _bad_values(out, afile):
        started = time.monotonic()
        code, lines = run_cli(*args)
        assert code == 2, (args, lines)
        assert needle in one_error_line(lines), (args, lines)
        assert not out.exists(), args  # refused before anything is written
        assert time.monotonic() - started < 20, args  # before any training
    assert afile.read_text() == "mine"


# --- a pickled expert -----------------------------------------------------------------------


class _Payload:
    def __reduce__(self) -> tuple[Any, ...]:
        return (os.system, (f"touch {os.environ['POKERIRL_PWNED']}",))


@pytest.mark.parametrize("how", ["pickle", "torch.save"])
def test_a_pickled_expert_model_is_refused_in_one_line_and_never_run(
    tmp_path: Path, how: str
) -> None:
    import pickle

    import torch

    from pokerirl.gym.expert_policies import resolve_expert_dir

    expert = tmp_path / "expert"
    expert.mkdir()
    shipped = resolve_expert_dir("shipped", "MountainCar-v0")
    (expert / "config.json").write_bytes((shipped / "config.json").read_bytes())
    pwned = tmp_path / "pwned"
    os.environ["POKERIRL_PWNED"] = str(pwned)
    try:
        if how == "pickle":
            (expert / "model.pt").write_bytes(pickle.dumps(_Payload()))
        else:  # torch's zip format around a pickled object
            torch.save({"weight": _Payload()}, expert / "model.pt")
    finally:
        del os.environ["POKERIRL_PWNED"]
    out = tmp_path / "t.parquet"
    code, lines = run_cli(
        "gym", "collect", "MountainCar-v0", "--expert", str(expert), "-n", "10", "--out", str(out)
    )
    assert code == 1
    line = one_error_line(lines)
    assert line == f"error: {expert / 'model.pt'}: not a state_dict (refusing to unpickle)"
    assert not pwned.exists() and not out.exists()


# --- a data path that is not UTF-8 ------------------------------------------------------------


def test_gym_irl_reads_data_at_a_path_that_is_not_utf8(tmp_path: Path) -> None:
    data = tmp_path / f"data{ODD}.parquet"
    code, lines = run_cli("gym", "collect", "MountainCar-v0", "-n", "400", "--out", str(data))
    assert code == 0, lines
    out = tmp_path / "irl"
    code, lines = run_cli(
        "gym", "irl", "MountainCar-v0", "--data", str(data), "--preset", "quick",
        "--runs", "1", "--epochs", "1", "--out", str(out),
    )  # fmt: skip
    assert code == 0, lines
    assert (out / "run-0").is_dir()


# --- the report checks a gym summary once, on reading ---------------------------------------


@pytest.fixture
def study(mountaincar_study: Path) -> Path:
    return mountaincar_study  # the session's (conftest): read only here


def _leaves(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    if isinstance(value, dict):
        return [path] + [leaf for k, v in value.items() for leaf in _leaves(v, (*path, k))]
    if isinstance(value, list):
        return [path] + [leaf for k, v in enumerate(value) for leaf in _leaves(v, (*path, k))]
    return [path]


def _set(document: Any, path: tuple[Any, ...], value: Any) -> Any:
    changed = copy.deepcopy(document)
    inner = changed
    for key in path[:-1]:
        inner = inner[key]
    inner[path[-1]] = value
    return changed


@pytest.mark.slow
def test_report_on_a_damaged_gym_summary_is_one_line_never_a_crash(
    study: Path, tmp_path: Path
) -> None:
    from pokerirl.studies.common import StudyError
    from pokerirl.studies.gym.report import load_gym_study

    summary = json.loads((study / "summary.json").read_text())
    load_gym_study(study)  # the real one renders
    folder = tmp_path / "damaged"
    folder.mkdir()
    tried = 0
    for path in _leaves(summary)[1:]:
        for bad in ("x", None, [], {}, -1, True):
            (folder / "summary.json").write_text(json.dumps(_set(summary, path, bad)))
            tried += 1
            try:
                load_gym_study(folder)
            except StudyError as error:
                assert "\n" not in str(error) and "summary.json" in str(error)
    assert tried > 300
    for path, bad, needle in [
        (("algos", "airl", "irl_final_return", "mean"), "x", "irl_final_return.mean"),
        (("seeds",), [], "seeds: expected a non-empty list"),
        (("algos", "hairl"), None, "algos.hairl: expected an object"),
        (("settings", "irl", "epochs"), "x", "settings.irl.epochs: expected an integer"),
    ]:
        (folder / "summary.json").write_text(json.dumps(_set(summary, path, bad)))
        code, lines = run_cli("report", str(folder))
        assert code == 1 and needle in one_error_line(lines), lines


# --- gym rl and gym expert reruns ------------------------------------------------------------


def test_gym_rl_rerun_resumes_refuses_other_settings_and_overwrites_whole(tmp_path: Path) -> None:
    out = tmp_path / "rl"
    base = ["gym", "rl", "MountainCar-v0", "--env-reward", "--runs", "2", "--out", str(out)]
    assert run_cli(*base, *RL_FAST)[0] == 0
    before = folder_bytes(out)
    assert {json.loads((out / f"run-{k}" / "unit.json").read_text())["config"]["seed"]
            for k in (0, 1)} == {0, 1}  # fmt: skip
    assert run_cli(*base, *RL_FAST)[0] == 0  # same settings: the runs are kept
    assert folder_bytes(out) == before
    other = ["--timesteps", "400", *RL_FAST[2:]]
    code, lines = run_cli(*base, *other)
    assert code == 1
    assert one_error_line(lines) == (
        f"error: {out / 'run-0'} was made with another configuration (timesteps 300 -> 400); "
        "use another --out, or --overwrite to recompute it"
    )
    assert folder_bytes(out) == before  # nothing replaced
    assert run_cli(*base, *other, "--overwrite")[0] == 0
    for k in (0, 1):
        assert json.loads((out / f"run-{k}" / "config.json").read_text())["timesteps"] == 400


def _timesteps(out: Path) -> dict[str, int]:
    """Each run folder's budget, from its config (what it was trained with)."""
    return {p.parent.name: json.loads(p.read_text())["timesteps"]
            for p in out.glob("run-*/config.json")}  # fmt: skip


def _killed(argv: list[str], ready: Callable[[], bool]) -> None:
    """Run the CLI in a subprocess and SIGKILL it as soon as ``ready()``."""
    process = subprocess.Popen(
        [sys.executable, "-m", "pokerirl", *argv], stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not ready() and process.poll() is None:
            time.sleep(0.02)
        assert ready() and process.poll() is None  # killed in the middle
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()


@pytest.mark.slow
def test_a_killed_gym_rl_overwrite_never_leaves_runs_of_two_settings(tmp_path: Path) -> None:
    """Runs are units, each saved on its own: an --overwrite first removes every run of other
    settings (run-4 beyond --runs too), so a kill after the first new run leaves no old one."""
    out = tmp_path / "rl"
    base = ["gym", "rl", "MountainCar-v0", "--env-reward", "--out", str(out), "-q"]
    assert run_cli(*base, "--runs", "5", *RL_FAST, "--rl-backend", "sb3")[0] == 0
    new = [*base, "--runs", "3", "--timesteps", "600", *RL_FAST[2:], "--rl-backend", "sb3"]
    _killed([*new, "--overwrite"], lambda: _timesteps(out).get("run-0") == 600)
    assert _timesteps(out) == {"run-0": 600}  # the old runs went before the new ones started
    # The next run resumes from the new run: no --overwrite needed, run-0 kept.
    kept = (out / "run-0" / "model.pt").read_bytes(), (out / "run-0" / "model.pt").stat().st_ino
    assert run_cli(*new)[0] == 0
    assert _timesteps(out) == {f"run-{k}": 600 for k in range(3)}
    assert ((out / "run-0" / "model.pt").read_bytes(),
            (out / "run-0" / "model.pt").stat().st_ino) == kept  # fmt: skip


@pytest.mark.slow
def test_a_gym_rl_overwrite_killed_in_a_lockstep_group_leaves_no_old_run(tmp_path: Path) -> None:
    out = tmp_path / "rl"
    base = ["gym", "rl", "MountainCar-v0", "--env-reward", "--out", str(out), "--runs", "2"]
    assert run_cli(*base, *RL_FAST)[0] == 0
    _killed([*base, "--overwrite", "--timesteps", "20000", *RL_FAST[2:]],
            lambda: not any(out.glob("run-*")))  # fmt: skip
    assert _timesteps(out) == {}
    assert not list(out.glob("*.json"))  # no record of either settings


@pytest.mark.slow
def test_gym_expert_rerun_with_another_seed_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "expert"
    base = ["gym", "expert", "MountainCar-v0", "--out", str(out), *EXPERT_FAST]
    assert run_cli(*base)[0] == 0
    before = folder_bytes(out)
    code, lines = run_cli(*base)
    assert code == 0 and any("reusing the expert" in line for line in lines)
    code, lines = run_cli(*base, "--seed", "3")
    assert code == 1 and "(seed 0 -> 3); use another --out, or --overwrite" in one_error_line(lines)
    assert folder_bytes(out) == before
    assert run_cli(*base, "--seed", "3", "--overwrite")[0] == 0
    assert json.loads((out / "config.json").read_text())["seed"] == 3


# --- gym rl and gym expert folders written before the store --------------------------------


def _before_the_store(out: Path, name: str, identity: dict[str, Any]) -> None:
    """Make ``out`` a folder as the claim-era code left it: one ``pokerirl-gym-job/1`` record
    for the folder (its bytes as that code wrote them), no ``unit.json``."""
    for record in out.rglob("unit.json"):
        record.unlink()
    document = {"format": "pokerirl-gym-job/1", "identity": identity}
    (out / name).write_text(json.dumps(document, indent=2) + "\n")


def test_a_gym_rl_folder_made_before_the_store_is_reused_refused_and_replaced(
    tmp_path: Path,
) -> None:
    out = tmp_path / "rl"
    base = ["gym", "rl", "MountainCar-v0", "--env-reward", "--runs", "2", "--out", str(out)]
    assert run_cli(*base, *RL_FAST)[0] == 0
    identity = {"env": "MountainCar-v0", "reward": "env", "timesteps": 300, "evaluations": 1,
                "eval_episodes": 1, "backend": "lockstep"}  # fmt: skip
    _before_the_store(out, "rl.job.json", identity)
    shutil.rmtree(out / "run-1")  # killed after its first run landed
    before = folder_snapshot(out)
    assert run_cli(*base, *RL_FAST)[0] == 0
    after = folder_snapshot(out)
    assert {k: v for k, v in after.items() if not k.startswith("run-1")} == before  # reused
    assert (out / "run-1" / "unit.json").is_file()  # the missing run, as a unit
    code, lines = run_cli(*base, "--timesteps", "400", *RL_FAST[2:])
    assert code == 1
    assert one_error_line(lines) == (
        f"error: {out / 'rl.job.json'} was made with another configuration "
        "(timesteps 300 -> 400); use another --out, or --overwrite to recompute it"
    )
    assert folder_snapshot(out) == after
    assert run_cli(*base, "--timesteps", "400", *RL_FAST[2:], "--overwrite")[0] == 0
    assert _timesteps(out) == {"run-0": 400, "run-1": 400}
    assert not (out / "rl.job.json").exists()  # it vouches for nothing any more


def test_a_gym_expert_folder_made_before_the_store_is_reused_and_refused(
    tmp_path: Path,
) -> None:
    out = tmp_path / "expert"
    base = ["gym", "expert", "MountainCar-v0", "--out", str(out), *EXPERT_FAST]
    assert run_cli(*base)[0] == 0
    identity = {"env": "MountainCar-v0", "seed": 0, "hyper": "paper", "timesteps": 300,
                "eval_every": None, "eval_episodes": 1, "final_episodes": 1}  # fmt: skip
    _before_the_store(out, "expert.job.json", identity)
    before = folder_snapshot(out)
    code, lines = run_cli(*base)
    assert code == 0 and any("reusing the expert" in line for line in lines)
    assert folder_snapshot(out) == before
    code, lines = run_cli(*base, "--seed", "3")
    assert code == 1
    assert f"{out / 'expert.job.json'} was made with another configuration (seed 0 -> 3)" in (
        one_error_line(lines))  # fmt: skip
    assert folder_snapshot(out) == before


# --- a killed gym irl ------------------------------------------------------------------------


def _writing(out: Path) -> bool:
    return any("abcd1234" not in str(p) for p in out.glob(".irl.*/**/run-0"))


@pytest.mark.slow
@pytest.mark.serial  # waits for the run to be writing, within a time: run alone
def test_a_killed_gym_irl_leaves_nothing_the_next_run_does_not_remove(tmp_path: Path) -> None:
    out, data = tmp_path / "irl", tmp_path / "expert.parquet"
    # Collected once (2,000 rows, not the preset's 10,000): each of the three runs reads it.
    collect = ["gym", "collect", "MountainCar-v0", "--expert", "shipped", "-n", "2000"]
    assert run_cli(*collect, "--out", str(data), "--seed", "0")[0] == 0
    args = ["gym", "irl", "MountainCar-v0", "--out", str(out), "--preset", "quick", "--runs", "1",
            "--data", str(data)]  # fmt: skip
    assert run_cli(*args, "--epochs", "1")[0] == 0
    before = folder_bytes(out)
    legacy = out / ".irl.abcd1234.tmp" / "run-0"  # what an earlier version's kill left
    legacy.mkdir(parents=True)
    argv = [sys.executable, "-m", "pokerirl", *args, "--epochs", "200", "--overwrite"]
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not _writing(out):
            time.sleep(0.05)
        assert _writing(out)  # killed while writing its runs
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    after = folder_bytes(out)
    assert after == before | {k: v for k, v in after.items() if k.startswith(".")}
    assert run_cli(*args, "--epochs", "1", "--overwrite")[0] == 0
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert folder_bytes(out).keys() == before.keys()
