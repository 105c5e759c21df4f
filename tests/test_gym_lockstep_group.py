"""The lock-step RL runner and the --rl-backend switch (issue 19): train_rl_group gives what
train_rl gives per run (curve timesteps, evaluation seeds, run folders SB3 loads), runs do not
depend on their group, and gym rl / gym study resume lock-step groups run by run."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import torch
from testkit import Cli, folder_snapshot

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.execution import pinned_threads
from pokerirl.gym.episodes import EVAL_SEED, sb3_evaluation
from pokerirl.gym.expert_policies import build_policy, policy_kwargs
from pokerirl.gym.lockstep import LockstepPPO
from pokerirl.gym.lockstep.group import train_rl_group
from pokerirl.gym.presets import TASKS, PPOSettings, RLSettings
from pokerirl.gym.rl import train_rl
from pokerirl.studies.gym.units import RLJob

CARTPOLE = RLSettings(
    algo="ppo",
    timesteps=1024,
    ppo=PPOSettings(n_steps=256, batch_size=64, gamma=0.99, gae_lambda=0.95, clip_range=0.2,
                    ent_coef=0.0, vf_coef=0.5, max_grad_norm=0.5, learning_rate=1e-3,
                    n_epochs=3),
)  # fmt: skip
_PENDULUM = TASKS["Pendulum-v1"].rl
PENDULUM = dataclasses.replace(
    _PENDULUM, ppo=dataclasses.replace(_PENDULUM.ppo, n_steps=128, n_epochs=2)
)
FILES = ("config.json", "metrics.jsonl", "model.pt")

CLI = Cli()  # pokerirl run in this process (tests/testkit.py)


@pytest.fixture(autouse=True)
def one_thread():
    """As the CLI and the units run RL: on busy cores, small ops on two threads crawl."""
    with pinned_threads(1):
        yield


def group(env: str, settings: RLSettings, seeds: list[int], outs: list[Path] | None = None,
          *, timesteps: int = 1000, evaluations: int = 3, episodes: int = 2) -> list:
    return train_rl_group(env, rewards=[None] * len(seeds), reward_names=["env"] * len(seeds),
                          seeds=seeds, settings=settings, timesteps=timesteps,
                          evaluations=evaluations, eval_episodes=episodes, outs=outs)


def test_run_of_a_group_equals_a_group_of_one(tmp_path: Path) -> None:
    outs = [tmp_path / "g" / f"run-{k}" for k in range(3)]
    three = group("CartPole-v1", CARTPOLE, [0, 1, 2], outs)
    one = group("CartPole-v1", CARTPOLE, [2], [tmp_path / "alone"])
    assert one[0] == three[2]  # curve, training episodes, seed, name
    assert len({r.train_episode_returns for r in three}) == 3  # the seeds do differ
    # Bit for bit: a resumed study's group of the unfinished runs writes the same bytes.
    for name in FILES[1:]:
        assert (outs[2] / name).read_bytes() == (tmp_path / "alone" / name).read_bytes()


@pytest.mark.parametrize(("timesteps", "evaluations", "expected"), [
    (1000, 3, [333, 666, 999, 1024]),  # the budget rounded up to whole rollouts
    (1024, 4, [256, 512, 768, 1024]),  # none at the budget itself but the final one
])  # fmt: skip
def test_curve_timesteps_are_train_rls(timesteps: int, evaluations: int,
                                       expected: list[int]) -> None:
    """Evaluations where train_rl's callback makes them, and one at the end."""
    kwargs = {"timesteps": timesteps, "evaluations": evaluations, "eval_episodes": 1}
    sb3 = train_rl("CartPole-v1", reward=None, reward_name="env", seed=0, settings=CARTPOLE,
                   **kwargs)  # fmt: skip
    ours = train_rl_group("CartPole-v1", rewards=[None], reward_names=["env"], seeds=[0],
                          settings=CARTPOLE, **kwargs)[0]  # fmt: skip
    assert [p.timesteps for p in ours.curve] == [p.timesteps for p in sb3.curve]
    assert [p.timesteps for p in ours.curve] == expected
    assert ours.timesteps == sb3.timesteps == timesteps
    # One Monitor episode per finished training episode in both.
    assert 1024 / 60 < len(ours.train_episode_returns) <= 1024 / 9


@pytest.mark.parametrize(("env", "settings"), [("CartPole-v1", CARTPOLE),
                                               ("Pendulum-v1", PENDULUM)])
def test_run_folder_loads_into_sb3_and_replays_the_last_point(
    tmp_path: Path, env: str, settings: RLSettings
) -> None:
    """model.pt loads strictly into SB3's policy, whose deterministic episodes on the
    evaluation seeds give the curve's last point: the batched evaluation is SB3's."""
    outs = [tmp_path / "run-0", tmp_path / "run-1"]
    results = group(env, settings, [3, 4], outs, timesteps=512, evaluations=1, episodes=3)
    sb3_folder = tmp_path / "sb3"
    train_rl(env, reward=None, reward_name="env", seed=0, settings=settings, timesteps=256,
             evaluations=1, eval_episodes=1, out=sb3_folder)  # fmt: skip
    sb3_config = json.loads((sb3_folder / "config.json").read_text())
    for out, result in zip(outs, results, strict=True):
        assert sorted(p.name for p in out.iterdir()) == sorted(FILES)
        config = json.loads((out / "config.json").read_text())
        assert config.pop("backend") == "lockstep"
        assert config.keys() == sb3_config.keys()
        assert config["final_return"] == result.final_return and config["seed"] == result.seed
        lines = (out / "metrics.jsonl").read_text().splitlines()
        assert [json.loads(line)["timesteps"] for line in lines] == [512]
        policy = build_policy(env, "ppo", config["policy_kwargs"])
        policy.load_state_dict(torch.load(out / "model.pt", weights_only=True), strict=True)
        replay = sb3_evaluation(policy, env, episodes=3, seed=EVAL_SEED)
        assert replay.mean == pytest.approx(result.curve[-1].return_mean, rel=1e-4)
        assert replay.std == pytest.approx(result.curve[-1].return_std, rel=1e-3, abs=1e-3)
    assert config["policy_kwargs"] == policy_kwargs(settings)


def test_predict_is_sb3s_deterministic_action() -> None:
    trained = LockstepPPO("Pendulum-v1", PENDULUM.ppo, seeds=[0, 1])
    trained.learn(128)
    obs = np.random.default_rng(0).uniform(-1, 1, (2, 50, 3)).astype(np.float32)
    weights = [dict(w) for w in trained.result().state_dicts]
    # Shift run 0's means to straddle the upper bound, 2, so that the clip matters.
    shift = 2.0 - float(np.median(trained.predict(obs)[0]))
    weights[0]["action_net.bias"] = weights[0]["action_net.bias"] + shift
    ppo = LockstepPPO("Pendulum-v1", PENDULUM.ppo, seeds=[0, 1], weights=weights)
    actions = ppo.predict(obs)
    assert actions.shape == (2, 50, 1)
    assert (actions[0] == 2.0).any() and (actions[0] < 2.0).any()
    for r in range(2):
        policy = build_policy("Pendulum-v1", "ppo", policy_kwargs(PENDULUM))
        policy.load_state_dict(ppo.policy.run_state_dict(r), strict=True)
        theirs, _ = policy.predict(obs[r], deterministic=True)
        np.testing.assert_allclose(actions[r], theirs, atol=1e-5)
    with pytest.raises(ValueError, match="predict: observations of shape"):
        ppo.predict(obs[0])


def test_learn_calls_back_after_every_step() -> None:
    seen: list[int] = []
    result = LockstepPPO("CartPole-v1", CARTPOLE.ppo, seeds=[0, 1]).learn(300,
                                                                          callback=seen.append)
    assert seen == list(range(1, 513)) and result.timesteps == 512


def test_mountaincar_dqn_runs_in_lock_step_and_sb3_loads_the_folders(tmp_path: Path) -> None:
    """gym rl --rl-backend lockstep trains the DQN task as one group: each folder's model.pt
    loads into SB3's DQN policy, whose deterministic episodes replay the curve's last point,
    and run 1 is what a group of one with seed 1 writes."""
    out = tmp_path / "mc"  # 1,200 steps: 200 after learning_starts, 100 gradient steps
    args = ["gym", "rl", "MountainCar-v0", "--env-reward", "--runs", "2", "--timesteps", "1200",
            "--evaluations", "1", "--eval-episodes", "1", "--rl-backend", "lockstep"]
    result = CLI.invoke([*args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    for k in range(2):
        config = json.loads((out / f"run-{k}" / "config.json").read_text())
        assert config["backend"] == "lockstep" and config["algo"] == "dqn"
        policy = build_policy("MountainCar-v0", "dqn", config["policy_kwargs"])
        policy.load_state_dict(torch.load(out / f"run-{k}" / "model.pt", weights_only=True),
                               strict=True)  # fmt: skip
        replay = sb3_evaluation(policy, "MountainCar-v0", episodes=1, seed=EVAL_SEED)
        assert replay.mean == pytest.approx(config["final_return"])
    group("MountainCar-v0", TASKS["MountainCar-v0"].rl, [1], [tmp_path / "alone"],
          timesteps=1200, evaluations=1, episodes=1)  # fmt: skip
    trained = (out / "run-1" / "model.pt").read_bytes()
    assert trained == (tmp_path / "alone" / "model.pt").read_bytes()
    assert trained != (out / "run-0" / "model.pt").read_bytes()


def test_sb3_rl_records_are_as_before() -> None:
    """The backend enters an RL unit's fingerprinted config for lock-step runs only, so
    studies made before the switch are reused."""
    job = RLJob(env="Acrobot-v1", reward="env", reward_run=None, seed=0,
                settings=TASKS["Acrobot-v1"].rl, evaluations=2, eval_episodes=1,
                folder=Path("rl/env/run-0"))  # fmt: skip
    identity = job.unit(None).identity  # the fingerprinted config and inputs together
    assert set(identity) == {"unit", "env", "reward", "reward_run", "seed", "settings",
                             "evaluations", "eval_episodes"}  # fmt: skip
    lockstep = dataclasses.replace(job, backend="lockstep").unit(None).identity
    assert lockstep == {**identity, "backend": "lockstep"}


RL_ARGS = ["gym", "rl", "Acrobot-v1", "--env-reward", "--runs", "3", "--timesteps", "1024",
           "--evaluations", "2", "--eval-episodes", "1", "--rl-backend", "lockstep"]


@pytest.mark.slow
def test_gym_rl_lockstep_resumes_the_missing_run_only(tmp_path: Path) -> None:
    out = tmp_path / "rl"
    args = [*RL_ARGS, "--out", str(out)]
    first = CLI.invoke(args)
    assert first.exit_code == 0, first.output
    before = folder_snapshot(out)
    for k in range(3):  # each run its own unit
        record = json.loads((out / f"run-{k}" / "unit.json").read_text())
        assert record["config"]["backend"] == "lockstep"
    lost = {name: (out / "run-1" / name).read_bytes() for name in FILES}
    for path in (out / "run-1").iterdir():
        path.unlink()
    (out / "run-1").rmdir()
    again = CLI.invoke(args)
    assert again.exit_code == 0, again.output
    after = folder_snapshot(out)
    # run-0 and run-2 untouched (same bytes, same files); run-1 trained alone, as in the group
    assert {k: v for k, v in after.items() if not k.startswith("run-1")} == {
        k: v for k, v in before.items() if not k.startswith("run-1")}
    assert {name: (out / "run-1" / name).read_bytes() for name in FILES} == lost
    kept = folder_snapshot(out)
    for changed in (["--timesteps", "2048"], ["--rl-backend", "sb3"]):
        refused = CLI.invoke([*args, *changed])
        assert refused.exit_code == 1
        lines = refused.output.strip().splitlines()
        assert len(lines) == 1 and "another configuration" in lines[0] and "--overwrite" in lines[0]
        assert folder_snapshot(out) == kept


STUDY = ["gym", "study", "Acrobot-v1", "--runs", "2", "--transitions", "1200", "--epochs", "1",
         "--eval-episodes", "1", "--timesteps", "1024", "--jobs", "2", "--quiet",
         "--rl-backend", "lockstep"]


@pytest.mark.slow
def test_gym_study_lockstep_reuses_every_unit(tmp_path: Path) -> None:
    out = tmp_path / "study"
    first = CLI.invoke([*STUDY, "--out", str(out)])
    assert first.exit_code == 0, first.output
    for reward in ("env", "airl", "hairl"):
        for k in range(2):
            run = out / "rl" / reward / f"run-{k}"
            assert json.loads((run / "config.json").read_text())["backend"] == "lockstep"
            assert json.loads((run / "unit.json").read_text())["config"]["backend"] == "lockstep"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["rl_backend"] == "lockstep"
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    again = CLI.invoke([*STUDY, "--out", str(out)])
    assert again.exit_code == 0, again.output
    assert "6 of 6 finished already, reused" in again.output
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    # A lost run is trained alone (a group of one) into what the group had made.
    lost = out / "rl" / "airl" / "run-1"
    for path in lost.iterdir():
        path.unlink()
    resumed = CLI.invoke([*STUDY, "--out", str(out)])
    assert resumed.exit_code == 0, resumed.output
    assert "5 of 6 finished already, reused" in resumed.output
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    # sb3 runs never pass for lock-step ones
    refused = CLI.invoke([*STUDY[:-2], "--rl-backend", "sb3", "--out", str(out)])
    assert refused.exit_code == 1
    assert "backend 'lockstep' -> None" in refused.output.strip().splitlines()[-1]


def test_a_group_is_one_folder_of_runs() -> None:
    """Study: one group per task and reward kind; sweep: one per point (its own rl/ folder)."""
    from pokerirl.studies.gym.config import study_preset
    from pokerirl.studies.gym.pipeline import rl_jobs

    preset = study_preset("quick", tasks=("Acrobot-v1",), runs=3)
    jobs = [job for root in ("points/a", "points/b")
            for job in rl_jobs(Path(root), "Acrobot-v1", "env", None, preset, backend="lockstep")]
    groups: dict[tuple, list[int]] = {}
    for job in jobs:
        groups.setdefault(job.group_key(), []).append(job.seed)
    assert sorted(groups.values()) == [[0, 1, 2], [0, 1, 2]]
    assert {job.config()["backend"] for job in jobs} == {"lockstep"}


def test_the_cli_default_backend_is_the_librarys() -> None:
    """The CLI spells the default out (importing pokerirl.gym.rl would load SB3): keep the two
    in step. Since the equivalence table held, lockstep is the default everywhere."""
    from pokerirl.cli.gym import RL_BACKEND
    from pokerirl.gym.rl import DEFAULT_RL_BACKEND

    assert RL_BACKEND.default == DEFAULT_RL_BACKEND == "lockstep"
