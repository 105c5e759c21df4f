"""The learned reward scored directly against the true env reward: Pearson and EPIC.

:func:`write_reward_quality` writes ``reward_quality.json`` into a Gymnasium IRL run folder
(``run-<k>`` of :func:`pokerirl.gym.irl.train_gym_irl`):

- ``pearson_expert`` / ``pearson_policy``: Pearson correlation of the learned f and the true
  r on the expert's transitions (a sample of the run's data) and on the run's policy's (its
  deterministic evaluation policy rolled out in the env);
- ``epic``: the EPIC distance (Gleave et al. 2021, "Quantifying Differences in Reward
  Functions") of f and r; ``epic_g`` the same for the transferable reward g (equal to f for
  the ``state_action`` family); ``epic_random_baseline`` that of a randomly initialised reward
  net of the same architecture, seeded as the run's own initial net.

EPIC canonicalizes a reward R with a coverage distribution of states D_S and actions D_A,

    C(R)(s, a, s') = R(s, a, s') + γ E[R(s', A, S')] − E[R(s, A, S')] − γ E[R(S, A, S')],

which removes potential shaping γφ(s') − φ(s) exactly, and then takes
``sqrt((1 − ρ) / 2)`` of the Pearson ρ of the canonical rewards over coverage transitions;
positive scaling does not change ρ either. 0 means the same reward up to shaping and scale,
1/√2 ≈ 0.707 uncorrelated, 1 opposite. Here (stated in the JSON):

- D_S: observations of the expert's data and of uniformly random rollouts, half each;
  the expectations use a fixed sample of ``coverage`` states S, actions A ~ D_A and next
  states S' = a permutation of the same S (so E over S and over S' are the same sum, and
  shaping cancels to rounding error, not just in expectation);
- D_A: uniform over the action box, or uniform over the discrete actions;
- the transitions ρ is taken over: real (s, a, s') of the expert's data and of the random
  rollouts, half each (s' follows from s and a, so rewards on s' such as reaching the goal
  occur);
- γ: the task's RL-phase discount (:mod:`pokerirl.gym.presets`).

The true reward r(s, a, s') must be computable on any transition; :func:`true_reward` gives
it per task, with what it is (exact, exact up to shaping, or an approximation) and a check
against the rewards recorded along rollouts (``true_reward_check``).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pokerirl.atomic import write_text
from pokerirl.errors import PokerIRLError
from pokerirl.execution import pinned_threads
from pokerirl.gym.collect import read_transitions
from pokerirl.gym.envs import make_env
from pokerirl.gym.episodes import episode_steps, policy_actions
from pokerirl.gym.presets import TASKS
from pokerirl.irl.nets import RewardFamily, fold_obs_standardization
from pokerirl.irl.run import (
    CONFIG_FILE,
    REWARD_FILE,
    RewardFunction,
    build_from_record,
    load_policy,
    load_reward,
    load_run_config,
)
from pokerirl.jsonio import read_json
from pokerirl.serial import Json, Serializable

QUALITY_FILE = "reward_quality.json"
QUALITY_FORMAT = "pokerirl-reward-quality/1"
QUALITY_SEED = 20_000  # rollouts start from reset(seed=QUALITY_SEED + k): not the eval seeds
DIGITS = 6  # JSON values rounded: the same bytes whatever the BLAS's summation order
CHUNK = 1 << 18  # rows per batched reward call in the expectations

SCORES = (
    "pearson_expert",
    "pearson_policy",
    "epic",
    "epic_g",
    "epic_random_baseline",
    "epic_expert_coverage",
    "epic_random_baseline_expert_coverage",
)

# A batched reward on transitions: (obs (n, d), actions (n,) or (n, k), next_obs (n, d)) -> (n,)
TransitionReward = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class QualityError(PokerIRLError, ValueError):
    """A run folder or task that cannot be scored; the message is one line."""


# --------------------------------------------------------------------------- EPIC


@dataclass(frozen=True, kw_only=True)
class Coverage:
    """The fixed sample behind the canonicalization's expectations: states S ~ D_S, actions
    A ~ D_A and next states S' (a permutation of S), ``m`` of each, row j one triple."""

    states: np.ndarray
    actions: np.ndarray
    next_states: np.ndarray

    @property
    def m(self) -> int:
        return len(self.states)


def make_coverage(states: np.ndarray, actions: np.ndarray, *, seed: int) -> Coverage:
    """Triples (S_j, A_j, S'_j) with S'_j = S_π(j) for a seeded permutation π."""
    if len(states) != len(actions) or len(states) < 2:
        raise ValueError("coverage needs as many actions as states, at least 2")
    perm = np.random.default_rng(seed).permutation(len(states))
    return Coverage(states=states, actions=actions, next_states=states[perm])


def _expected_from(reward: TransitionReward, x: np.ndarray, coverage: Coverage) -> np.ndarray:
    """E_j[R(x_i, A_j, S'_j)] for every row x_i: n · m reward calls, in chunks."""
    m = coverage.m
    out = np.empty(len(x), dtype=np.float64)
    rows = max(1, CHUNK // m)
    for start in range(0, len(x), rows):
        block = x[start : start + rows]
        obs = np.repeat(block, m, axis=0)
        actions = np.tile(coverage.actions, (len(block),) + (1,) * (coverage.actions.ndim - 1))
        nxt = np.tile(coverage.next_states, (len(block), 1))
        values = np.asarray(reward(obs, actions, nxt), dtype=np.float64)
        out[start : start + rows] = values.reshape(len(block), m).mean(axis=1)
    return out


def canonicalize(
    reward: TransitionReward,
    obs: np.ndarray,
    actions: np.ndarray,
    next_obs: np.ndarray,
    *,
    coverage: Coverage,
    gamma: float,
) -> np.ndarray:
    """C(R)(s, a, s') on each transition (float64)."""
    own = np.asarray(reward(obs, actions, next_obs), dtype=np.float64)
    after = _expected_from(reward, next_obs, coverage)
    before = _expected_from(reward, obs, coverage)
    overall = float(
        np.asarray(
            reward(coverage.states, coverage.actions, coverage.next_states), dtype=np.float64
        ).mean()
    )
    return own + gamma * after - before - gamma * overall


def pearson(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson's ρ; NaN when either side is constant.

    >>> round(pearson(np.array([1.0, 2, 3]), np.array([2.0, 4, 7])), 4)
    0.9934
    """
    x, y = np.asarray(x, np.float64) - np.mean(x), np.asarray(y, np.float64) - np.mean(y)
    denominator = math.sqrt(float(x @ x) * float(y @ y))
    if denominator <= 1e-300 or not math.isfinite(denominator):
        return math.nan
    return float(np.clip(float(x @ y) / denominator, -1.0, 1.0))


def epic_distance(
    a: TransitionReward,
    b: TransitionReward,
    obs: np.ndarray,
    actions: np.ndarray,
    next_obs: np.ndarray,
    *,
    coverage: Coverage,
    gamma: float,
) -> float:
    """sqrt((1 − ρ) / 2) of the canonical rewards' Pearson ρ over the given transitions."""
    ca = canonicalize(a, obs, actions, next_obs, coverage=coverage, gamma=gamma)
    cb = canonicalize(b, obs, actions, next_obs, coverage=coverage, gamma=gamma)
    rho = pearson(ca, cb)
    return math.nan if math.isnan(rho) else math.sqrt(max(0.0, (1.0 - rho) / 2.0))


# --------------------------------------------------------------------------- true rewards


@dataclass(frozen=True, kw_only=True)
class TrueReward:
    """r(s, a, s') of a task on any transition, and what it is.

    ``step`` is the env's per-step reward as far as (s, a, s') determine it (compared with
    recorded rewards); ``reward`` adds, where an episode ends in a terminal state, the
    absorbing-state bonus that makes the episodic reward an infinite-horizon one (EPIC's
    setting): a constant per-step reward c that stops at termination equals, up to potential
    shaping, −γc/(1−γ) on the transition into the terminal state.
    """

    env: str
    kind: str  # "exact", "exact up to potential shaping", "approximation"
    description: str
    step: TransitionReward
    reward: TransitionReward


def _pendulum(obs: np.ndarray, actions: np.ndarray, next_obs: np.ndarray) -> np.ndarray:
    theta = np.arctan2(obs[:, 1], obs[:, 0])  # in (−π, π]: Pendulum's angle_normalize
    u = np.clip(np.asarray(actions, np.float64).reshape(len(obs), -1)[:, 0], -2.0, 2.0)
    return -(theta**2 + 0.1 * obs[:, 2] ** 2 + 0.001 * u**2)


def _acrobot_terminal(next_obs: np.ndarray) -> np.ndarray:
    c1, s1, c2, s2 = next_obs[:, 0], next_obs[:, 1], next_obs[:, 2], next_obs[:, 3]
    return -c1 - (c1 * c2 - s1 * s2) > 1.0  # −cos θ1 − cos(θ1 + θ2) > 1


def _mountaincar_goal(next_obs: np.ndarray) -> np.ndarray:
    return (next_obs[:, 0] >= 0.5) & (next_obs[:, 1] >= 0.0)


def _lunar_shaping(x: np.ndarray) -> np.ndarray:
    return (
        -100 * np.sqrt(x[:, 0] ** 2 + x[:, 1] ** 2)
        - 100 * np.sqrt(x[:, 2] ** 2 + x[:, 3] ** 2)
        - 100 * np.abs(x[:, 4])
        + 10 * x[:, 6]
        + 10 * x[:, 7]
    )


def _lunar(obs: np.ndarray, actions: np.ndarray, next_obs: np.ndarray) -> np.ndarray:
    a = np.asarray(actions).reshape(-1)
    fuel = 0.30 * (a == 2) + 0.03 * ((a == 1) | (a == 3))
    return _lunar_shaping(next_obs) - _lunar_shaping(obs) - fuel


def _ctrl(actions: np.ndarray, n: int) -> np.ndarray:
    a = np.asarray(actions, np.float64).reshape(n, -1)
    return (a * a).sum(axis=1)


def _ant_unhealthy(next_obs: np.ndarray) -> np.ndarray:
    z = next_obs[:, 0]
    return ~(np.isfinite(next_obs).all(axis=1) & (z >= 0.2) & (z <= 1.0))


def has_true_reward(env_id: str) -> bool:
    """Whether :func:`true_reward` knows ``env_id``'s reward as a function of (s, a, s'): the
    paper's six tasks. Another task's reward lives only in its environment's code, so its IRL
    runs get no ``reward_quality.json`` (issue 34)."""
    return env_id in TASKS


def true_reward(env_id: str, gamma: float) -> TrueReward:
    """The true reward of one of the six tasks (see each ``description``)."""
    bonus = gamma / (1.0 - gamma)  # −γc/(1−γ) for c = −1; its negative for c = +1 (Ant)

    def const(c: float) -> TransitionReward:
        return lambda o, a, n: np.full(len(o), c)

    if env_id == "Pendulum-v1":
        return TrueReward(
            env=env_id,
            kind="exact",
            description="−(θ² + 0.1 θ̇² + 0.001 u²), θ = atan2(sin θ, cos θ) of s, u the "
            "action clipped to [−2, 2]",
            step=_pendulum,
            reward=_pendulum,
        )
    if env_id == "Acrobot-v1":
        return TrueReward(
            env=env_id,
            kind="exact up to potential shaping",
            description="the env's −1 per step, 0 into the terminal state (−cos θ1 − "
            "cos(θ1+θ2) > 1 at s'); plus γ/(1−γ) into it for the absorbing state",
            step=lambda o, a, n: np.where(_acrobot_terminal(n), 0.0, -1.0),
            reward=lambda o, a, n: np.where(_acrobot_terminal(n), bonus, -1.0),
        )
    if env_id == "MountainCar-v0":
        return TrueReward(
            env=env_id,
            kind="exact up to potential shaping",
            description="the env's −1 per step; plus γ/(1−γ) into the goal (position ≥ 0.5 "
            "and velocity ≥ 0 at s') for the absorbing state; the 200-step time limit ignored",
            step=const(-1.0),
            reward=lambda o, a, n: np.where(_mountaincar_goal(n), bonus - 1.0, -1.0),
        )
    if env_id == "LunarLander-v3":
        return TrueReward(
            env=env_id,
            kind="approximation",
            description="shaping(s') − shaping(s) − fuel(a) (0.3 main engine, 0.03 side), the "
            "env's own terms read off the observations; the terminal −100 (crash, out of "
            "bounds) and +100 (at rest) need the physics state and are left out, as is the "
            "first step's (no previous shaping)",
            step=_lunar,
            reward=_lunar,
        )
    if env_id == "HalfCheetah-v4":

        def cheetah(o: np.ndarray, a: np.ndarray, n: np.ndarray) -> np.ndarray:
            return (o[:, 8] + n[:, 8]) / 2 - 0.1 * _ctrl(a, len(o))

        return TrueReward(
            env=env_id,
            kind="approximation",
            description="(v_x(s) + v_x(s'))/2 − 0.1‖a‖²: the forward reward Δx/dt needs x, "
            "which is not observed; the mean of the root's x velocity (observation 8) at s and "
            "s' stands in for it (ρ ≈ 0.97 with the env's reward on random rollouts)",
            step=cheetah,
            reward=cheetah,
        )
    if env_id == "Ant-v4":

        def ant_step(o: np.ndarray, a: np.ndarray, n: np.ndarray) -> np.ndarray:
            return 1.0 + (o[:, 13] + n[:, 13]) / 2 - 0.5 * _ctrl(a, len(o))

        return TrueReward(
            env=env_id,
            kind="approximation",
            description="1 (healthy) + (v_x(s) + v_x(s'))/2 − 0.5‖a‖²: the forward reward "
            "Δx/dt needs x, which is not observed; the mean of the torso's x velocity "
            "(observation 13) at s and s' stands in for it (ρ ≈ 0.99 with the env's reward on "
            "random rollouts); minus γ/(1−γ) into an unhealthy s' (z outside [0.2, 1]) for the "
            "absorbing state; no contact cost (v4's default)",
            step=ant_step,
            reward=lambda o, a, n: ant_step(o, a, n) - bonus * _ant_unhealthy(n),
        )
    raise QualityError(f"no true reward for {env_id!r}; choose one of {', '.join(TASKS)}")


def task_gamma(env_id: str) -> float:
    """The task's RL-phase discount (PPO's or DQN's gamma)."""
    rl = TASKS[env_id].rl
    settings = rl.ppo if rl.ppo is not None else rl.dqn
    assert settings is not None  # RLSettings checks it
    return float(settings.gamma)


# --------------------------------------------------------------------------- rollouts


@dataclass(frozen=True, kw_only=True)
class Rollouts:
    """Transitions (s, a, r, s') with the env's recorded rewards."""

    obs: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    next_obs: np.ndarray

    def __len__(self) -> int:
        return len(self.obs)

    def take(self, n: int, rng: np.random.Generator) -> Rollouts:
        """At most ``n`` rows, a seeded sample in their order."""
        if len(self) <= n:
            return self
        rows = np.sort(rng.choice(len(self), size=n, replace=False))
        return Rollouts(
            obs=self.obs[rows],
            actions=self.actions[rows],
            rewards=self.rewards[rows],
            next_obs=self.next_obs[rows],
        )


def roll_out(
    env_id: str, act: Callable[[np.ndarray], np.ndarray], *, episodes: int, seed: int
) -> Rollouts:
    """``episodes`` episodes in lock-step (episode k from ``reset(seed=seed + k)``)."""

    steps = list(episode_steps(env_id, act, episodes=episodes, seed=seed))
    return Rollouts(
        obs=np.asarray([s.obs for s in steps], np.float32),
        actions=np.asarray([s.action for s in steps]),
        rewards=np.asarray([s.reward for s in steps], np.float64),
        next_obs=np.asarray([s.next_obs for s in steps], np.float32),
    )


def _expert_rollouts(path: Path) -> Rollouts:
    table = read_transitions(path)
    return Rollouts(
        obs=table["obs"].astype(np.float32),
        actions=table["action"].copy(),  # writable: torch warns on views
        rewards=table["reward"].astype(np.float64),
        next_obs=table["next_obs"].astype(np.float32),
    )


# --------------------------------------------------------------------------- the run's rewards


def _as_transition_reward(function: RewardFunction, *, full: bool) -> TransitionReward:
    def reward(obs: np.ndarray, actions: np.ndarray, next_obs: np.ndarray) -> np.ndarray:
        obs32 = np.asarray(obs, np.float32)
        if full:  # f of the shaped family: s' never terminal on coverage transitions
            done = np.zeros(len(obs32), dtype=bool)
            return function(obs32, actions, np.asarray(next_obs, np.float32), done)
        return function(obs32, actions)

    return reward


def initial_reward(record: Mapping[str, Any]) -> RewardFunction:
    """The run's reward net as it was before training: same architecture, built from the
    run's seed as :func:`pokerirl.irl.adversarial.default_nets` does, standardization folded in."""
    space = record["architecture"]["action_space"]
    discrete = space["type"] == "discrete"
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(int(record["hyperparameters"]["seed"]))
        net, _ = build_from_record(record)
    standard = (record.get("data") or {}).get("obs_standardization")
    if standard:
        fold_obs_standardization(
            net, torch.tensor(standard["shift"]), torch.tensor(standard["scale"])
        )
    return RewardFunction(net, num_actions=space["num_actions"] if discrete else None)


# --------------------------------------------------------------------------- the file


@dataclass(frozen=True, kw_only=True)
class RewardQuality(Serializable):
    """What ``reward_quality.json`` holds (NaN there is null: a constant reward)."""

    env: str
    algo: str
    reward_family: str
    pearson_expert: float
    pearson_policy: float
    epic: float
    epic_g: float
    epic_random_baseline: float
    epic_expert_coverage: float  # f's EPIC with D_S and the transitions the expert's only
    epic_random_baseline_expert_coverage: float
    gamma: float
    seed: int
    samples: int
    coverage: Mapping[str, Any]
    true_reward: Mapping[str, Any]
    true_reward_check: Mapping[str, Any]
    reward_sha256: str  # of the run's reward.pt: a stale file is one whose digest differs

    def to_json(self) -> Json:
        """The file's object: ``format`` first, the scores rounded (NaN: null)."""
        record = {"format": QUALITY_FORMAT, **super().to_json()}
        return record | {key: _number(getattr(self, key)) for key in SCORES}

    @classmethod
    def from_json(cls, data: Json, path: str = "") -> RewardQuality:
        """A file's object (null scores read as NaN)."""
        if isinstance(data, Mapping):
            nulls = [key for key in SCORES if key in data and data[key] is None]
            data = {**data, **dict.fromkeys(nulls, math.nan)}
        return super().from_json(data, path)


def _number(x: float) -> float | None:
    return None if x is None or not math.isfinite(x) else round(float(x), DIGITS)


@dataclass(frozen=True)
class _UniformActions:
    """Uniform draws from an action space: D_A of the coverage, the random rollouts' policy."""

    space: Any  # Discrete (n) or Box (low, high)

    @property
    def discrete(self) -> bool:
        return hasattr(self.space, "n")

    def __call__(self, n: int, generator: np.random.Generator) -> np.ndarray:
        if self.discrete:
            return generator.integers(0, int(self.space.n), size=n)
        low, high = self.space.low.astype(np.float64), self.space.high.astype(np.float64)
        return generator.uniform(low, high, size=(n, len(low))).astype(np.float32)

    def describe(self) -> str:
        if self.discrete:
            return f"uniform over the {int(self.space.n)} discrete actions"
        return "uniform over the action box"


@dataclass(frozen=True, kw_only=True)
class _Sample:
    """Every transition and coverage behind the scores, drawn in one seeded order."""

    expert: Rollouts  # as many rows as ``random``: ρ is taken over both
    random: Rollouts
    on_policy: Rollouts
    cover: Coverage  # D_S half the expert's states, half the random rollouts'
    expert_cover: Coverage  # D_S the expert's states alone

    def transitions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ρ's rows (s, a, s'): the expert's, then the random rollouts'."""
        return (
            np.concatenate([self.expert.obs, self.random.obs]),
            np.concatenate([self.expert.actions, self.random.actions]),
            np.concatenate([self.expert.next_obs, self.random.next_obs]),
        )


def _run_record(
    run: Path, data_path: str | os.PathLike[str] | None
) -> tuple[Mapping[str, Any], Path]:
    """The run's config and the expert data it scores against (refusals are QualityErrors)."""
    try:
        record = load_run_config(run)
    except ValueError as error:
        raise QualityError(str(error)) from None
    if data_path is None:
        data_path = (record.get("data") or {}).get("path")
        if not data_path:
            raise QualityError(f"{run / CONFIG_FILE} names no expert data; pass data_path")
    data_path = Path(data_path)
    if not data_path.is_file():
        raise QualityError(f"expert data not found: {data_path}")
    return record, data_path


def _draw_sample(
    run: Path, env_id: str, data_path: Path, uniform: _UniformActions, *,
    samples: int, coverage: int, episodes: int, seed: int,
) -> _Sample:  # fmt: skip
    """The expert's, random and the run's policy's transitions and the two coverages; every
    draw from one generator in a fixed order (the same inputs, the same sample)."""
    rng = np.random.default_rng(seed)
    random_rng = np.random.default_rng(seed + 1)
    expert = _expert_rollouts(data_path).take(samples, rng)
    random = roll_out(
        env_id, lambda obs: uniform(len(obs), random_rng), episodes=episodes, seed=QUALITY_SEED
    ).take(samples, rng)
    try:
        policy = load_policy(run)
    except ValueError as error:
        raise QualityError(str(error)) from None
    with torch.no_grad():
        on_policy = roll_out(
            env_id,
            lambda obs: policy_actions(policy, obs, discrete=uniform.discrete),
            episodes=episodes,
            seed=QUALITY_SEED,
        ).take(samples, rng)
    half = coverage // 2
    states = np.concatenate(
        [expert.obs[rng.choice(len(expert), half)], random.obs[rng.choice(len(random), half)]]
    )
    cover = make_coverage(states, uniform(len(states), rng), seed=seed)
    size = min(len(expert), len(random))  # ρ over as many of each
    expert, random = expert.take(size, rng), random.take(size, rng)
    # The same on the expert's states alone (one cluster of states, not two).
    expert_cover = make_coverage(
        expert.obs[rng.choice(len(expert), coverage)], uniform(coverage, rng), seed=seed
    )
    return _Sample(
        expert=expert, random=random, on_policy=on_policy, cover=cover, expert_cover=expert_cover
    )


def _scores(run: Path, record: Mapping[str, Any], truth: Any, sample: _Sample,
            gamma: float) -> dict[str, float]:  # fmt: skip
    """Pearson and EPIC of the run's f (and g, and the untrained net) against the truth."""
    family = record["architecture"].get("reward_family", RewardFamily.STATE_ACTION)
    obs, actions, next_obs = sample.transitions()
    expert = sample.expert
    with pinned_threads(1):  # one summation order: the same bytes on any machine
        shaped = family == RewardFamily.SHAPED
        f_full = _as_transition_reward(load_reward(run, full=shaped), full=shaped)
        g = _as_transition_reward(load_reward(run), full=False)
        initial = _as_transition_reward(initial_reward(record), full=False)

        def epic(reward: TransitionReward) -> float:
            return epic_distance(
                reward, truth.reward, obs, actions, next_obs, coverage=sample.cover, gamma=gamma
            )

        def epic_on_expert(reward: TransitionReward) -> float:
            return epic_distance(reward, truth.reward, expert.obs, expert.actions,
                                 expert.next_obs, coverage=sample.expert_cover,
                                 gamma=gamma)  # fmt: skip

        def raw(reward: TransitionReward, source: Rollouts) -> float:
            return pearson(
                reward(source.obs, source.actions, source.next_obs),
                truth.reward(source.obs, source.actions, source.next_obs),
            )

        return {
            "pearson_expert": raw(f_full, expert),
            "pearson_policy": raw(f_full, sample.on_policy),
            "epic": epic(f_full),
            "epic_g": epic(g),
            "epic_random_baseline": epic(initial),
            "epic_expert_coverage": epic_on_expert(f_full),
            "epic_random_baseline_expert_coverage": epic_on_expert(initial),
        }


def _truth_check(truth: Any, sample: _Sample) -> dict[str, Any]:
    """The per-step part of the true reward against the env's recorded rewards."""
    checks: dict[str, Any] = {"what": "the per-step part of r against the env's recorded rewards"}
    for name, source in (("expert", sample.expert), ("random", sample.random)):
        step = np.asarray(truth.step(source.obs, source.actions, source.next_obs), np.float64)
        checks[name] = {
            "pearson": _number(pearson(step, source.rewards)),
            "max_abs_error": _number(float(np.abs(step - source.rewards).max())),
        }
    return checks


def _coverage_record(sample: _Sample, uniform: _UniformActions, *, coverage: int,
                     episodes: int) -> dict[str, Any]:  # fmt: skip
    """What the file says of the states, actions and transitions behind the scores."""
    half, expert, random = coverage // 2, sample.expert, sample.random
    rollouts = f"({episodes} episodes from reset(seed={QUALITY_SEED} + k))"
    return {
        "states": f"observations: {half} of the expert's data, {half} of uniformly random "
        f"rollouts {rollouts}",
        "actions": uniform.describe(),
        "next_states": "a seeded permutation of the same states",
        "transitions": f"{len(expert)} of the expert's data and {len(random)} of the random "
        "rollouts, actions as taken: ρ is taken over them",
        "policy_transitions": f"{len(sample.on_policy)} of the run's deterministic policy "
        f"{rollouts}",
        "size": sample.cover.m,
        "expert_coverage": f"epic_expert_coverage: {sample.cover.m} of the expert's states, "
        f"the same actions, ρ over the {len(expert)} expert transitions",
    }


def write_reward_quality(
    run_dir: str | os.PathLike[str],
    *,
    env_id: str,
    data_path: str | os.PathLike[str] | None = None,
    samples: int = 2000,
    coverage: int = 256,
    episodes: int = 4,
    seed: int = 0,
) -> RewardQuality:
    """Score the run's learned reward against ``env_id``'s true reward; write
    ``run_dir/reward_quality.json`` and return it.

    ``data_path`` is the expert data (default: the path the run's config records);
    ``samples`` transitions per source (expert, random, policy), ``coverage`` states and
    actions behind each expectation, ``episodes`` random and policy episodes from
    ``reset(seed=QUALITY_SEED + k)``. The same inputs give the same bytes.
    """
    if env_id not in TASKS:
        raise QualityError(f"unknown task {env_id!r}; choose one of {', '.join(TASKS)}")
    run = Path(run_dir)
    record, data = _run_record(run, data_path)
    gamma = task_gamma(env_id)
    truth = true_reward(env_id, gamma)
    env = make_env(env_id)
    uniform = _UniformActions(env.action_space)
    env.close()
    sample = _draw_sample(run, env_id, data, uniform, samples=samples, coverage=coverage,
                          episodes=episodes, seed=seed)  # fmt: skip
    quality = RewardQuality(
        env=env_id,
        algo=str(record.get("algo", "")),
        reward_family=record["architecture"].get("reward_family", RewardFamily.STATE_ACTION),
        **_scores(run, record, truth, sample, gamma),
        gamma=gamma,
        seed=seed,
        samples=2 * len(sample.expert),
        coverage=_coverage_record(sample, uniform, coverage=coverage, episodes=episodes),
        true_reward={"kind": truth.kind, "description": truth.description},
        true_reward_check=_truth_check(truth, sample),
        reward_sha256=reward_digest(run),
    )
    write_quality(run / QUALITY_FILE, quality)
    return quality


def write_quality(path: Path, quality: RewardQuality) -> None:
    write_text(path, json.dumps(quality.to_json(), indent=2, ensure_ascii=False) + "\n")


def reward_digest(run_dir: str | os.PathLike[str]) -> str:
    return hashlib.sha256((Path(run_dir) / REWARD_FILE).read_bytes()).hexdigest()


def read_reward_quality(run_dir: str | os.PathLike[str]) -> Mapping[str, Any] | None:
    """A run's ``reward_quality.json`` as JSON (:func:`read_quality`: typed); None when
    missing, unreadable, made for another ``reward.pt`` than the folder's, or lacking a score
    (an older file)."""
    try:
        found = read_json(Path(run_dir) / QUALITY_FILE)
        if not isinstance(found, dict) or found.get("format") != QUALITY_FORMAT:
            return None
        current = found.get("reward_sha256") == reward_digest(run_dir)
        return found if current and all(key in found for key in SCORES) else None
    except (OSError, ValueError):
        return None


def read_quality(run_dir: str | os.PathLike[str]) -> RewardQuality | None:
    """:func:`read_reward_quality`, typed; None as there, or for a file lacking a field."""
    found = read_reward_quality(run_dir)
    try:
        return None if found is None else RewardQuality.from_json(found)
    except KeyError:
        return None


def run_quality(
    run_dir: str | os.PathLike[str], *, env_id: str, data_path: str | os.PathLike[str] | None
) -> Mapping[str, Any]:
    """The run's ``reward_quality.json``, computed and written first when missing or stale
    (runs made before the file existed)."""
    found = read_reward_quality(run_dir)
    if found is None:
        write_reward_quality(run_dir, env_id=env_id, data_path=data_path)
        found = read_reward_quality(run_dir)
        assert found is not None
    return found
