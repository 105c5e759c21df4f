"""The study's settings: one frozen dataclass and its two presets, ``quick`` and ``paper``.

>>> PRESETS["paper"].runs, len(PRESETS["paper"].seeds), PRESETS["paper"].hands
(10, 20, 1000000)
>>> preset("quick", runs=3).runs
3
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

AGENT_KINDS = ("dqn", "airl_dqn", "hairl_dqn")  # report.json names
IRL_ALGOS = ("airl", "hairl")
BUILT_INS = ("random", "call", "raise")


class StudyError(ValueError):
    """Bad study input or a study folder that does not fit; the message is one line."""


@dataclass(frozen=True, kw_only=True)
class StudyConfig:
    """Every setting that determines a study's results (``jobs`` does not).

    ``irl_epochs`` None keeps the IRL core's defaults (the paper's poker settings);
    ``short_agent_hands`` trains a second sparse DQN set at the paper's training length
    (5,000 episodes) beside ours, on the same seeds.
    """

    preset: str
    runs: int  # IRL runs per algorithm
    seeds: tuple[int, ...]  # agent seeds and tournament seeds
    hands: int  # tournament hands per seed (Table 1)
    panel_hands: int  # tournament hands per seed (the panel)
    agent_hands: int  # DQN training hands
    short_agent_hands: int = 5_000
    eval_every: int = 5_000
    eval_hands: int = 20_000
    irl_epochs: int | None = None
    irl_seed: int = 0
    duplicate: bool = True
    jobs: int = 2  # processes; the one setting that does not change a result

    def __post_init__(self) -> None:
        checks = {
            "runs >= 1": self.runs >= 1,
            "at least one seed": len(self.seeds) >= 1,
            "seeds >= 0": all(s >= 0 for s in self.seeds),
            "seeds distinct": len(set(self.seeds)) == len(self.seeds),
            "hands >= 2": self.hands >= 2,
            "panel hands >= 2": self.panel_hands >= 2,
            "agent hands >= 1": self.agent_hands >= 1,
            "short agent hands >= 1": self.short_agent_hands >= 1,
            "eval every >= 1": self.eval_every >= 1,
            "eval hands >= 2": self.eval_hands >= 2,
            "IRL epochs >= 1": self.irl_epochs is None or self.irl_epochs >= 1,
            "jobs >= 1": self.jobs >= 1,
        }
        broken = [name for name, ok in checks.items() if not ok]
        if broken:
            raise StudyError(f"bad study settings: {', '.join(broken)}")

    def settings(self) -> dict[str, Any]:
        """What determines the results: every field but ``jobs``."""
        found = dataclasses.asdict(self)
        found.pop("jobs")
        found["seeds"] = list(self.seeds)
        return found


PRESETS: dict[str, StudyConfig] = {
    # The paper's protocol: 10 IRL runs each, 20 agent seeds of 50k hands, 20 x 1M duplicate
    # hands for Table 1, 20 x 100k for each panel pair.
    "paper": StudyConfig(
        preset="paper",
        runs=10,
        seeds=tuple(range(20)),
        hands=1_000_000,
        panel_hands=100_000,
        agent_hands=50_000,
        eval_every=5_000,
        eval_hands=20_000,
    ),
    # Under 5 minutes on 2 cores on the April 1995 sample: 2 runs, 4 seeds (two per IRL run,
    # so two seeds train side by side), 20k training hands, fewer tournament hands.
    "quick": StudyConfig(
        preset="quick",
        runs=2,
        seeds=(0, 1, 2, 3),
        hands=100_000,
        panel_hands=20_000,
        agent_hands=20_000,
        eval_every=4_000,
        eval_hands=4_000,
        irl_epochs=20,
    ),
}


def preset(name: str, **overrides: Any) -> StudyConfig:
    """The preset ``name`` with ``overrides`` (None values ignored)."""
    if name not in PRESETS:
        raise StudyError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")
    changes = {k: v for k, v in overrides.items() if v is not None}
    if "seeds" in changes:
        changes["seeds"] = tuple(changes["seeds"])
    try:
        return dataclasses.replace(PRESETS[name], **changes)
    except TypeError as error:
        raise StudyError(f"bad study setting: {error}") from None


def parse_seeds(text: str) -> tuple[int, ...]:
    """``"0-19"``, ``"0,2,5"`` or ``"0-3,7"`` as seeds.

    >>> parse_seeds("0-3,7")
    (0, 1, 2, 3, 7)
    """
    seeds: list[int] = []
    try:
        for part in text.split(","):
            low, _, high = part.strip().partition("-")
            seeds.extend(range(int(low), int(high or low) + 1))
    except ValueError:
        raise StudyError(f"bad --seeds {text!r}; write e.g. 0-19 or 0,2,5") from None
    if not seeds:
        raise StudyError(f"bad --seeds {text!r}; no seeds")
    return tuple(seeds)
