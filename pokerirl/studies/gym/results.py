"""A gym study task's ``summary.json``, typed: what the report and the figures read.

Written and read by :mod:`pokerirl.serial` from the fields below, in the order (and with the
names) ``summary.json`` has always had; reading checks every field the classes type and names
the first bad one by its path (``algos.airl.irl_final_return.mean``). An older summary may
lack the fields added since: the reward map, the reward quality, the RL backend; an offline
study's has no IRL mode (only an online study's says ``settings.mode = "online"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from pokerirl.meanstd import Curve, MeanStd
from pokerirl.serial import Json, Omit, SerialError, Serializable, meta

OMIT_NONE = meta(omit=Omit.NONE)  # a field older summaries lack, or one only some tasks have


@dataclass(frozen=True, kw_only=True)
class AlgoCurves(Serializable):
    """An algorithm's curves: the IRL phase's per epoch, and the RL phase's on its rewards."""

    irl_epochs: list[int]
    irl_return: Curve
    rl: Curve
    alignment: Curve | None = field(default=None, metadata=OMIT_NONE)  # discrete tasks


@dataclass(frozen=True, kw_only=True)
class AlgoSummary(Serializable):
    """One IRL algorithm on one task: its IRL phase, the RL phase on its rewards, and how its
    reward compares with the true one."""

    irl_final_return: MeanStd
    rl_final_return: MeanStd
    baselines: dict[str, MeanStd]
    irl_per_run_final: list[float]
    rl_per_run_final: list[float]
    curves: AlgoCurves
    final_alignment: MeanStd | None = field(default=None, metadata=OMIT_NONE)  # discrete tasks
    final_reward_alignment: MeanStd | None = field(default=None, metadata=OMIT_NONE)
    final_disc_acc_expert: MeanStd | None = field(default=None, metadata=OMIT_NONE)
    final_disc_acc_policy: MeanStd | None = field(default=None, metadata=OMIT_NONE)
    # EPIC and Pearson by score (gym.quality.SCORES), each a key of its own
    quality: dict[str, MeanStd] = field(default_factory=dict, metadata=meta(flatten=True))
    reward_quality: Json | None = field(default=None, metadata=OMIT_NONE)  # per run, γ, ...


@dataclass(frozen=True, kw_only=True)
class RLCurve(Serializable):
    rl: Curve


@dataclass(frozen=True, kw_only=True)
class EnvRewardSummary(Serializable):
    """The RL phase on the environment's own reward."""

    rl_final_return: MeanStd
    rl_per_run_final: list[float]
    curves: RLCurve


@dataclass(frozen=True, kw_only=True)
class IRLBudget(Serializable):
    """What the report reads of ``settings.irl`` (``asdict(IRLSettings)``, kept whole as JSON):
    checked on reading."""

    transitions: int
    epochs: int
    batch_size: int
    alpha: float
    beta: float
    sigma_start: float
    sigma_end: float
    eval_episodes: int


@dataclass(frozen=True, kw_only=True)
class RLBudget(Serializable):
    """What the report reads of ``settings.rl``: checked on reading."""

    algo: str
    timesteps: int


@dataclass(frozen=True, kw_only=True)
class StudySettings(Serializable):
    """The budgets a task ran with (``irl`` and ``rl``: the presets' settings as JSON)."""

    irl: Json
    rl: Json
    rl_evaluations: int
    rl_eval_episodes: int
    seed: int
    authors_budget: bool
    rl_backend: str | None = field(default=None, metadata=OMIT_NONE)  # None: before (sb3)
    mode: str | None = field(default=None, metadata=OMIT_NONE)  # None: offline IRL
    online: Json | None = field(default=None, metadata=OMIT_NONE)  # rounds, generator steps, envs

    @classmethod
    def from_json(cls, data: Json, path: str = "") -> StudySettings:
        found = super().from_json(data, path)
        IRLBudget.from_json(found.irl, _at(path, "irl"))
        RLBudget.from_json(found.rl, _at(path, "rl"))
        return found


@dataclass(frozen=True, kw_only=True)
class PaperFinals(Serializable):
    """The authors' final values for the task (their figures' last points)."""

    irl_final_return: dict[str, MeanStd]  # airl, hairl
    expert_return: float | None
    rl_final_return: dict[str, MeanStd]  # airl, hairl, env_reward
    final_alignment: dict[str, float | None] | None  # discrete tasks
    random_return: float | None


@dataclass(frozen=True, kw_only=True)
class Agreement(Serializable):
    """Cells of the reward map where an algorithm's mean f (and each run's) prefers the
    shipped expert's action (None: no expert)."""

    mean_f: float | None
    runs: list[float]


@dataclass(frozen=True, kw_only=True)
class RewardMapSummary(Serializable):
    """Figure 4's agreements, by algorithm, beside a constant action's."""

    grid: int
    agreement: dict[str, Agreement]
    constant_action: Any
    constant_agreement: float


@dataclass(frozen=True, kw_only=True)
class TaskSummary(Serializable):
    """One task of a gym study (its ``summary.json``)."""

    format: str
    env: str
    preset: str
    runs: int
    seeds: list[int]
    discrete: bool
    expert_return: float
    random_return: float
    algos: dict[str, AlgoSummary]
    env_reward: EnvRewardSummary
    settings: StudySettings
    paper: PaperFinals | None  # None: a task the paper does not have (issue 34)
    reward_map: RewardMapSummary | None = None  # null where the task has none

    @classmethod
    def from_json(cls, data: Json, path: str = "") -> TaskSummary:
        found = super().from_json(data, path)
        if not found.seeds:  # the report names the first and the last
            raise SerialError(f"{_at(path, 'seeds')}: expected a non-empty list, got []")
        return found


def _at(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key
