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

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from pokerirl.meanstd import MeanStd, mean_and_std, mean_std_curve

Json = dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class Ingested:
    """The table's summary (``datasets.ingest``'s), and the print of the ingest stage that an
    older pokerirl's later stage records were made with."""

    # The file as written, whatever pokerirl wrote it: only this package's report reads it.
    summary: dict[str, Any]
    fingerprint: str


@dataclass(frozen=True, kw_only=True)
class Curve:
    """Mean and std per point (an epoch, an action) over runs or seeds."""

    mean: list[float]
    std: list[float]

    @classmethod
    def of(cls, values: Sequence[Sequence[float]]) -> Curve:
        """Over the first axis of ``values`` (one row per run)."""
        mean, std = mean_std_curve(values)
        return cls(mean=mean, std=std)

    def to_json(self) -> Json:
        return {"mean": self.mean, "std": self.std}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Curve:
        return cls(mean=list(data["mean"]), std=list(data["std"]))


@dataclass(frozen=True, kw_only=True)
class Spread:
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

    def to_json(self) -> Json:
        return {"values": self.values, "mean": self.mean, "std": self.std}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Spread:
        return cls(values=list(data["values"]), mean=data["mean"], std=data["std"])


@dataclass(frozen=True, kw_only=True)
class IRLRuns:
    """One algorithm's IRL runs: per-epoch curves, finals per run, the mean action
    distributions at the end, and the baselines trained beside them."""

    runs: int
    epochs: int
    curves: dict[str, Curve]  # val_alignment, disc_acc_expert, disc_acc_policy, ...
    final: dict[str, Spread]  # the curves' last values
    action_dist: dict[str, Curve]  # val_expert_dist, val_policy_dist
    baselines: dict[str, Spread]  # majority, legal_majority, bc

    def to_json(self) -> Json:
        return {
            "runs": self.runs,
            "epochs": self.epochs,
            "curves": {key: curve.to_json() for key, curve in self.curves.items()},
            "final": {key: spread.to_json() for key, spread in self.final.items()},
            "action_dist": {key: curve.to_json() for key, curve in self.action_dist.items()},
            "baselines": {key: spread.to_json() for key, spread in self.baselines.items()},
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> IRLRuns:
        return cls(
            runs=data["runs"],
            epochs=data["epochs"],
            curves={k: Curve.from_json(v) for k, v in data["curves"].items()},
            final={k: Spread.from_json(v) for k, v in data["final"].items()},
            action_dist={k: Curve.from_json(v) for k, v in data["action_dist"].items()},
            baselines={k: Spread.from_json(v) for k, v in data["baselines"].items()},
        )


@dataclass(frozen=True, kw_only=True)
class Replaced:
    """An algorithm whose IRL runs a given reward replaced (``authors:FILE``)."""

    source: str

    def to_json(self) -> Json:
        return {"replaced": self.source}


IRLResult = dict[str, IRLRuns | Replaced]  # by algorithm


@dataclass(frozen=True, kw_only=True)
class HandsCurve:
    """Mbb/h against random at each evaluation, mean and std over seeds."""

    hands: list[int]
    mean: list[float]
    std: list[float]

    def to_json(self) -> Json:
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class Reference:
    """A fixed strategy against random."""

    mbb_per_hand: float
    std_error: float

    def to_json(self) -> Json:
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class TrainingLength:
    """The sparse DQN's final results at our training length and at the paper's."""

    agent_hands: int
    short_agent_hands: int
    long: list[float]
    short: list[float]

    def to_json(self) -> Json:
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class AgentsResult:
    """Every agent kind over its seeds: its last evaluation against random, its curve, the
    training-length comparison, the references; with the authors' preset, the playing
    checkpoint measured against random."""

    final_vs_random: dict[str, list[float]]
    curves: dict[str, HandsCurve]
    training_length: TrainingLength
    references: dict[str, Reference]
    playing_vs_random: dict[str, list[float]] | None = None
    playing_hands: int | None = None

    @property
    def vs_random(self) -> dict[str, list[float]]:
        """What the report measures: the playing checkpoint where one is kept."""
        return self.final_vs_random if self.playing_vs_random is None else self.playing_vs_random

    def to_json(self) -> Json:
        found: Json = {
            "final_vs_random": self.final_vs_random,
            "curves": {kind: curve.to_json() for kind, curve in self.curves.items()},
            "training_length": self.training_length.to_json(),
            "references": {name: ref.to_json() for name, ref in self.references.items()},
        }
        if self.playing_vs_random is not None:
            found["playing_vs_random"] = self.playing_vs_random
            found["playing_hands"] = self.playing_hands
        return found


@dataclass(frozen=True, kw_only=True)
class Table1Line:
    """One Table 1 matchup against the sparse DQN: the pooled line and its seeds."""

    mbb_per_hand: float
    std_error: float
    p_value: float
    p_bonferroni: float
    p_holm: float
    n: int
    per_seed: list[float] = field(default_factory=list)
    seeds_significant_bonferroni: int = 0

    def to_json(self) -> Json:
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class Panel:
    """Every panel member against every other: row agent's mbb/h and its SE (None on the
    diagonal); and LBR's win rate against each member with its SE, pooled over seeds (None:
    not measured)."""

    agents: list[str]
    mbb_per_hand: list[list[float | None]]
    std_error: list[list[float | None]]
    lbr_mbb_per_hand: list[float | None] = field(default_factory=list)
    lbr_std_error: list[float | None] = field(default_factory=list)

    def to_json(self) -> Json:
        return asdict(self)
