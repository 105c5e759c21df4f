"""The poker study (:func:`pokerirl.studies.poker.run_study`, demo preset) on built-in
synthetic data, then the Gymnasium study's demo preset on the shipped MountainCar expert.

1. ``synth``: a month of heads-up 10-20 hands between two scripted players, in IRC format
   (written once; a rerun reuses it, so the study's stages resume);
2. the study: ingest -> IRL (AIRL, H-AIRL) -> agents (DQN, AIRL-DQN, H-AIRL-DQN) -> Table 1
   tournament -> panel -> ``report.md``, ``report.json``, ``panel.csv`` and ``figures/``;
3. :func:`run_gym_demo`: ``pokerirl gym study MountainCar-v0 --preset demo`` into
   ``out/gym`` (needs the ``pokerirl[gym]`` extra).

One code path: ``pokerirl demo`` is ``pokerirl study --preset demo`` on the synthetic month,
then ``pokerirl gym study MountainCar-v0 --preset demo``; both presets are sized so that the
poker report prints within about 2 minutes and the whole demo takes about 5 on 2 cores.

>>> DemoConfig().study.preset, DemoConfig().gym.name
('demo', 'demo')
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from pokerirl.execution import Backend
from pokerirl.game.synth import write_synthetic_month
from pokerirl.studies.gym.config import PRESETS as GYM_PRESETS
from pokerirl.studies.gym.config import StudyPreset
from pokerirl.studies.poker import PRESETS, StudyConfig, StudyResult, run_study

if TYPE_CHECKING:  # the gym layer loads only when its demo runs
    from pokerirl.studies.gym.pipeline import GymStudyResult

SYNTH_FOLDER = "irc"
GYM_FOLDER = "gym"


@dataclass(frozen=True, kw_only=True)
class DemoConfig:
    """The synthetic month's size and seed, the poker study's settings and the Gymnasium
    study's (both their ``demo`` presets)."""

    synthetic_hands: int = 5_000
    seed: int = 0
    jobs: int = 2
    study: StudyConfig = field(default_factory=lambda: PRESETS["demo"])
    gym: StudyPreset = field(default_factory=lambda: GYM_PRESETS["demo"])


def synthetic_month(root: Path, *, hands: int, seed: int) -> Path:
    """The month folder under ``root/irc``: written on the first call, reused after."""
    folder = root / SYNTH_FOLDER
    found = sorted(p.parent for p in folder.glob("*/*/hdb")) if folder.is_dir() else []
    if found:
        return found[0]
    return write_synthetic_month(folder, hands=hands, seed=seed)


def run_demo(
    out: str | os.PathLike[str],
    config: DemoConfig = DemoConfig(),
    *,
    say: Callable[[str], None] = lambda message: None,
    progress: bool = False,
    overwrite: bool = False,
) -> StudyResult:
    """Write the synthetic month into ``out/irc`` and run the study into ``out``."""
    root = Path(out)
    root.mkdir(parents=True, exist_ok=True)
    month = synthetic_month(root, hands=config.synthetic_hands, seed=config.seed)
    say(f"synth: {config.synthetic_hands:,} heads-up hands, seed {config.seed} -> {month}")
    study = dataclasses.replace(config.study, jobs=config.jobs)
    return run_study([month], root, study, overwrite=overwrite, progress=progress, say=say)


def run_gym_demo(
    out: str | os.PathLike[str],
    config: DemoConfig = DemoConfig(),
    *,
    say: Callable[[str], None] = lambda message: None,
    progress: bool = False,
    overwrite: bool = False,
) -> GymStudyResult:
    """The Gymnasium study of ``config.gym`` (the demo preset: MountainCar-v0, AIRL and
    H-AIRL, then DQN on each reward and on the env reward) into ``out/gym``."""
    from pokerirl.studies.gym.pipeline import run_gym_study

    return run_gym_study(
        Path(out) / GYM_FOLDER,
        config.gym,
        backend=Backend(jobs=config.jobs),
        overwrite=overwrite,
        progress=progress,
        say=say,
    )
