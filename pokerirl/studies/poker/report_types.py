"""The poker study's ``report.json``, typed: what :func:`~pokerirl.studies.poker.report.
render_markdown`, the figures and ``pokerirl report`` read.

``to_json`` writes exactly the names (and their order) ``report.json`` has always had;
``from_json`` reads one back (``from_json(data).to_json() == data``). The parts that are the
paper's constants or the study's settings stay open mappings.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pokerirl.meanstd import MeanStd
from pokerirl.serial import Omit, Serializable, meta
from pokerirl.studies.poker.results import Json, Panel, Reference, Replaced, Table1Line


@dataclass(frozen=True, kw_only=True)
class Table1Row(Serializable):
    """One Table 1 matchup: ours (the tournament's pooled line) and the paper's (None for a
    matchup the paper does not have: GAIL's)."""

    line: Table1Line = field(metadata=meta(flatten=True))
    paper: Reference | None


@dataclass(frozen=True, kw_only=True)
class DataPart(Serializable):
    """The table's size (None where the ingest summary lacks it)."""

    kept_hands: int | None
    rows: int | None
    hands_read_total: int | None


@dataclass(frozen=True, kw_only=True)
class IRLPaper(Serializable):
    """An algorithm's final alignment and discriminator accuracy as the paper gives them
    (None: an algorithm the paper does not have, GAIL)."""

    final_val_alignment: MeanStd | None
    final_disc_acc: float | None


@dataclass(frozen=True, kw_only=True)
class IRLAlgoPart(Serializable):
    """One algorithm's trained IRL runs: final alignment and discriminator accuracy, with the
    paper's."""

    final_val_alignment: MeanStd
    final_disc_acc_expert: MeanStd
    final_disc_acc_policy: MeanStd
    per_run_val_alignment: list[float]
    paper: IRLPaper
    # f's argmax against the expert on validation states (runs that record it; the policy's
    # alignment is final_val_alignment).
    final_val_reward_alignment: MeanStd | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )


@dataclass(frozen=True, kw_only=True)
class BCPart(Serializable):
    """Behavioural cloning, trained inside every IRL run."""

    final_val_alignment: MeanStd
    per_run_val_alignment: list[float]


@dataclass(frozen=True, kw_only=True)
class IRLPart(Serializable):
    """Every algorithm (trained or replaced: its keys, first); BC, the baselines and the
    epochs when any algorithm was trained."""

    algos: Mapping[str, IRLAlgoPart | Replaced] = field(metadata=meta(flatten=True))
    bc: BCPart | None = field(default=None, metadata=meta(omit=Omit.NONE))
    baselines: Mapping[str, MeanStd] | None = field(default=None, metadata=meta(omit=Omit.NONE))
    epochs: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    runs: int


@dataclass(frozen=True, kw_only=True)
class RLKindPart(Serializable):
    """One agent kind against random: mean and std over seeds, and the paper's figure (None:
    a kind the paper does not have)."""

    mean: float
    std: float
    paper: float | None


@dataclass(frozen=True, kw_only=True)
class RLPart(Serializable):
    """Every agent kind against random (its keys, first), the fixed-strategy references, each
    seed's value and what was measured (None: a report written before it was said)."""

    kinds: Mapping[str, RLKindPart] = field(metadata=meta(flatten=True))
    references: Mapping[str, Reference]
    per_seed: Mapping[str, list[float]]
    measured: str | None = field(default=None, metadata=meta(omit=Omit.NONE))
    # Each learned-reward kind's share of its decisions against random that take its reward's
    # best legal action, per seed (agents trained before the metric: absent).
    follows_reward: Mapping[str, list[float]] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )


@dataclass(frozen=True, kw_only=True)
class HandsResult(Serializable):
    """The sparse DQN's final value against random after ``hands`` training hands."""

    hands: int
    mean: float
    std: float


@dataclass(frozen=True, kw_only=True)
class TrainingLengthPart(Serializable):
    """The sparse DQN at the paper's training length (short) and at ours (long)."""

    short: HandsResult
    long: HandsResult
    paper: str


LBR_KEYS = ("lbr_mbb_per_hand", "lbr_std_error", "lbr_hands", "lbr_check_until")


@dataclass(frozen=True, kw_only=True)
class PanelPart(Serializable):
    """The panel's cross-table and its hands per seed per pair; LBR's hands per seed against
    each member, and the street from which it bets (it checks or calls before)."""

    panel: Panel = field(metadata=meta(flatten=True))
    hands: int
    lbr_hands: int = 0
    lbr_check_until: str = "turn"

    def to_json(self) -> Json:
        found: Json = super().to_json()
        if not self.lbr_hands:  # no LBR: the keys of reports written before it
            return {key: value for key, value in found.items() if key not in LBR_KEYS}
        return found


@dataclass(frozen=True, kw_only=True)
class CardSummary(Serializable):
    """One algorithm's reward cards over its runs (``reward_card.card_summary``), with the
    first run's figure."""

    runs: int
    mean_f: Mapping[str, MeanStd]
    decision_bonus: MeanStd
    argmax_share: Mapping[str, MeanStd]
    agree_expert: MeanStd
    agree_legal_majority: MeanStd
    legal_majority_agree_expert: MeanStd
    expert_share: Mapping[str, MeanStd] | None
    predictions: list[str]
    figure: str | None = field(default=None, metadata=meta(omit=Omit.NONE))
    # runs whose reward argmax falls below their BC baseline
    below_bc: int | None = field(default=None, metadata=meta(omit=Omit.NONE))


@dataclass(frozen=True, kw_only=True)
class AuthorsRow(Serializable):
    """One matchup under the authors' tournament protocol, with the paper's Table 1 line:
    :class:`~pokerirl.tournaments.authors.AuthorsSummary`'s fields (not its subclass: reading
    a report loads no tournament code; a test checks the fields agree), then ``paper``."""

    mean: float
    paper_style_se: float
    se_over_experiments: float | None
    duplicate_mbb_per_hand: float | None
    per_experiment: list[float]
    repeats: int
    games: int
    agent_a: str
    agent_b: str
    paper: Reference | None


@dataclass(frozen=True, kw_only=True)
class StudyReport(Serializable):
    """The whole ``report.json``: the settings, every stage's numbers beside the paper's, the
    figures' paths; the reward cards and the authors' tournament when the study made them."""

    format: str
    preset: str
    runs: int
    seeds: list[int]
    hands: int
    settings: Mapping[str, Any]  # StudyConfig.settings(): open-ended
    data: DataPart
    table1: Mapping[str, Table1Row]
    irl: IRLPart
    rl_vs_random: RLPart
    training_length: TrainingLengthPart
    panel: PanelPart
    figures: Mapping[str, str]
    paper: Mapping[str, Any]  # paper.paper_values(): the paper's constants
    reward_cards: Mapping[str, CardSummary | None] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )
    table1_authors: Mapping[str, AuthorsRow] | None = field(
        default=None, metadata=meta(omit=Omit.NONE)
    )
