"""EPIC and the reward-quality file: invariance to shaping and scale, 1/√2 for independent
rewards, the true rewards against the env's own, and a real tiny Pendulum IRL run scored."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

pytest.importorskip("gymnasium")

from pokerirl.gym.quality import (
    QUALITY_FILE,
    QualityError,
    RewardQuality,
    Rollouts,
    canonicalize,
    epic_distance,
    make_coverage,
    pearson,
    read_quality,
    roll_out,
    task_gamma,
    true_reward,
    write_reward_quality,
)
from pokerirl.irl.nets import ShapedReward
from pokerirl.irl.run import RewardFunction

GAMMA = 0.95
KEYS = {"pearson_expert", "pearson_policy", "epic", "epic_g", "epic_random_baseline"}


def continuous_world(n: int = 3000, seed: int = 0):
    rng = np.random.default_rng(seed)
    obs = rng.normal(size=(n, 3)).astype(np.float32)
    actions = rng.uniform(-1, 1, size=(n, 2)).astype(np.float32)
    next_obs = (obs + 0.3 * rng.normal(size=(n, 3))).astype(np.float32)
    coverage = make_coverage(
        rng.normal(size=(200, 3)).astype(np.float32),
        rng.uniform(-1, 1, size=(200, 2)).astype(np.float32),
        seed=seed,
    )
    return obs, actions, next_obs, coverage


def r(o: np.ndarray, a: np.ndarray, n: np.ndarray) -> np.ndarray:
    return -(o[:, 0] ** 2) + np.sin(o[:, 1]) * a[:, 0] - 0.5 * a[:, 1] ** 2 + np.tanh(n[:, 2])


def phi(x: np.ndarray) -> np.ndarray:
    return 4.0 * (3.0 * np.cos(x[:, 0]) + x[:, 1] * x[:, 2] + 2.0 * x[:, 2])


def shaped(o: np.ndarray, a: np.ndarray, n: np.ndarray) -> np.ndarray:
    return r(o, a, n) + GAMMA * phi(n) - phi(o)


def test_epic_is_zero_for_shaped_and_scaled_copies_and_raw_pearson_is_not() -> None:
    obs, actions, next_obs, coverage = continuous_world()
    world = dict(coverage=coverage, gamma=GAMMA)
    assert epic_distance(r, shaped, obs, actions, next_obs, **world) < 1e-4
    scaled = lambda o, a, n: 3.7 * r(o, a, n) - 12.0  # noqa: E731
    assert epic_distance(r, scaled, obs, actions, next_obs, **world) < 1e-4
    # The shaping is large: without canonicalization the two rewards are far apart.
    raw = pearson(r(obs, actions, next_obs), shaped(obs, actions, next_obs))
    assert math.sqrt((1 - raw) / 2) > 0.3
    # Shaping cancels exactly term by term: the canonical rewards are equal.
    np.testing.assert_allclose(
        canonicalize(r, obs, actions, next_obs, **world),
        canonicalize(shaped, obs, actions, next_obs, **world),
        atol=1e-5,
        rtol=0,
    )
    # A negated reward is at distance 1.
    negated = lambda o, a, n: -r(o, a, n)  # noqa: E731
    assert epic_distance(r, negated, obs, actions, next_obs, **world) == pytest.approx(1.0)


def test_epic_of_an_independent_random_reward_is_near_one_over_root_two() -> None:
    # Discrete states and actions; the random reward is an i.i.d. table over (s, a, s').
    rng = np.random.default_rng(1)
    states, acts, n = 40, 4, 20_000
    obs = rng.integers(0, states, size=(n, 1)).astype(np.float32)
    actions = rng.integers(0, acts, size=n)
    next_obs = rng.integers(0, states, size=(n, 1)).astype(np.float32)
    coverage = make_coverage(
        np.arange(states, dtype=np.float32).reshape(-1, 1), np.arange(states) % acts, seed=1
    )
    table = rng.normal(size=(states, acts, states))

    def noise(o: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
        return table[o[:, 0].astype(int), a, x[:, 0].astype(int)]

    def structured(o: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
        return np.cos(o[:, 0] / 7) + 0.5 * (a == 2) - (x[:, 0] > 30)

    distance = epic_distance(
        structured, noise, obs, actions, next_obs, coverage=coverage, gamma=GAMMA
    )
    assert abs(distance - 1 / math.sqrt(2)) < 0.02


def test_shaped_family_f_and_g_are_epic_equivalent() -> None:
    torch.manual_seed(0)
    net = ShapedReward(obs_dim=3, action_dim=2, hidden=(16,), gamma=GAMMA)
    full = RewardFunction(net, num_actions=None, full=True)
    g = RewardFunction(net, num_actions=None)
    obs, actions, next_obs, coverage = continuous_world(n=1500)

    def f_of(o, a, x):  # s' never terminal here
        return full(o, a, x, np.zeros(len(o), dtype=bool))

    def g_of(o, a, x):
        return g(o, a)

    assert epic_distance(f_of, g_of, obs, actions, next_obs, coverage=coverage, gamma=GAMMA) < 1e-3
    assert pearson(f_of(obs, actions, next_obs), g_of(obs, actions, next_obs)) < 0.999


def _random_rollouts(env_id: str, *, episodes: int) -> Rollouts:
    """Episodes of uniformly random actions (the action space seeded 0), from seed 0."""
    from pokerirl.gym.envs import make_env

    env = make_env(env_id)
    space = env.action_space
    env.close()
    space.seed(0)
    return roll_out(
        env_id, lambda o: np.stack([space.sample() for _ in o]), episodes=episodes, seed=0
    )


@pytest.mark.parametrize(
    ("env_id", "tolerance"),
    [("Pendulum-v1", 1e-4), ("Acrobot-v1", 0.0), ("MountainCar-v0", 0.0), ("LunarLander-v3", 1e-3)],
)
def test_true_step_reward_matches_the_env_on_random_rollouts(env_id: str, tolerance: float) -> None:
    if env_id == "LunarLander-v3":
        pytest.importorskip("Box2D")
    found = _random_rollouts(env_id, episodes=3)
    truth = true_reward(env_id, task_gamma(env_id))
    step = truth.step(found.obs, found.actions, found.next_obs)
    error = np.abs(step - found.rewards)
    if env_id == "LunarLander-v3":
        # Left out: each episode's first step (no previous shaping) and its ±100 at the end.
        assert np.mean(error <= tolerance) > 0.95
    else:
        assert error.max() <= tolerance
    if env_id == "MountainCar-v0":  # the absorbing-state bonus only on entering the goal
        goal = np.array([[0.0, 0.0], [0.55, 0.01]], np.float32)
        values = truth.reward(goal, np.zeros(2, int), goal)
        assert values[0] == -1 and values[1] == pytest.approx(0.98 / 0.02 - 1)


@pytest.mark.parametrize(("env_id", "least"), [("HalfCheetah-v4", 0.9), ("Ant-v4", 0.95)])
def test_mujoco_forward_reward_approximation_follows_the_env(env_id: str, least: float) -> None:
    pytest.importorskip("mujoco")
    found = _random_rollouts(env_id, episodes=1)
    truth = true_reward(env_id, task_gamma(env_id))
    assert truth.kind == "approximation"
    step = truth.step(found.obs, found.actions, found.next_obs)
    assert pearson(step, found.rewards) > least


def test_unknown_task_and_missing_run_are_one_line(tmp_path: Path) -> None:
    with pytest.raises(QualityError, match="unknown task"):
        write_reward_quality(tmp_path, env_id="CartPole-v1")
    with pytest.raises(QualityError, match="not a training run folder"):
        write_reward_quality(tmp_path, env_id="Pendulum-v1")
    assert not (tmp_path / QUALITY_FILE).exists()


def test_reward_quality_round_trips_with_null_scores_as_nan() -> None:
    found = {
        "format": "pokerirl-reward-quality/1", "env": "Pendulum-v1", "algo": "hairl",
        "reward_family": "state_action", "pearson_expert": None, "pearson_policy": 0.5,
        "epic": 0.25, "epic_g": 0.25, "epic_random_baseline": 0.7, "epic_expert_coverage": 0.3,
        "epic_random_baseline_expert_coverage": 0.71, "gamma": 0.95, "seed": 0, "samples": 10,
        "coverage": {"size": 4}, "true_reward": {"kind": "exact"},
        "true_reward_check": {"what": "r"}, "reward_sha256": "ab",
    }  # fmt: skip
    quality = RewardQuality.from_json(found)
    assert math.isnan(quality.pearson_expert) and quality.epic == 0.25
    assert quality.to_json() == found and list(quality.to_json()) == list(found)


@pytest.mark.slow
def test_a_real_tiny_pendulum_irl_run_is_scored(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    from pokerirl.gym.collect import collect
    from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir
    from pokerirl.gym.irl import train_gym_irl
    from pokerirl.gym.presets import TASKS

    data = tmp_path / "expert.parquet"
    collect(
        load_expert(resolve_expert_dir("shipped", "Pendulum-v1")), data, transitions=800, seed=0
    )
    settings = replace(TASKS["Pendulum-v1"].irl, epochs=1, eval_episodes=1)
    train_gym_irl(
        "Pendulum-v1", data, algo="hairl", runs=1, settings=settings, out=tmp_path / "irl",
        progress=False,
    )  # fmt: skip
    run = tmp_path / "irl" / "run-0"
    quality = write_reward_quality(run, env_id="Pendulum-v1", samples=400, episodes=2)
    first = (run / QUALITY_FILE).read_bytes()
    found = json.loads(first)
    assert KEYS <= set(found)
    for key in KEYS:
        assert found[key] == pytest.approx(getattr(quality, key), abs=1e-6)
    for key in ("pearson_expert", "pearson_policy"):
        assert -1 <= found[key] <= 1
    for key in ("epic", "epic_g", "epic_random_baseline"):
        assert 0 <= found[key] <= 1
    assert found["epic_g"] == found["epic"]  # state_action family: g is f
    assert found["gamma"] == 0.95 and found["true_reward"]["kind"] == "exact"
    assert found["true_reward_check"]["expert"]["max_abs_error"] < 1e-4
    assert "uniform over the action box" in found["coverage"]["actions"]
    write_reward_quality(run, env_id="Pendulum-v1", samples=400, episodes=2)
    assert (run / QUALITY_FILE).read_bytes() == first  # same inputs, same bytes
    # The file reads back typed, and writes back the same bytes.
    typed = read_quality(run)
    assert typed is not None and typed.reward_family == "state_action"
    assert json.dumps(typed.to_json(), indent=2, ensure_ascii=False) + "\n" == first.decode()
    assert typed.to_json() == quality.to_json() == found
