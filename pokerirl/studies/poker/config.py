"""The study's settings: one frozen dataclass and its presets, ``quick``, ``paper`` (ours)
and ``authors`` (the authors' protocol, from their code).

>>> PRESETS["paper"].runs, len(PRESETS["paper"].seeds), PRESETS["paper"].hands
(10, 20, 1000000)
>>> preset("quick", runs=3).runs
3
>>> preset("authors", runs=3).seeds  # one experiment per IRL run
(0, 1, 2)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from pokerirl.agents.config import AGENT_PRESETS as AGENT_TRAIN_PRESETS
from pokerirl.agents.config import Opponent as AgentOpponent
from pokerirl.game.encodings import EncodingName
from pokerirl.game.match import MAX_HANDS
from pokerirl.irl.config import MAX_EPOCHS, Algo, IRLMode
from pokerirl.poker.folds import FoldsMode
from pokerirl.poker.rewards import Transform
from pokerirl.settings import MAX_LBR_HANDS, MAX_STEPS
from pokerirl.studies.common import StudyError, with_overrides

# The IRL algorithms a study can train; a study trains the paper's two unless told otherwise
# (GAIL: `--algos airl,hairl,gail`).
IRL_ALGOS: tuple[str, ...] = tuple(algo.value for algo in Algo)
PAPER_ALGOS = ("airl", "hairl")
# Table 1's rows: the paper's two first, then the others in the order of Algo.
TABLE1_ORDER = ("hairl", "airl", *(algo for algo in IRL_ALGOS if algo not in ("hairl", "airl")))
ALGO_LABELS = {"airl": "AIRL", "hairl": "H-AIRL", "gail": "GAIL"}
KIND_LABELS = {"dqn": "DQN", **{f"{algo}_dqn": f"{name}-DQN" for algo, name in ALGO_LABELS.items()}}
BUILT_INS = ("random", "call", "raise")
IRL_SETTINGS = ("ours", "authors")
# The choices of the settings below, from where each is declared (all torch-free modules).
AGENT_PRESETS: tuple[str, ...] = tuple(AGENT_TRAIN_PRESETS)
TRANSFORMS: tuple[str, ...] = tuple(t.value for t in Transform)
ENCODING_NAMES: tuple[str, ...] = tuple(e.value for e in EncodingName)
FOLDS: tuple[str, ...] = tuple(f.value for f in FoldsMode)  # ingest's fold hands
LBR_CHECK_UNTIL = "turn"  # a study's LBR checks or calls before the turn: faster (exploit.md)

# The authors' poker IRL settings (silue-dev/hairl, src/utils/training.py, LimitHoldem-v0):
# one hidden layer of 64 in both nets, leaky ReLU, lr 1e-3 for both, weight decay 5e-3 on the
# discriminator only, 50 steps (epochs) of batches of 256, an 80/20 split, the policy's
# distribution (not a sample) shown to the discriminator; H-AIRL: gt_ratio_p 0.33,
# gt_ratio_d 0, noise over the batch from 1.0 to 0.1 with decay 0.1. Their split is the first
# 80% of rows; ours stays a seeded share of hands. Their supervised term is a summed MSE of
# the probabilities against the one-hot expert action (`supervised_form = "sum_mse"`).
AUTHORS_IRL: dict[str, object] = {
    "reward_hidden": (64,),
    "policy_hidden": (64,),
    "activation": "leaky_relu",
    "reward_lr": 1e-3,
    "policy_lr": 1e-3,
    "reward_weight_decay": 5e-3,
    "batch_size": 256,
    "epochs": 50,
    "beta": 0.0,
    "disc_action": "distribution",
    "val_fraction": 0.2,
}
AUTHORS_HAIRL: dict[str, object] = {
    "alpha": 0.33,
    "sigma_start": 1.0,
    "sigma_end": 0.1,
    "noise_schedule": "authors",
    "noise_decay": 0.1,
    "supervised_form": "sum_mse",
}


# Settings a study's record leaves out at these values (see StudyConfig.settings).
UNRECORDED_DEFAULTS: dict[str, object] = {
    "encoding": "rlcard", "folds": "drop", "algos": PAPER_ALGOS, "opponent": "random",
    "payoff_weight": 0.0, "reward_decay": None, "experts": "all", "period": (0.0, 1.0),
    "winners_bb_per_100": 0.0, "winners_min_hands": 200, "irl_mode": IRLMode.OFFLINE.value,
}  # fmt: skip
class Experts(StrEnum):
    """Which players' decisions are the expert's."""

    ALL = "all"
    WINNERS = "winners"  # won >= winners_bb_per_100 over >= winners_min_hands in the period


EXPERTS: tuple[str, ...] = tuple(Experts)
# Whom the DQNs train against: random, or an opponent that names no agent (self, pool).
OPPONENTS: tuple[str, ...] = ("random", *AgentOpponent)


def irl_overrides(settings: str, algo: str) -> dict[str, object]:
    """The IRL core's settings the study changes for ``settings`` (ours: none)."""
    if settings == "ours":
        return {}
    return {**AUTHORS_IRL, **(AUTHORS_HAIRL if algo == "hairl" else {})}


def matchup_label(name: str) -> str:
    """``hairl_dqn_vs_dqn`` -> ``H-AIRL-DQN vs DQN``."""
    return " vs ".join(KIND_LABELS[kind] for kind in name.split("_vs_"))


def one_of(name: str, value: str, allowed: Sequence[str]) -> dict[str, bool]:
    """A settings check that names the value given: ``folds in drop, impute (got 'x')``."""
    return {f"{name} in {', '.join(allowed)} (got {value!r})": value in allowed}


ONLINE_FIELDS = ("online_rounds", "online_generator_steps", "online_opponent")

MAX_RUNS = 10_000  # IRL runs per algorithm, as many as --seeds takes seeds
# Each count's upper bound: the bound of the stage that uses it (a match's hands, LBR's, the
# DQN's and the IRL trainer's), checked by StudyConfig before any stage runs.
STAGE_BOUNDS: dict[str, int] = {
    "runs": MAX_RUNS,
    "hands": MAX_HANDS,
    "panel_hands": MAX_HANDS,
    "lbr_hands": MAX_LBR_HANDS,
    "agent_hands": MAX_STEPS,
    "short_agent_hands": MAX_STEPS,
    "eval_every": MAX_STEPS,
    "eval_hands": MAX_HANDS,
    "irl_epochs": MAX_EPOCHS,
    "authors_repeats": MAX_RUNS,
    "authors_games": MAX_HANDS,
    "jobs": 1024,
}


@dataclass(frozen=True, kw_only=True)
class StudyConfig:
    """Every setting that determines a study's results (``jobs`` does not).

    ``irl_epochs`` None keeps the IRL core's defaults (the paper's poker settings);
    ``short_agent_hands`` trains a second sparse DQN set at the paper's training length
    (5,000 episodes) beside ours, on the same seeds. ``irl_settings`` and ``agent_preset``
    choose ours or the authors' settings; ``authors_repeats`` > 0 adds the authors' tournament
    (that many repeats of ``authors_games`` games per experiment and matchup);
    ``reward_sources`` replaces an algorithm's IRL runs by a reward (``authors:FILE``), as
    ``(algo, spec)`` pairs; ``reward_transform`` is the learned-reward DQNs' transform;
    ``algos`` the IRL algorithms trained (each gives an ``<algo>_dqn`` agent kind).
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
    irl_settings: str = "ours"
    agent_preset: str = "default"
    authors_repeats: int = 0
    authors_games: int = 1_000
    reward_sources: tuple[tuple[str, str], ...] = ()
    reward_transform: str = "raw"
    algos: tuple[str, ...] = PAPER_ALGOS
    encoding: str = "rlcard"  # what rewards, policies and DQNs read (pokerirl.game.encodings)
    folds: str = "drop"  # ingest's hands that end in a fold: left out, or imputed (docs/folds.md)
    # LBR (docs/exploit.md) against every panel member, per seed, from the turn; 0: none.
    lbr_hands: int = 10_000
    # What the poker sweep varies (docs/sweep.md): every DQN's training opponent, the learned
    # reward's payoff weight, the reward net's weight decay (None: the IRL core's), which
    # players are the expert (winners: >= winners_bb_per_100 over >= winners_min_hands in
    # the period) and the period of each month (fractions of its hands by time).
    opponent: str = "random"
    payoff_weight: float = 0.0
    reward_decay: float | None = None
    experts: str = "all"
    winners_bb_per_100: float = 0.0
    winners_min_hands: int = 200
    period: tuple[float, float] = (0.0, 1.0)
    # The IRL stage's mode (issue 43): offline (the paper's), or online as `train --mode
    # online` trains (the policy plays hands on the engine against ``online_opponent``),
    # ``online_rounds`` rounds of ``online_generator_steps`` decisions; None: that command's
    # defaults. Recorded only when online, so that offline studies keep their bytes.
    irl_mode: str = IRLMode.OFFLINE
    online_rounds: int | None = None
    online_generator_steps: int | None = None
    online_opponent: str | None = None
    jobs: int = 2  # processes; the one setting that does not change a result

    def __post_init__(self) -> None:
        algos = ", ".join(repr(algo) for algo, _ in self.reward_sources)
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
            f"LBR hands even and >= 0 (got {self.lbr_hands})": self.lbr_hands >= 0
            and self.lbr_hands % 2 == 0,
            **one_of("irl settings", self.irl_settings, IRL_SETTINGS),
            **one_of("agent preset", self.agent_preset, AGENT_PRESETS),
            "authors' repeats >= 0": self.authors_repeats >= 0,
            "authors' games >= 2": self.authors_games >= 2,
            f"algos among {', '.join(IRL_ALGOS)}, once each (got {', '.join(self.algos)})":
            len(self.algos) >= 1
            and set(self.algos) <= set(IRL_ALGOS)
            and len(set(self.algos)) == len(self.algos),
            f"reward sources for the study's algos, once each (got {algos})": all(
                algo in self.algos for algo, _ in self.reward_sources
            )
            and len({algo for algo, _ in self.reward_sources}) == len(self.reward_sources),
            **one_of("reward transform", self.reward_transform, TRANSFORMS),
            **one_of("encoding", self.encoding, ENCODING_NAMES),
            **one_of("folds", self.folds, FOLDS),
            **one_of("opponent", self.opponent, OPPONENTS),
            **one_of("experts", self.experts, EXPERTS),
            "payoff weight in [0, 1]": 0 <= self.payoff_weight <= 1,
            "reward decay >= 0": self.reward_decay is None or self.reward_decay >= 0,
            "winners' min hands >= 1": self.winners_min_hands >= 1,
            f"period START:END with 0 <= START < END <= 1 (got {self.period})": len(self.period)
            == 2 and 0 <= self.period[0] < self.period[1] <= 1,
            **one_of("IRL mode", self.irl_mode, tuple(IRLMode)),
            "online rounds, generator steps and opponent with the online IRL mode only": (
                self.irl_mode == IRLMode.ONLINE or not self.online_given()),
            # An imputed table weighs its rows; online IRL has no state to pair a weight with.
            "folds drop with the online IRL mode": self.irl_mode == IRLMode.OFFLINE
            or self.folds == FoldsMode.DROP,
        }
        broken = [name for name, ok in checks.items() if not ok]
        # every stage's bounds, before the first stage starts (an LBR of 10^15 hands was
        # refused only after ingest, IRL, the agents and the tournament had run)
        broken += [
            f"{name} <= {high:,} (got {getattr(self, name):,})"
            for name, high in STAGE_BOUNDS.items()
            if isinstance(getattr(self, name), int) and getattr(self, name) > high
        ]
        if broken:
            raise StudyError(f"bad study settings: {', '.join(broken)}")
        self.online_settings()  # online: an unknown opponent is refused before any stage

    def settings(self) -> dict[str, Any]:
        """What determines the results: every field but ``jobs``."""
        found = dataclasses.asdict(self)
        found.pop("jobs")
        # Studies made before encodings, fold imputation and a choice of algorithms keep
        # their records: these settings are written only when they are not the default.
        for name, default in UNRECORDED_DEFAULTS.items():
            if found[name] == default:
                found.pop(name)
        if "algos" in found:
            found["algos"] = list(self.algos)
        if "period" in found:
            found["period"] = list(self.period)
        found["seeds"] = list(self.seeds)
        found["reward_sources"] = [list(pair) for pair in self.reward_sources]
        for name in ("irl_mode", *ONLINE_FIELDS):
            found.pop(name, None)
        online = self.online_settings()
        if online is not None:  # the generator's settings, resolved, as its runs record them
            found["irl_mode"] = str(self.irl_mode)
            found.update({name: getattr(online, name.removeprefix("online_"))
                          for name in ONLINE_FIELDS})  # fmt: skip
            found["online_opponent"] = str(online.opponent)
        return found

    def online_given(self) -> bool:
        """Whether any online setting is given (not left to its default)."""
        return any(getattr(self, name) is not None for name in ONLINE_FIELDS)

    def online_settings(self) -> Any:
        """The IRL stage's :class:`~pokerirl.poker.online.PokerOnlineSettings`, or None
        offline (imported only then: it loads torch)."""
        if self.irl_mode != IRLMode.ONLINE:
            return None
        from pokerirl.poker.online import PokerOnlineSettings

        try:
            return PokerOnlineSettings.given(rounds=self.online_rounds,
                                             generator_steps=self.online_generator_steps,
                                             opponent=self.online_opponent)  # fmt: skip
        except ValueError as error:  # ConfigError: an unknown opponent, a count < 1
            raise StudyError(
                f"bad study settings, the online IRL mode's generator: {error}"
            ) from None

    @property
    def kinds(self) -> tuple[str, ...]:
        """The agent kinds (report.json names): the sparse DQN, then one per algorithm."""
        return ("dqn", *(f"{algo}_dqn" for algo in self.algos))

    @property
    def table1_kinds(self) -> tuple[str, ...]:
        """The learned-reward kinds Table 1 plays against the sparse DQN, in its order."""
        return tuple(f"{algo}_dqn" for algo in TABLE1_ORDER if algo in self.algos)

    def reward_source(self, algo: str) -> str | None:
        """The reward that replaces ``algo``'s IRL runs, if any."""
        return dict(self.reward_sources).get(algo)


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
        lbr_hands=500,
    ),
    # Seconds, not minutes: every stage runs, at sizes whose numbers mean nothing. For
    # checking a pipeline, a cluster or a data folder end to end before a real run.
    "smoke": StudyConfig(
        preset="smoke",
        runs=2,
        seeds=(0, 1),
        hands=200,
        panel_hands=100,
        agent_hands=400,
        short_agent_hands=200,
        eval_every=200,
        eval_hands=100,
        irl_epochs=1,
        lbr_hands=20,
    ),
    # `pokerirl demo`'s poker half, sized so that its report prints within about 2 minutes on
    # 2 cores: the quick preset's IRL (2 runs of 20 epochs) and training length (20k hands),
    # on 2 seeds (one per IRL run), with fewer evaluation, tournament, panel and LBR hands.
    "demo": StudyConfig(
        preset="demo",
        runs=2,
        seeds=(0, 1),
        hands=50_000,
        panel_hands=10_000,
        agent_hands=20_000,
        eval_every=5_000,
        eval_hands=2_000,
        irl_epochs=20,
        lbr_hands=200,
    ),
    # The authors' protocol (src/main.py, train_rl.py): per experiment k, IRL run k with their
    # settings, then a sparse DQN, an AIRL-DQN and an H-AIRL-DQN with their DQN preset (5,000
    # hands; the > 0.8 x best checkpoint plays), then 50 x 1,000 non-duplicate games per pair.
    # They ran 20 experiments; our own duplicate-deal Table 1 and panel play the same agents.
    "authors": StudyConfig(
        preset="authors",
        runs=20,
        seeds=tuple(range(20)),
        hands=100_000,
        panel_hands=20_000,
        agent_hands=5_000,
        short_agent_hands=5_000,
        eval_every=100,
        eval_hands=1_000,
        irl_settings="authors",
        agent_preset="authors",
        authors_repeats=50,
        lbr_hands=1_000,
    ),
}


# What `pokerirl sweep --preset sample` chose on the first 60% of the April 1995 sample
# (docs/results/poker-real: its cell drop-all-rlcard-hairl-decay0-advantage-w0-pool-20k, chosen
# by a rule fixed in advance; it met 2 of the 5 targets, no cell met more), at the quick
# preset's sizes: H-AIRL on RLCard's encoding, the advantage transform, every DQN trained
# against the pool. Shown with --period 0.6:1 on the later hands.
PRESETS["real"] = dataclasses.replace(
    PRESETS["quick"], preset="real", algos=("hairl",), encoding="rlcard",
    reward_transform="advantage", opponent="pool",
)  # fmt: skip


def preset(name: str, **overrides: Any) -> StudyConfig:
    """The preset ``name`` with ``overrides`` (None values ignored)."""
    changes = {k: v for k, v in overrides.items() if v is not None}
    if "seeds" in changes:
        changes["seeds"] = tuple(changes["seeds"])
    elif name == "authors" and "runs" in changes:
        changes["seeds"] = tuple(range(changes["runs"]))  # experiment k: IRL run k, seed k
    if "algos" in changes:  # in one order, so that the same choice is the same study
        rank = {algo: k for k, algo in enumerate(IRL_ALGOS)}
        changes["algos"] = tuple(sorted(changes["algos"], key=lambda a: rank.get(a, len(rank))))
    if "reward_sources" in changes:
        changes["reward_sources"] = tuple(tuple(pair) for pair in changes["reward_sources"])
    if "period" in changes:
        changes["period"] = tuple(changes["period"])
    return with_overrides(PRESETS, name, **changes)
