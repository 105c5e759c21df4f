"""Callers ported onto pokerirl.store keep the folders written before the port: a unit folder
or seed file whose record is main's ``pokerirl-unit/1`` (``execution.make_record``, the writer
every one of them used, copied below as main had it) is reused by a rerun, not recomputed or
refused."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
import torch

import pokerirl.tournaments.authors as authors
from pokerirl.agents.dqn import DQNConfig
from pokerirl.agents.train import TrainConfig, train_agent
from pokerirl.datasets.toy import toy_expert_table
from pokerirl.execution import Backend
from pokerirl.game.match import DEFAULT_BATCH_SIZE
from pokerirl.irl import load_config
from pokerirl.poker import train_runs
from pokerirl.tournaments import run_authors_tournament, run_tournament

torch.set_num_threads(1)

# The fingerprint main's `train_agent` wrote for AGENT (pokerirl-unit/1, commit 0fb1fe8).
AGENT = TrainConfig(
    hands=512, seed=0, eval_every=512, eval_hands=200, dqn=DQNConfig(concurrent_hands=128)
)
AGENT_PRINT = "sha256:d36978d0ebbced675f2b2b6d19881d61236f35ce98a60144eb10cf1524ac5637"


def bytes_fingerprint(data: bytes) -> str:
    return f"sha256:{hashlib.sha256(data).hexdigest()}"


def make_record(config: dict, *, files: dict | None = None, result: Any = None) -> dict:
    """main's ``execution.make_record`` (commit 02205d6), the writer of every unit record."""
    text = json.dumps(config, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return {
        "format": "pokerirl-unit/1",
        "fingerprint": f"sha256:{hashlib.sha256(text.encode()).hexdigest()}",
        "config": dict(config),
        "files": {name: bytes_fingerprint(data) for name, data in sorted((files or {}).items())},
        "result": result,
    }


def save_record(path: Path, record: dict) -> None:
    """main's ``execution.save_record``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2, sort_keys=True) + "\n")


def _as_main_wrote(record_path: Path, config: dict, names: list[str]) -> None:
    """Replace a unit folder's record with the one main's save_unit_folder wrote."""
    folder = record_path.parent
    files = {n: (folder / n).read_bytes() for n in names}
    save_record(record_path, make_record(config, files=files))


def test_an_agent_folder_of_main_is_reused(tmp_path: Path) -> None:
    out = tmp_path / "agent"
    assert train_agent(out, AGENT) is not None
    new = json.loads((out / "unit.json").read_text())
    assert new["fingerprint"] == AGENT_PRINT  # the same identity as main's
    assert new["inputs"] == {"reward_run": None, "opponent": "builtin:random"}
    _as_main_wrote(out / "unit.json", {**new["config"], **new["inputs"]}, sorted(new["files"]))
    old = (out / "unit.json").read_bytes()
    assert json.loads(old)["format"] == "pokerirl-unit/1"
    model = (out / "model.pt").stat().st_mtime_ns
    assert train_agent(out, AGENT) is None  # reused: not retrained, not rewritten
    assert (out / "unit.json").read_bytes() == old
    assert (out / "model.pt").stat().st_mtime_ns == model


def test_runs_of_main_are_reused(tmp_path: Path) -> None:
    table = tmp_path / "table.parquet"
    pq.write_table(toy_expert_table(num_hands=60, seed=5), table)
    config = load_config("hairl", overrides={"epochs": 1, "batch_size": 64})
    out = tmp_path / "runs"
    train_runs(table, out, runs=2, config=config, progress=False)
    for k in range(2):  # main's record: its own formula, the table's digest inline
        main_config = {
            "algo": "hairl",
            "device": "cpu",
            "table": bytes_fingerprint(table.read_bytes()),
            "settings": {**config.to_dict(), "seed": config.seed + k},
        }
        names = sorted(json.loads((out / f"run-{k}" / "unit.json").read_text())["files"])
        _as_main_wrote(out / f"run-{k}" / "unit.json", main_config, names)
    before = {k: (out / f"run-{k}" / "reward.pt").stat().st_mtime_ns for k in range(2)}
    records = {k: (out / f"run-{k}" / "unit.json").read_bytes() for k in range(2)}
    train_runs(table, out, runs=2, config=config, progress=False)
    assert {k: (out / f"run-{k}" / "reward.pt").stat().st_mtime_ns for k in range(2)} == before
    assert {k: (out / f"run-{k}" / "unit.json").read_bytes() for k in range(2)} == records


def _seed_config(seed: int, hands: int) -> dict:
    """What main's tournaments/runner.py fingerprinted for seed ``seed`` of call vs random."""
    return {
        "kind": "pokerirl-tournament-seed", "seed": seed, "fingerprint_a": "builtin:call",
        "fingerprint_b": "builtin:random", "hands": hands, "duplicate": True,
        "batch_size": DEFAULT_BATCH_SIZE,
    }  # fmt: skip


def test_seed_files_of_main_are_reused_and_one_without_an_estimate_is_replayed(
    tmp_path: Path,
) -> None:
    planted = {
        "mbb_per_hand": 123.25, "std_error": 1.0, "ci95": [121.0, 125.5], "p_value": 0.5,
        "n": 500,
    }  # fmt: skip
    folder = tmp_path / "seeds" / "call-vs-random"
    # Seed 0 as main wrote it (with the timings older files held), seed 1 without an estimate.
    save_record(folder / "seed-0.json", make_record(
        _seed_config(0, 1000), result={"estimate": planted, "seconds": 0.5}
    ))  # fmt: skip
    save_record(folder / "seed-1.json", make_record(_seed_config(1, 1000), result={}))
    report = run_tournament([("call", "random")], hands=1000, seeds=[0, 1], out=tmp_path)
    assert report.timing["seeds_reused"] == 1 and report.timing["hands_played"] == 1000
    assert report.matchups[0].seeds[0].mbb_per_hand == 123.25
    assert report.matchups[0].seeds[1].mbb_per_hand != 0.0  # played: call beats random
    assert "estimate" in json.loads((folder / "seed-1.json").read_text())["result"]


def test_experiment_files_of_main_are_reused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = {
        "kind": "pokerirl-authors-tournament", "experiment": 0, "repeats": 2, "games": 100,
        "fingerprint_a": "builtin:raise", "fingerprint_b": "builtin:call",
    }  # fmt: skip
    path = tmp_path / "experiments" / "raise-vs-call" / "experiment-0.json"
    save_record(path, make_record(config, result=[7.5, -2.5]))

    def refuse(*args: object) -> object:
        raise AssertionError("replayed a saved experiment")

    monkeypatch.setattr(authors, "_play_experiment", refuse)
    found = run_authors_tournament(
        [("raise", "call")], experiments=[0], out=tmp_path, repeats=2, games=100
    )
    assert found["raise-vs-call"].experiments[0].repeats_mbb == (7.5, -2.5)


@pytest.mark.slow
def test_a_gym_study_folder_of_main_is_reused(tmp_path: Path) -> None:
    """Data, IRL and RL units (sb3 and lock-step) whose records main's gym/jobs.py wrote."""
    pytest.importorskip("gymnasium")
    pytest.importorskip("stable_baselines3")
    from pokerirl.studies.gym.config import study_preset
    from pokerirl.studies.gym.pipeline import data_job, irl_job, rl_jobs
    from pokerirl.studies.gym.units import DATA_FILE, run_data_jobs, run_irl_jobs, run_rl_jobs

    env = "MountainCar-v0"
    preset = study_preset("quick", tasks=(env,), runs=2, transitions=1_500, epochs=1,
                          eval_episodes=1, rl_timesteps=400)  # fmt: skip
    data = data_job(tmp_path, env, preset)
    irl = irl_job(tmp_path, env, "hairl", preset, data=tmp_path / DATA_FILE)
    rl = [*rl_jobs(tmp_path, env, "hairl", irl, preset, backend="lockstep"),
          *rl_jobs(tmp_path, env, "env", None, preset, backend="sb3")]  # fmt: skip

    def study() -> tuple[int, int, int]:
        backend = Backend()
        return (run_data_jobs([data], backend=backend), run_irl_jobs([irl], backend=backend),
                run_rl_jobs(rl, backend=backend))  # fmt: skip

    assert study() == (0, 0, 0)
    # main's records, each with main's own formula: the input digests inside the config.
    save_record(tmp_path / "expert.unit.json", make_record(
        data.config(), files={DATA_FILE: data.path.read_bytes()}))  # fmt: skip
    main_irl = {
        "unit": "gym-irl", "env": env, "algo": "hairl", "runs": 2, "seed": preset.seed,
        "settings": asdict(irl.settings), "data": bytes_fingerprint(data.path.read_bytes()),
    }  # fmt: skip
    _as_main_wrote(irl.folder / "unit.json", main_irl, _recorded(irl.folder))
    for job in rl:
        main_rl = {
            "unit": "gym-rl", "env": env, "reward": job.reward, "seed": job.seed,
            "reward_run": None if job.reward_run is None else {
                name: bytes_fingerprint((job.reward_run / name).read_bytes())
                for name in ("config.json", "reward.pt")},
            "settings": asdict(job.settings), "evaluations": job.evaluations,
            "eval_episodes": job.eval_episodes,
            **({"backend": "lockstep"} if job.backend == "lockstep" else {}),
        }  # fmt: skip
        _as_main_wrote(job.folder / "unit.json", main_rl, _recorded(job.folder))
    before = {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in tmp_path.rglob("*") if p.is_file()}
    assert all(
        json.loads(p.read_text())["format"] == "pokerirl-unit/1"
        for p in tmp_path.rglob("*unit.json")
    )
    assert study() == (1, 1, 4)  # every unit reused: nothing trained, nothing rewritten
    after = {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before


def _recorded(folder: Path) -> list[str]:
    return sorted(json.loads((folder / "unit.json").read_text())["files"])
