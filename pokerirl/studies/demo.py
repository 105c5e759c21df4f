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

The demo is expected to see a learned reward agree with the expert less than behaviour
cloning (the study's :class:`~pokerirl.poker.train.RewardBelowBC` warning): it says so as a
``note:`` that explains it, and again in :func:`closing_lines`, instead of a bare warning.

>>> DemoConfig().study.preset, DemoConfig().gym.name
('demo', 'demo')
"""

from __future__ import annotations

import dataclasses
import os
import warnings
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
    from pokerirl.poker.train import RewardBelowBC

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RewardBelowBC)  # every run's, to count them
        result = run_study([month], root, study, overwrite=overwrite, progress=progress, say=say)
    below = [w for w in caught if issubclass(w.category, RewardBelowBC)]
    for other in caught:  # every other warning as it would have been shown
        if other not in below:
            warnings.warn_explicit(other.message, other.category, other.filename, other.lineno)
    if below:
        say(f"note: {below_bc_line(len(below), root)}")
    return result


def below_bc_line(runs: int, out: Path) -> str:
    """The demo's words for its expected :class:`~pokerirl.poker.train.RewardBelowBC`."""
    return (
        f"{runs} learned reward{'s' if runs != 1 else ''} agree{'s' if runs == 1 else ''} with "
        "the expert less than behaviour cloning: expected on the demo's synthetic month "
        f"(BC is trained to predict the expert's action, the reward is not), not a broken "
        f"install; {out / 'report.md'} says why, under 'Reward cards'"
    )


def below_bc_runs(result: StudyResult) -> int:
    """How many of the study's IRL runs have a reward below their BC baseline."""
    cards = result.report.reward_cards or {}
    return sum(card.below_bc or 0 for card in cards.values() if card is not None)


def closing_lines(result: StudyResult, out: Path, *, gym: bool) -> list[str]:
    """What ``pokerirl demo`` says last: where the reports are, the expected note again, and
    what to run next on real hands."""
    reports = f"{out / 'report.md'}" + (f" and {out / GYM_FOLDER / 'report.md'}" if gym else "")
    lines = [f"demo: done; the reports are {reports}"]
    below = below_bc_runs(result)
    if below:
        lines.append(f"note: {below_bc_line(below, out)}")
    lines.append(
        "next: real hands ship with pokerirl: pokerirl study irc-199504 --preset quick "
        "--out study-real/"
    )
    return lines


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
