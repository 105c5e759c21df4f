"""The gym study's settings: its presets (budgets, tasks, runs, algorithms) and the tasks it
runs. Torch- and Gymnasium-free: the command line reads the presets for its help.

>>> PRESETS["quick"].tasks
('MountainCar-v0',)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from pokerirl.errors import ConfigError
from pokerirl.gym.presets import TASK_ORDER, TASKS, IRLSettings, RLSettings, Task
from pokerirl.irl.config import MAX_EPOCHS, Algo  # torch-free
from pokerirl.settings import MAX_STEPS
from pokerirl.studies.common import StudyError, with_overrides

MAX_EPISODES = 1_000_000  # evaluation episodes: each is played whole

# The IRL algorithms a study may train, in the order they are run and shown: the paper's two,
# then GAIL (opt-in).
STUDY_ALGOS: tuple[str, ...] = tuple(algo.value for algo in Algo)
PAPER_ALGOS = ("airl", "hairl")


@dataclass(frozen=True, kw_only=True)
class StudyPreset:
    """A study's budgets: which tasks, how many runs, and overrides of the authors' budgets.

    ``None`` keeps the task's own value (the paper's).
    """

    name: str
    tasks: tuple[str, ...]
    runs: int
    algos: tuple[str, ...] = PAPER_ALGOS  # the paper's two always; GAIL beside them if named
    transitions: int | None = None
    epochs: int | None = None
    eval_episodes: int | None = None
    rl_timesteps: int | None = None
    rl_evaluations: int = 10  # points on each RL run's true-return curve, the last at its end
    seed: int = 0  # expert data from reset(seed + k); IRL run k and RL run k use seed + k
    standardize_obs: bool = True  # IRL on standardized observations (see IRLSettings)
    notes: str = ""

    def __post_init__(self) -> None:
        for env_id in self.tasks:
            _task(env_id)  # one line for an id that is neither a paper task nor usable
        checks = {
            "runs >= 1": self.runs >= 1,
            "at least one task": len(self.tasks) >= 1,
            "transitions >= 2": self.transitions is None or self.transitions >= 2,
            f"1 <= epochs <= {MAX_EPOCHS:,}": self.epochs is None
            or 1 <= self.epochs <= MAX_EPOCHS,
            f"1 <= eval episodes <= {MAX_EPISODES:,}": self.eval_episodes is None
            or 1 <= self.eval_episodes <= MAX_EPISODES,
            f"1 <= RL timesteps <= {MAX_STEPS:,}": self.rl_timesteps is None
            or 1 <= self.rl_timesteps <= MAX_STEPS,
            "RL evaluations >= 1": self.rl_evaluations >= 1,
            "seed >= 0": self.seed >= 0,
            "algos: airl, hairl, then optionally gail": self.algos in (
                PAPER_ALGOS, STUDY_ALGOS),
        }
        broken = [name for name, ok in checks.items() if not ok]
        if broken:
            raise ConfigError(f"bad study settings: {', '.join(broken)}")

    def rewards(self) -> tuple[str, ...]:
        """The RL phase's rewards: the env's, then each IRL algorithm's."""
        return ("env", *self.algos)

    def irl(self, env_id: str) -> IRLSettings:
        """The task's IRL settings with this preset's budget overrides applied."""
        base = _task(env_id).irl
        return replace(
            base,
            transitions=self.transitions or base.transitions,
            epochs=self.epochs or base.epochs,
            eval_episodes=self.eval_episodes or base.eval_episodes,
            standardize_obs=self.standardize_obs,
        )

    def rl(self, env_id: str) -> RLSettings:
        """The task's RL settings with this preset's budget override applied."""
        base = _task(env_id).rl
        return replace(base, timesteps=self.rl_timesteps or base.timesteps)


def _task(env_id: str) -> Task:
    # A task the paper lacks is resolved by pokerirl.gym.tasks, which imports Gymnasium to
    # read its spaces: only then, so that the paper's tasks cost nothing.
    if env_id in TASKS:
        return TASKS[env_id]
    from pokerirl.gym.tasks import task

    return task(env_id)


PRESETS: dict[str, StudyPreset] = {
    preset.name: preset
    for preset in (
        StudyPreset(
            name="quick",
            tasks=("MountainCar-v0",),
            runs=3,
            # Budgeted for < 10 minutes on 2 cores for the whole study (3 runs x AIRL, H-AIRL,
            # then DQN on AIRL, H-AIRL and the env reward): 25k expert transitions (about 240
            # episodes of the shipped expert), 20 IRL epochs, 5 evaluation episodes, 50k DQN
            # steps (9 RL runs at about 600-1,000 steps/s per core: 4-6 core-minutes). On the
            # env reward, the shipped expert's DQN run (seed 0) first beat -200 at 90k steps, so
            # the quick env-reward baseline will likely stay at -200; the study measures it.
            transitions=25_000,
            epochs=20,
            eval_episodes=5,
            rl_timesteps=50_000,
            notes="MountainCar only, 3 runs, short IRL and RL phases; the demo runs it.",
        ),
        StudyPreset(
            name="demo",
            tasks=("MountainCar-v0",),
            runs=2,
            # `pokerirl demo`'s Gymnasium half: the quick preset's data and IRL budgets on 2 runs,
            # and 20k DQN steps. The quick study's learned-reward DQN runs reached the flag from
            # their first evaluation (5k steps) while the env-reward runs mostly did not by 50k,
            # so 20k steps still separate them.
            transitions=25_000,
            epochs=20,
            eval_episodes=5,
            rl_timesteps=20_000,
            notes="MountainCar only, 2 runs, the quick preset's IRL, 20k DQN steps; the demo.",
        ),
        StudyPreset(
            name="paper",
            tasks=TASK_ORDER,
            runs=10,
            notes="The authors' budgets on all six tasks (about 70-80 CPU-hours here).",
        ),
    )
}


def study_preset(name: str, **overrides: Any) -> StudyPreset:
    """The preset ``name`` with ``overrides`` (None values ignored).

    >>> study_preset("quick", runs=2).runs
    2
    """
    return with_overrides(PRESETS, name, **overrides)


def parse_tasks(text: str) -> tuple[str, ...]:
    """``all`` (the six, cheapest first) or one task id.

    >>> parse_tasks("MountainCar-v0")
    ('MountainCar-v0',)
    """
    if text == "all":
        return TASK_ORDER
    if text not in TASKS:
        try:
            _task(text)  # any other registered Gymnasium task, with generic settings
        except ConfigError as error:
            raise StudyError(f"{error}; or all") from None
    return (text,)


def parse_algos(text: str) -> tuple[str, ...]:
    """``--algos``: comma-separated names, returned in the study's order.

    >>> parse_algos("gail,airl,hairl")
    ('airl', 'hairl', 'gail')
    """
    names = {name.strip() for name in text.split(",") if name.strip()}
    unknown = sorted(names - set(STUDY_ALGOS))
    if unknown or not set(PAPER_ALGOS) <= names:
        raise StudyError(
            f"algos {text!r}: the study trains airl and hairl (the paper's), and gail if named; "
            f"choose from {', '.join(STUDY_ALGOS)}"
        )
    return tuple(algo for algo in STUDY_ALGOS if algo in names)


def task_root(out: Path, env: str, tasks: Sequence[str]) -> Path:
    """Where a task's study lives: ``out`` for a single task, else ``out/<env>``."""
    return out if len(tasks) == 1 else out / env


def authors_budget(env: str, preset: StudyPreset) -> bool:
    """Whether ``preset`` trains ``env`` with the authors' budgets (data, epochs, evaluation
    episodes, RL steps) and their 10 runs (never, for a task the paper does not have)."""
    if env not in TASKS:
        return False
    paper = TASKS[env]
    irl = replace(preset.irl(env), standardize_obs=paper.irl.standardize_obs)
    return irl == paper.irl and preset.rl(env) == paper.rl and preset.runs == 10
