"""A gym study's report: its ``summary.json`` typed (:class:`GymStudySummary`), read back
(:func:`load_gym_study`) and rendered as ``report.md``. Torch- and Gymnasium-free, so that
``pokerirl report`` starts fast; :mod:`pokerirl.studies.gym.pipeline` runs the study that writes it.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from pokerirl.gym.presets import TASKS, RLBackend
from pokerirl.irl.config import IRLMode  # torch-free
from pokerirl.jsonio import read_json
from pokerirl.meanstd import MeanStd
from pokerirl.serial import Json, SerialError, Serializable, meta
from pokerirl.studies.common import SUMMARY_JSON, StudyError, markdown_table
from pokerirl.studies.gym.results import AlgoSummary, PaperFinals, TaskSummary

SUMMARY_FORMAT = "pokerirl-gym-study/1"
FIGURES = {
    "irl_returns": "figures/irl_returns.png",
    "alignment": "figures/alignment.png",
    "rl_returns": "figures/rl_returns.png",
    "reward_map": "figures/reward_map.png",
}


@dataclass(frozen=True, kw_only=True)
class GymStudySummary(Serializable):
    """A gym study's ``summary.json``: a single task's :class:`TaskSummary`, or (``all``)
    the tasks' under ``tasks`` with the preset and the runs."""

    format: str = SUMMARY_FORMAT
    preset: str
    runs: int
    tasks: dict[str, TaskSummary]
    several: bool = field(default=True, metadata=meta(skip=True))  # the ``tasks`` form

    def to_json(self) -> Json:
        if self.several:
            return super().to_json()
        (only,) = self.tasks.values()
        return only.to_json()

    @classmethod
    def from_json(cls, data: Json, path: str = "") -> GymStudySummary:
        if not (isinstance(data, Mapping) and "tasks" in data):
            task = TaskSummary.from_json(data, path)
            return cls(preset=task.preset, runs=task.runs, tasks={task.env: task}, several=False)
        found = super().from_json(data, path)
        if not found.tasks:
            raise SerialError("tasks: expected an object of task summaries, got {}")
        for env, task in found.tasks.items():
            if task.env != env:
                raise SerialError(f"tasks.{env}.env: expected {env!r}, got {task.env!r}")
        return found

    def render(self) -> str:
        """The study's ``report.md``."""
        return render_report(self.tasks, self.preset, prefix=None if self.several else "")


def is_gym_study(folder: str | os.PathLike[str]) -> bool:
    """Whether ``folder`` holds a gym study's ``summary.json``."""
    try:
        found = read_json(Path(folder) / SUMMARY_JSON)
    except (OSError, ValueError):
        return False
    return isinstance(found, dict) and found.get("format") == SUMMARY_FORMAT


def load_gym_study(folder: str | os.PathLike[str]) -> tuple[GymStudySummary, str]:
    """A finished study's ``summary.json`` and its report rendered again (``pokerirl report``)."""
    path = Path(folder) / SUMMARY_JSON
    try:
        summary = GymStudySummary.from_json(read_json(path))
        return summary, summary.render()
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        # Reading names a field of the wrong type by its path; what the types cannot say (a
        # paper's algorithm missing, a settings value the report cannot format) fails in
        # rendering, in one line too.
        raise StudyError(f"{path}: not a readable gym study summary ({error})") from None


_NONE = MeanStd(mean=None)
NO_PAPER = PaperFinals(
    irl_final_return={"airl": _NONE, "hairl": _NONE},
    expert_return=None,
    rl_final_return={"airl": _NONE, "hairl": _NONE, "env_reward": _NONE},
    final_alignment=None,
    random_return=None,
)


def _value(value: MeanStd | None, *, percent: bool = False, digits: int = 1) -> str:
    if value is None or value.mean is None:
        return "–"
    scale = 100.0 if percent else 1.0
    text = f"{scale * value.mean:,.{digits}f}"
    if value.std is not None:
        text += f" ± {scale * value.std:,.{digits}f}"
    return text + ("%" if percent else "")


def _paper_percent(value: float | None) -> str:
    return "–" if value is None else f"{value:.1f}%"


def _percent(share: float | None) -> float | None:
    return None if share is None else 100 * share


def task_table(summary: TaskSummary) -> list[str]:
    """Our finals beside the authors', one row per figure of the paper."""
    airl, hairl = summary.algos["airl"], summary.algos["hairl"]
    gail = summary.algos.get("gail")  # opt-in: the authors report none
    paper = summary.paper or NO_PAPER  # a task the paper does not have: "–" throughout

    def of_gail(label: str, value: Callable[[AlgoSummary], str]) -> list[tuple[str, str, str]]:
        return [] if gail is None else [(label, value(gail), "not reported")]

    rows = [
        ("IRL-phase return, AIRL", _value(airl.irl_final_return),
         _value(paper.irl_final_return["airl"])),
        ("IRL-phase return, H-AIRL", _value(hairl.irl_final_return),
         _value(paper.irl_final_return["hairl"])),
        *of_gail("IRL-phase return, GAIL", lambda a: _value(a.irl_final_return)),
        ("expert (its data's episodes)", _value(MeanStd(mean=summary.expert_return)),
         _value(MeanStd(mean=paper.expert_return))),
        ("RL-phase return, AIRL reward", _value(airl.rl_final_return),
         _value(paper.rl_final_return["airl"])),
        ("RL-phase return, H-AIRL reward", _value(hairl.rl_final_return),
         _value(paper.rl_final_return["hairl"])),
        *of_gail("RL-phase return, GAIL reward", lambda a: _value(a.rl_final_return)),
        ("RL-phase return, env reward", _value(summary.env_reward.rl_final_return),
         _value(paper.rl_final_return["env_reward"])),
    ]  # fmt: skip
    if summary.discrete:
        alignment = paper.final_alignment or {}
        rows += [
            ("alignment, AIRL policy", _value(airl.final_alignment, percent=True),
             _paper_percent(alignment.get("airl"))),
            ("alignment, H-AIRL policy", _value(hairl.final_alignment, percent=True),
             _paper_percent(alignment.get("hairl"))),
            *of_gail("alignment, GAIL policy", lambda a: _value(a.final_alignment, percent=True)),
            ("alignment, behaviour cloning (same net and epochs)",
             _value(hairl.baselines["bc"], percent=True), "not reported"),
            ("alignment, reward argmax: AIRL / H-AIRL",
             f"{_value(airl.final_reward_alignment, percent=True)} / "
             f"{_value(hairl.final_reward_alignment, percent=True)}", "not reported"),
            *of_gail("alignment, reward argmax: GAIL",
                     lambda a: _value(a.final_reward_alignment, percent=True)),
        ]  # fmt: skip
    if "epic" in airl.quality:
        a, h = airl.quality, hairl.quality
        rows += [
            ("EPIC distance to the true reward (0 same up to shaping and scale, 0.71 "
             "unrelated, 1 opposite): AIRL / H-AIRL",
             f"{_value(a['epic'], digits=3)} / {_value(h['epic'], digits=3)}", "not reported"),
            ("EPIC of a random reward net (same architecture, the runs' initial nets): "
             "AIRL / H-AIRL",
             f"{_value(a['epic_random_baseline'], digits=3)} / "
             f"{_value(h['epic_random_baseline'], digits=3)}", "not reported"),
            ("EPIC on the expert's states and transitions only: AIRL / H-AIRL / random net",
             f"{_value(a['epic_expert_coverage'], digits=3)} / "
             f"{_value(h['epic_expert_coverage'], digits=3)} / "
             f"{_value(a['epic_random_baseline_expert_coverage'], digits=3)}",
             "not reported"),
            ("Pearson of f and the true reward on expert / policy transitions: AIRL",
             f"{_value(a['pearson_expert'], digits=3)} / "
             f"{_value(a['pearson_policy'], digits=3)}", "not reported"),
            ("Pearson of f and the true reward on expert / policy transitions: H-AIRL",
             f"{_value(h['pearson_expert'], digits=3)} / "
             f"{_value(h['pearson_policy'], digits=3)}", "not reported"),
            *of_gail("EPIC distance to the true reward / on the expert's states and "
                     "transitions only: GAIL",
                     lambda a: f"{_value(a.quality['epic'], digits=3)} / "
                     f"{_value(a.quality['epic_expert_coverage'], digits=3)}"),
            *of_gail("Pearson of f and the true reward on expert / policy transitions: GAIL",
                     lambda a: f"{_value(a.quality['pearson_expert'], digits=3)} / "
                     f"{_value(a.quality['pearson_policy'], digits=3)}"),
        ]  # fmt: skip
    found = summary.reward_map
    if found is not None:
        agree = {algo: agreement.mean_f for algo, agreement in found.agreement.items()}
        rows.append(
            (f"reward map: cells where f prefers the expert's action ({found.grid}² lattice), "
             "AIRL / H-AIRL",
             f"{_paper_percent(_percent(agree['airl']))} / "
             f"{_paper_percent(_percent(agree['hairl']))} "
             f"(a constant {found.constant_action!r}: {100 * found.constant_agreement:.1f}%)",
             "Figure 4: maps only"),
        )  # fmt: skip
        if "gail" in agree:
            rows.append(("reward map: cells where f prefers the expert's action, GAIL",
                         _paper_percent(_percent(agree["gail"])), "not reported"))
    rows.append(
        ("random policy", _value(MeanStd(mean=summary.random_return)),
         _value(MeanStd(mean=paper.random_return)))
    )  # fmt: skip
    return markdown_table(["", "ours", "the authors"], rows)


def _budget(summary: TaskSummary) -> str:
    settings = summary.settings
    irl, rl = settings.irl, settings.rl
    seeds = summary.seeds
    backend = settings.rl_backend or RLBackend.SB3
    online = settings.online if settings.mode == IRLMode.ONLINE else None
    phase = f"IRL {irl['epochs']} epochs" if online is None else (
        f"IRL online (a PPO generator in the env): {online['rounds']} rounds of "
        f"{online['generator_steps']:,} generator steps over {online['envs']} envs")  # fmt: skip
    return (
        f"{summary.runs} runs per algorithm (seeds {seeds[0]}–{seeds[-1]}); expert data "
        f"{irl['transitions']:,} transitions; {phase}, batch "
        f"{irl['batch_size']}, α {irl['alpha']}, β {irl['beta']}, σ {irl['sigma_start']} → "
        f"{irl['sigma_end']} (H-AIRL), each {'epoch' if online is None else 'round'}'s policy "
        f"over {irl['eval_episodes']} episodes; RL {rl['algo'].upper()} for "
        f"{rl['timesteps']:,} steps, each point "
        f"{settings.rl_eval_episodes} deterministic episodes"
        + ("." if backend == RLBackend.SB3 else f" ({backend} RL backend).")
    )


def render_report(
    summaries: Mapping[str, TaskSummary], preset: str, *, prefix: str | None = ""
) -> str:
    """``report.md``: per task, the budget, our finals beside the authors', the figures.

    ``preset`` is the preset's name; ``prefix`` is where each task's figures are, relative to
    the report (None: ``<env>/``).
    """
    lines = [f"# pokerirl gym study ({preset} preset)", ""]
    lines += [
        "Mean ± std (sample std) over runs of each curve's last point; the authors' values are "
        "the last points of their figures' curves, at their budgets."
    ]
    for env, summary in summaries.items():
        where = f"{env}/" if prefix is None else prefix
        lines += ["", f"## {env}", "", _budget(summary), ""]
        if not summary.settings.authors_budget and summary.paper is not None:
            lines += ["**Not the authors' budget or number of runs** (theirs: 10 runs, "
                      "docs/gym.md): compare the directions, not the digits.", ""]  # fmt: skip
        lines += task_table(summary)
        quality = summary.algos["airl"].reward_quality
        if quality is not None:
            truth = quality["true_reward"]
            cover = quality["coverage"]
            lines += ["", f"EPIC and Pearson against the true reward ({truth['kind']}: "
                      f"{truth['description']}), γ {quality['gamma']}; coverage: states "
                      f"{cover['states']}, actions {cover['actions']}."]  # fmt: skip
        generic = f"{env} is not one of the paper's tasks: generic settings (docs/gym.md), no "
        note = TASKS[env].version_note if env in TASKS else generic + "authors' values."
        if note:
            lines += ["", note]
        lines += [""]
        figures = ["irl_returns", "alignment", "rl_returns"] if summary.discrete else [
            "irl_returns", "rl_returns"]  # fmt: skip
        if summary.reward_map is not None:
            figures.append("reward_map")
        lines += [f"![{name}]({where}{FIGURES[name]})" for name in figures]
    return "\n".join(lines) + "\n"
