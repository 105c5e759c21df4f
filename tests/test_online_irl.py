"""Online adversarial IRL (issue 43): SB3 PPO as the generator on real Gymnasium envs, tiny
budgets. The run folder is the offline one and loads; a seed gives the same bytes; the
discriminator sees the generator's own states; the saved policy is the generator."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from testkit import Cli, folder_bytes

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.gym.collect import collect
from pokerirl.gym.episodes import play_episodes, policy_actions
from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir
from pokerirl.gym.irl import irl_config, load_env_transitions, obs_standardization, standardized
from pokerirl.gym.online import OnlineSettings, PPOGenerator, train_gym_online
from pokerirl.gym.presets import TASKS
from pokerirl.gym.quality import run_quality
from pokerirl.irl import load_policy, load_reward
from pokerirl.irl.adversarial import default_nets
from pokerirl.irl.losses import gaussian_log_prob
from pokerirl.irl.online import OnlineTrainer, Rollout

CLI = Cli()
TINY = ["--mode", "online", "--rounds", "2", "--generator-steps", "256", "--generator-envs", "2"]


@pytest.fixture(scope="module")
def mountaincar(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("data") / "expert.parquet"
    collect(load_expert(resolve_expert_dir("shipped", "MountainCar-v0")), path,
            transitions=1200, seed=0)  # fmt: skip
    return path


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("data") / "expert.parquet"
    collect(load_expert(resolve_expert_dir("shipped", "Pendulum-v1")), path,
            transitions=600, seed=0)  # fmt: skip
    return path


def _generator_and_trainer(
    env_id: str, data_path: Path, *, algo: str, steps: int = 256
) -> tuple[PPOGenerator, OnlineTrainer, torch.Tensor]:
    """A real PPO generator and the online trainer on ``env_id``'s expert data."""
    settings = replace(TASKS[env_id].irl, epochs=1)
    config = irl_config(algo, settings, seed=0)
    data = load_env_transitions(env_id, data_path)
    shift, scale = obs_standardization(data)
    data = standardized(data, shift, scale)
    reward, policy = default_nets(data, config, 0)
    online = OnlineSettings(rounds=1, generator_steps=steps, envs=2)
    generator = PPOGenerator(env_id=env_id, reward=reward, policy=policy,
                             config_activation=config.activation,
                             policy_hidden=tuple(config.policy_hidden), shift=shift, scale=scale,
                             settings=online, seed=0)  # fmt: skip
    trainer = OnlineTrainer(demonstrations=data, validation=data, generator=generator,
                            reward=reward, config=config, generator_steps=steps)  # fmt: skip
    return generator, trainer, data.obs


@pytest.mark.slow
def test_an_online_run_writes_the_offline_run_folder_and_a_seed_gives_its_bytes(
    mountaincar: Path, tmp_path: Path
) -> None:
    args = ["gym", "irl", "MountainCar-v0", "--data", str(mountaincar), "--algo", "airl"]
    args += ["--runs", "1", "--epochs", "1", *TINY]
    first = CLI.ok(*args, "--out", tmp_path / "a")
    assert "run 0 round 1/2" in first and "run 0 round 2/2" in first  # a line a round
    CLI.ok(*args, "--out", tmp_path / "b")
    run = tmp_path / "a" / "run-0"
    config = json.loads((run / "config.json").read_text())
    assert config["data"]["mode"] == "online" and config["algo"] == "airl"
    assert config["data"]["generator"]["generator_steps"] == 256
    reward = load_reward(run)  # what gym rl --reward-run, EPIC and the reward map read
    assert reward(np.zeros((3, 2), np.float32), np.array([0, 1, 2])).shape == (3,)
    assert (run / "reward_quality.json").is_file()  # EPIC against the true reward
    lines = (run / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["epoch"] for line in lines] == [1, 2]
    same = {k: v for k, v in folder_bytes(tmp_path / "a").items() if "timings" not in k}
    again = {k: v for k, v in folder_bytes(tmp_path / "b").items() if "timings" not in k}
    assert same == again  # same seed, same bytes (all but the wall-clock timings)
    # Read where an offline run is: the reward quality (EPIC) reader and gym rl.
    written = json.loads((run / "reward_quality.json").read_text())
    (run / "reward_quality.json").unlink()  # computed again by the reader, as for an old run
    quality = run_quality(run, env_id="MountainCar-v0", data_path=mountaincar)
    assert quality == written and quality["epic"] is not None
    rl = ["gym", "rl", "MountainCar-v0", "--reward-run", run, "--runs", "1", "--timesteps", "300",
          "--evaluations", "1", "--eval-episodes", "1", "--quiet", "--out", tmp_path / "rl"]
    assert "final true return" in CLI.ok(*rl)
    assert (tmp_path / "rl" / "run-0" / "metrics.jsonl").is_file()


def test_the_discriminator_learns_on_the_generators_states(mountaincar: Path) -> None:
    """Every generator row of a round reaches the discriminator's batches (the reward net's
    inputs while it learns), and they are states the expert never visited."""
    generator, trainer, expert_obs = _generator_and_trainer("MountainCar-v0", mountaincar,
                                                            algo="gail")  # fmt: skip
    collected: list[Rollout] = []
    seen: list[torch.Tensor] = []
    collect_rollout, net = generator.collect, trainer.reward

    def recording_collect(steps: int) -> Rollout:
        rollout = collect_rollout(steps)
        collected.append(rollout)
        return rollout

    def recording_reward(obs: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        if torch.is_grad_enabled():  # the discriminator's step (relabelling runs without)
            seen.append(obs.detach().clone())
        return net(obs, actions)

    generator.collect = recording_collect  # type: ignore[method-assign]
    trainer.reward = recording_reward  # type: ignore[assignment]
    metrics = trainer.round()
    assert np.isfinite(metrics["disc_loss"]) and metrics["generator_steps"] == 256
    (rollout,) = collected
    generated = {tuple(row) for row in rollout.transitions.obs.tolist()}
    in_batches = {tuple(row) for row in torch.cat(seen).tolist()}
    expert = {tuple(row) for row in expert_obs.tolist()}
    assert generated <= in_batches  # 256 rows, batches of 64: all of them
    assert len(generated - expert) > 0.9 * len(generated)  # the generator's own states


def test_the_saved_policy_is_the_generator(mountaincar: Path, pendulum: Path) -> None:
    """policy_net copies the actor exactly: its log π equals the generator's, discrete and box."""
    for env_id, data, algo in (("MountainCar-v0", mountaincar, "airl"),
                               ("Pendulum-v1", pendulum, "hairl")):  # fmt: skip
        generator, trainer, expert_obs = _generator_and_trainer(env_id, data, algo=algo)
        trainer.round()  # PPO moved the actor away from its initialization
        policy = generator.policy_net()
        obs = expert_obs[:32]
        with torch.no_grad():
            if env_id == "MountainCar-v0":
                actions = torch.eye(3)[torch.arange(32) % 3]
                ours = (policy(obs, None) * actions).sum(-1)
            else:
                actions = torch.linspace(-2, 2, 32)[:, None]
                ours = gaussian_log_prob(actions, *policy(obs))
            theirs = generator.log_prob(obs, actions)
        torch.testing.assert_close(ours, theirs)


def test_the_hybrid_supervised_step_moves_the_generator_toward_the_expert(pendulum: Path) -> None:
    generator, trainer, _ = _generator_and_trainer("Pendulum-v1", pendulum, algo="hairl")
    data = trainer.data
    expert = data.action_vectors()
    before = generator.log_prob(data.obs, expert).mean().item()
    for _ in range(20):
        trainer.imitate()
    assert generator.log_prob(data.obs, expert).mean().item() > before
    # H-AIRL's noise: the discriminator sees noised actions, kept in the box
    obs, actions = data.obs[:64], expert[:64]
    _, noised = trainer.discriminator_inputs(obs, actions)
    assert not torch.equal(noised, actions) and float(noised.abs().max()) <= 2.0


@pytest.mark.slow
def test_a_continuous_online_run_trains_and_its_policy_replays_its_return(
    pendulum: Path, tmp_path: Path
) -> None:
    settings = replace(TASKS["Pendulum-v1"].irl, epochs=1, eval_episodes=1)
    result = train_gym_online(
        "Pendulum-v1", pendulum, algo="hairl", runs=1, settings=settings,
        online=OnlineSettings(rounds=2, generator_steps=256, envs=2), out=tmp_path / "irl",
        progress=False,
    )  # fmt: skip
    run = tmp_path / "irl" / "run-0"
    last = json.loads((run / "metrics.jsonl").read_text().splitlines()[-1])
    assert {"val_mse", "policy_sup_loss", "disc_loss"} <= set(last)
    assert np.isfinite(result.final_return.measured[0])
    policy = load_policy(run)  # raw observations: the standardization is folded in
    (replay,) = play_episodes(
        "Pendulum-v1", lambda obs: policy_actions(policy, obs, discrete=False), episodes=1
    )
    assert replay.mean == pytest.approx(last["eval_return"])
