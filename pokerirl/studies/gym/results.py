"""A gym study task's ``summary.json``, typed: what the report and the figures read.

``to_json`` writes the names (and their order) ``summary.json`` has always had; ``from_json``
reads a summary checked by :mod:`pokerirl.studies.gym_summary_check` (an older one may lack
the fields added since: the reward map, the reward quality, the RL backend).

"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pokerirl.meanstd import MeanStd

Json = dict[str, Any]
QUALITY_KEYS = ("disc_acc_expert", "disc_acc_policy")  # written as final_<key>


@dataclass(frozen=True, kw_only=True)
class Band:
    """A curve: mean and std over runs at each point (``timesteps`` for RL curves)."""

    mean: list[float]
    std: list[float]
    timesteps: list[int] | None = None

    def to_json(self) -> Json:
        head = {} if self.timesteps is None else {"timesteps": self.timesteps}
        return {**head, "mean": self.mean, "std": self.std}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Band:
        return cls(mean=data["mean"], std=data["std"], timesteps=data.get("timesteps"))


@dataclass(frozen=True, kw_only=True)
class AlgoSummary:
    """One IRL algorithm on one task: its IRL phase, the RL phase on its rewards, and how its
    reward compares with the true one."""

    irl_final_return: MeanStd
    rl_final_return: MeanStd
    baselines: dict[str, MeanStd]
    irl_per_run_final: list[float]
    rl_per_run_final: list[float]
    irl_epochs: list[int]
    irl_return: Band
    rl_curve: Band
    alignment: Band | None = None  # discrete tasks: validation alignment per epoch
    final_alignment: MeanStd | None = None
    final_reward_alignment: MeanStd | None = None
    final_disc_acc: dict[str, MeanStd] = field(default_factory=dict)  # by QUALITY_KEYS
    quality: dict[str, MeanStd] = field(default_factory=dict)  # EPIC, Pearson (gym.quality)
    reward_quality: Json | None = None  # per run, γ, coverage, the true reward

    def to_json(self) -> Json:
        curves: Json = {
            "irl_epochs": self.irl_epochs,
            "irl_return": self.irl_return.to_json(),
            "rl": self.rl_curve.to_json(),
        }
        found: Json = {
            "irl_final_return": self.irl_final_return.to_json(),
            "rl_final_return": self.rl_final_return.to_json(),
            "baselines": {name: value.to_json() for name, value in self.baselines.items()},
            "irl_per_run_final": self.irl_per_run_final,
            "rl_per_run_final": self.rl_per_run_final,
            "curves": curves,
        }
        if self.final_alignment is not None and self.final_reward_alignment is not None:
            found["final_alignment"] = self.final_alignment.to_json()
            found["final_reward_alignment"] = self.final_reward_alignment.to_json()
        if self.alignment is not None:
            curves["alignment"] = self.alignment.to_json()
        for key, value in self.final_disc_acc.items():
            found[f"final_{key}"] = value.to_json()
        found.update({key: value.to_json() for key, value in self.quality.items()})
        if self.reward_quality is not None:
            found["reward_quality"] = self.reward_quality
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> AlgoSummary:
        curves = data["curves"]
        known = {"irl_final_return", "rl_final_return", "baselines", "irl_per_run_final",
                 "rl_per_run_final", "curves", "final_alignment", "final_reward_alignment",
                 "reward_quality", *(f"final_{key}" for key in QUALITY_KEYS)}  # fmt: skip
        return cls(
            irl_final_return=MeanStd.from_json(data["irl_final_return"]),
            rl_final_return=MeanStd.from_json(data["rl_final_return"]),
            baselines={k: MeanStd.from_json(v) for k, v in data["baselines"].items()},
            irl_per_run_final=data["irl_per_run_final"],
            rl_per_run_final=data["rl_per_run_final"],
            irl_epochs=curves["irl_epochs"],
            irl_return=Band.from_json(curves["irl_return"]),
            rl_curve=Band.from_json(curves["rl"]),
            alignment=Band.from_json(curves["alignment"]) if "alignment" in curves else None,
            final_alignment=_optional(data.get("final_alignment")),
            final_reward_alignment=_optional(data.get("final_reward_alignment")),
            final_disc_acc={
                key: MeanStd.from_json(data[f"final_{key}"])
                for key in QUALITY_KEYS
                if f"final_{key}" in data
            },
            quality={k: MeanStd.from_json(v) for k, v in data.items() if k not in known},
            reward_quality=data.get("reward_quality"),
        )


def _optional(data: Mapping[str, Any] | None) -> MeanStd | None:
    return None if data is None else MeanStd.from_json(data)


@dataclass(frozen=True, kw_only=True)
class EnvRewardSummary:
    """The RL phase on the environment's own reward."""

    rl_final_return: MeanStd
    rl_per_run_final: list[float]
    rl_curve: Band

    def to_json(self) -> Json:
        return {
            "rl_final_return": self.rl_final_return.to_json(),
            "rl_per_run_final": self.rl_per_run_final,
            "curves": {"rl": self.rl_curve.to_json()},
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> EnvRewardSummary:
        return cls(
            rl_final_return=MeanStd.from_json(data["rl_final_return"]),
            rl_per_run_final=data["rl_per_run_final"],
            rl_curve=Band.from_json(data["curves"]["rl"]),
        )


@dataclass(frozen=True, kw_only=True)
class StudySettings:
    """The budgets a task ran with (``irl`` and ``rl``: the presets' settings as JSON)."""

    irl: Json
    rl: Json
    rl_evaluations: int
    rl_eval_episodes: int
    seed: int
    authors_budget: bool
    rl_backend: str | None = None  # None: a study made before the choice (sb3)

    def to_json(self) -> Json:
        found: Json = {
            "irl": self.irl,
            "rl": self.rl,
            "rl_evaluations": self.rl_evaluations,
            "rl_eval_episodes": self.rl_eval_episodes,
            "seed": self.seed,
            "authors_budget": self.authors_budget,
        }
        if self.rl_backend is not None:
            found["rl_backend"] = self.rl_backend
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> StudySettings:
        return cls(
            irl=data["irl"],
            rl=data["rl"],
            rl_evaluations=data["rl_evaluations"],
            rl_eval_episodes=data["rl_eval_episodes"],
            seed=data["seed"],
            authors_budget=data["authors_budget"],
            rl_backend=data.get("rl_backend"),
        )


@dataclass(frozen=True, kw_only=True)
class PaperFinals:
    """The authors' final values for the task (their figures' last points)."""

    irl_final_return: dict[str, MeanStd]  # airl, hairl
    expert_return: float | None
    rl_final_return: dict[str, MeanStd]  # airl, hairl, env_reward
    final_alignment: dict[str, float | None] | None  # discrete tasks
    random_return: float | None

    def to_json(self) -> Json:
        return {
            "irl_final_return": {k: v.to_json() for k, v in self.irl_final_return.items()},
            "expert_return": self.expert_return,
            "rl_final_return": {k: v.to_json() for k, v in self.rl_final_return.items()},
            "final_alignment": self.final_alignment,
            "random_return": self.random_return,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PaperFinals:
        return cls(
            irl_final_return={
                k: MeanStd.from_json(v) for k, v in data["irl_final_return"].items()
            },
            expert_return=data["expert_return"],
            rl_final_return={k: MeanStd.from_json(v) for k, v in data["rl_final_return"].items()},
            final_alignment=data["final_alignment"],
            random_return=data["random_return"],
        )


@dataclass(frozen=True, kw_only=True)
class RewardMapSummary:
    """Figure 4's agreements: cells where each algorithm's mean f prefers the shipped
    expert's action (and each run's), beside a constant action's."""

    grid: int
    agreement: dict[str, float | None]  # by algorithm: the mean f's (None: no expert)
    run_agreements: dict[str, list[float]]
    constant_action: Any
    constant_agreement: float

    def to_json(self) -> Json:
        return {
            "grid": self.grid,
            "agreement": {
                algo: {"mean_f": value, "runs": self.run_agreements[algo]}
                for algo, value in self.agreement.items()
            },
            "constant_action": self.constant_action,
            "constant_agreement": self.constant_agreement,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RewardMapSummary:
        return cls(
            grid=data["grid"],
            agreement={k: v["mean_f"] for k, v in data["agreement"].items()},
            run_agreements={k: v["runs"] for k, v in data["agreement"].items()},
            constant_action=data["constant_action"],
            constant_agreement=data["constant_agreement"],
        )


@dataclass(frozen=True, kw_only=True)
class TaskSummary:
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
    reward_map: RewardMapSummary | None = None
    has_reward_map: bool = True  # whether the file names it (null or not): older ones do not

    def to_json(self) -> Json:
        found: Json = {
            "format": self.format,
            "env": self.env,
            "preset": self.preset,
            "runs": self.runs,
            "seeds": self.seeds,
            "discrete": self.discrete,
            "expert_return": self.expert_return,
            "random_return": self.random_return,
            "algos": {algo: summary.to_json() for algo, summary in self.algos.items()},
            "env_reward": self.env_reward.to_json(),
            "settings": self.settings.to_json(),
            "paper": None if self.paper is None else self.paper.to_json(),
        }
        if self.has_reward_map:
            found["reward_map"] = None if self.reward_map is None else self.reward_map.to_json()
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TaskSummary:
        found = data.get("reward_map")
        return cls(
            format=data["format"],
            env=data["env"],
            preset=data["preset"],
            runs=data["runs"],
            seeds=data["seeds"],
            discrete=data["discrete"],
            expert_return=data["expert_return"],
            random_return=data["random_return"],
            algos={k: AlgoSummary.from_json(v) for k, v in data["algos"].items()},
            env_reward=EnvRewardSummary.from_json(data["env_reward"]),
            settings=StudySettings.from_json(data["settings"]),
            paper=None if data["paper"] is None else PaperFinals.from_json(data["paper"]),
            reward_map=None if found is None else RewardMapSummary.from_json(found),
            has_reward_map="reward_map" in data,
        )
