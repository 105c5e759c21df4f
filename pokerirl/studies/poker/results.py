"""What each stage of the poker study hands to the report and the figures, typed.

Each is read again from the stage's units on every run (:mod:`pokerirl.studies.poker.pipeline`);
``to_json`` gives the JSON the report is built of (the names ``report.json`` has always had),
``from_json`` reads it back.

>>> Spread.of([1.0, 3.0]).to_json()
{'values': [1.0, 3.0], 'mean': 2.0, 'std': 1.4142135623730951}
>>> Spread.from_json(Spread.of([2.0]).to_json())
Spread(values=[2.0], mean=2.0, std=0.0)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from pokerirl.meanstd import Curve, MeanStd, mean_and_std
from pokerirl.serial import Omit, Serializable, meta

Json = dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class Ingested:
    """The table's summary (``datasets.ingest``'s), and the print of the ingest stage that an
    older pokerirl's later stage records were made with."""

    # The file as written, whatever pokerirl wrote it: only this package's report reads it.
    summary: dict[str, Any]
    fingerprint: str


@dataclass(frozen=True, kw_only=True)
class Spread(Serializable):
    """Values (one per run or seed) with their mean and sample std."""

    values: list[float]
    mean: float
    std: float

    @classmethod
    def of(cls, values: Sequence[float]) -> Spread:
        mean, std = mean_and_std(values)
        return cls(values=list(values), mean=mean, std=std)

    @property
    def stats(self) -> MeanStd:
        return MeanStd(mean=self.mean, std=self.std)


@dataclass(frozen=True, kw_only=True)
class IRLRuns(Serializable):
    """One algorithm's IRL runs: per-epoch curves, finals per run, the mean action
    distributions at the end, and the baselines trained beside them."""

    runs: int
    epochs: int
    curves: dict[str, Curve]  # val_alignment, disc_acc_expert, disc_acc_policy, ...
    final: dict[str, Spread]  # the curves' last values
    action_dist: dict[str, Curve]  # val_expert_dist, val_policy_dist
    baselines: dict[str, Spread]  # majority, legal_majority, bc


@dataclass(frozen=True, kw_only=True)
class Replaced(Serializable):
    """An algorithm whose IRL runs a given reward replaced (``authors:FILE``)."""

    source: str = field(metadata=meta(key="replaced_by"))


IRLResult = dict[str, IRLRuns | Replaced]  # by algorithm


@dataclass(frozen=True, kw_only=True)
class Reference(Serializable):
    """A win rate in mbb/h and its standard error: a fixed strategy's against random, or a
    Table 1 line as the paper gives it."""

    mbb_per_hand: float
    std_error: float


@dataclass(frozen=True, kw_only=True)
class TrainingLength(Serializable):
    """The sparse DQN's final results at our training length and at the paper's."""

    agent_hands: int
    short_agent_hands: int
    long: list[float]
    short: list[float]


@dataclass(frozen=True, kw_only=True)
class AgentsResult(Serializable):
    """Every agent kind over its seeds: its last evaluation against random, its curve (at
    the hands of each evaluation), the training-length comparison, the references; with the
    authors' preset, the playing checkpoint measured against random."""

    final_vs_random: dict[str, list[float]]
    curves: dict[str, Curve]
    training_length: TrainingLength
    references: dict[str, Reference]
    playing_vs_random: dict[str, list[float]] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )
    playing_hands: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    # Learned-reward kinds: how closely each seed's DQN follows its reward (read from its
    # last evaluation; None for agents trained before the metric).
    follows_reward: dict[str, list[float]] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )

    @property
    def vs_random(self) -> dict[str, list[float]]:
        """What the report measures: the playing checkpoint where one is kept."""
        return self.final_vs_random if self.playing_vs_random is None else self.playing_vs_random


@dataclass(frozen=True, kw_only=True)
class Table1Line(Serializable):
    """One Table 1 matchup against the sparse DQN: the tournament comparison's test (across
    training seeds: seed k against seed k) and its seeds.

    ``replicated_over`` (the tournament's ``Replication``: ``training seeds`` or ``deal seeds
    only``), the agents per side, ``df`` and the deal-only standard error are None in reports
    written before they were said; those tested over the seeds as the replicates too."""

    mbb_per_hand: float
    std_error: float
    p_value: float
    p_bonferroni: float
    p_holm: float
    n: int
    per_seed: list[float] = field(default_factory=list)
    seeds_significant_bonferroni: int = 0
    replicated_over: str | None = field(default=None, metadata=meta(omit=Omit.NONE))
    agents_a: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    agents_b: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    df: float | None = field(default=None, metadata=meta(omit=Omit.NONE))
    deal_std_error: float | None = field(default=None, metadata=meta(omit=Omit.NONE))


@dataclass(frozen=True, kw_only=True)
class Panel(Serializable):
    """Every panel member against every other: row agent's mbb/h and its SE (None on the
    diagonal), from the tournament's comparison of the pair (across training seeds where a
    side has several agents); and LBR's win rate against each member with its SE, pooled over
    seeds (None: not measured). ``replicated_over``: each cell's unit of replication (the
    tournament's ``Replication``), None in reports written before it was said."""

    agents: list[str]
    mbb_per_hand: list[list[float | None]]
    std_error: list[list[float | None]]
    lbr_mbb_per_hand: list[float | None] = field(default_factory=list)
    lbr_std_error: list[float | None] = field(default_factory=list)
    replicated_over: list[list[str | None]] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )
