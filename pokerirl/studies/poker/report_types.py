"""The poker study's ``report.json``, typed: what :func:`~pokerirl.studies.poker.report.
render_markdown`, the figures and ``pokerirl report`` read.

``to_json`` writes exactly the names (and their order) ``report.json`` has always had;
``from_json`` reads one back (``from_json(data).to_json() == data``). The parts that are the
paper's constants or the study's settings stay open mappings.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pokerirl.meanstd import MeanStd
from pokerirl.studies.poker.results import Json, Panel, Reference, Table1Line


def _stats(data: Mapping[str, Any]) -> dict[str, MeanStd]:
    return {key: MeanStd.from_json(value) for key, value in data.items()}


def _stats_json(stats: Mapping[str, MeanStd]) -> Json:
    return {key: value.to_json() for key, value in stats.items()}


@dataclass(frozen=True, kw_only=True)
class PaperLine:
    """A Table 1 result as the paper gives it."""

    mbb_per_hand: float
    std_error: float

    def to_json(self) -> Json:
        return {"mbb_per_hand": self.mbb_per_hand, "std_error": self.std_error}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PaperLine:
        return cls(mbb_per_hand=data["mbb_per_hand"], std_error=data["std_error"])


def _paper_line(data: Mapping[str, Any] | None) -> PaperLine | None:
    return None if data is None else PaperLine.from_json(data)


def _json_or_none(part: PaperLine | MeanStd | None) -> Json | None:
    return None if part is None else part.to_json()


@dataclass(frozen=True, kw_only=True)
class Table1Row:
    """One Table 1 matchup: ours (the tournament's pooled line) and the paper's (None for a
    matchup the paper does not have: GAIL's)."""

    line: Table1Line
    paper: PaperLine | None

    def to_json(self) -> Json:
        return {**self.line.to_json(), "paper": _json_or_none(self.paper)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Table1Row:
        line = Table1Line(**{k: v for k, v in data.items() if k != "paper"})
        return cls(line=line, paper=_paper_line(data["paper"]))


@dataclass(frozen=True, kw_only=True)
class DataPart:
    """The table's size (None where the ingest summary lacks it)."""

    kept_hands: int | None
    rows: int | None
    hands_read_total: int | None

    def to_json(self) -> Json:
        return {
            "kept_hands": self.kept_hands,
            "rows": self.rows,
            "hands_read_total": self.hands_read_total,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> DataPart:
        return cls(kept_hands=data["kept_hands"], rows=data["rows"],
                   hands_read_total=data["hands_read_total"])  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class IRLAlgoPart:
    """One algorithm's trained IRL runs: final alignment and discriminator accuracy, with the
    paper's."""

    final_val_alignment: MeanStd
    final_disc_acc_expert: MeanStd
    final_disc_acc_policy: MeanStd
    per_run_val_alignment: list[float]
    paper_val_alignment: MeanStd | None  # None: an algorithm the paper does not have
    paper_disc_acc: float | None

    def to_json(self) -> Json:
        return {
            "final_val_alignment": self.final_val_alignment.to_json(),
            "final_disc_acc_expert": self.final_disc_acc_expert.to_json(),
            "final_disc_acc_policy": self.final_disc_acc_policy.to_json(),
            "per_run_val_alignment": self.per_run_val_alignment,
            "paper": {
                "final_val_alignment": _json_or_none(self.paper_val_alignment),
                "final_disc_acc": self.paper_disc_acc,
            },
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> IRLAlgoPart:
        return cls(
            final_val_alignment=MeanStd.from_json(data["final_val_alignment"]),
            final_disc_acc_expert=MeanStd.from_json(data["final_disc_acc_expert"]),
            final_disc_acc_policy=MeanStd.from_json(data["final_disc_acc_policy"]),
            per_run_val_alignment=list(data["per_run_val_alignment"]),
            paper_val_alignment=(None if data["paper"]["final_val_alignment"] is None
                                 else MeanStd.from_json(data["paper"]["final_val_alignment"])),
            paper_disc_acc=data["paper"]["final_disc_acc"],
        )


@dataclass(frozen=True, kw_only=True)
class IRLReplacedPart:
    """An algorithm whose IRL runs a given reward replaced."""

    replaced_by: str

    def to_json(self) -> Json:
        return {"replaced_by": self.replaced_by}


@dataclass(frozen=True, kw_only=True)
class BCPart:
    """Behavioural cloning, trained inside every IRL run."""

    final_val_alignment: MeanStd
    per_run_val_alignment: list[float]

    def to_json(self) -> Json:
        return {
            "final_val_alignment": self.final_val_alignment.to_json(),
            "per_run_val_alignment": self.per_run_val_alignment,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> BCPart:
        return cls(final_val_alignment=MeanStd.from_json(data["final_val_alignment"]),
                   per_run_val_alignment=list(data["per_run_val_alignment"]))  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class IRLPart:
    """Every algorithm (trained or replaced); BC, the baselines and the epochs when any
    algorithm was trained."""

    algos: Mapping[str, IRLAlgoPart | IRLReplacedPart]
    runs: int
    bc: BCPart | None = None
    baselines: Mapping[str, MeanStd] | None = None
    epochs: int | None = None

    def to_json(self) -> Json:
        found: Json = {algo: part.to_json() for algo, part in self.algos.items()}
        if self.bc is not None:
            found["bc"] = self.bc.to_json()
        if self.baselines is not None:
            found["baselines"] = _stats_json(self.baselines)
        if self.epochs is not None:
            found["epochs"] = self.epochs
        found["runs"] = self.runs
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> IRLPart:
        algos: dict[str, IRLAlgoPart | IRLReplacedPart] = {}
        for algo, part in data.items():
            if algo in ("bc", "baselines", "epochs", "runs"):
                continue
            algos[algo] = (
                IRLReplacedPart(replaced_by=part["replaced_by"])
                if "replaced_by" in part
                else IRLAlgoPart.from_json(part)
            )
        return cls(
            algos=algos,
            runs=data["runs"],
            bc=BCPart.from_json(data["bc"]) if "bc" in data else None,
            baselines=_stats(data["baselines"]) if "baselines" in data else None,
            epochs=data.get("epochs"),
        )


@dataclass(frozen=True, kw_only=True)
class RLKindPart:
    """One agent kind against random: mean and std over seeds, and the paper's figure (None:
    a kind the paper does not have)."""

    mean: float
    std: float
    paper: float | None

    def to_json(self) -> Json:
        return {"mean": self.mean, "std": self.std, "paper": self.paper}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RLKindPart:
        return cls(mean=data["mean"], std=data["std"], paper=data["paper"])


@dataclass(frozen=True, kw_only=True)
class RLPart:
    """Every agent kind against random, the fixed-strategy references, each seed's value and
    what was measured (None: a report written before it was said)."""

    kinds: Mapping[str, RLKindPart]
    references: Mapping[str, Reference]
    per_seed: Mapping[str, list[float]]
    measured: str | None = None

    def to_json(self) -> Json:
        found: Json = {kind: part.to_json() for kind, part in self.kinds.items()}
        found["references"] = {name: ref.to_json() for name, ref in self.references.items()}
        found["per_seed"] = dict(self.per_seed)
        if self.measured is not None:
            found["measured"] = self.measured
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RLPart:
        rest = ("references", "per_seed", "measured")
        return cls(
            kinds={k: RLKindPart.from_json(v) for k, v in data.items() if k not in rest},
            references={k: Reference(**v) for k, v in data["references"].items()},
            per_seed={k: list(v) for k, v in data["per_seed"].items()},
            measured=data.get("measured"),
        )


@dataclass(frozen=True, kw_only=True)
class HandsResult:
    """The sparse DQN's final value against random after ``hands`` training hands."""

    hands: int
    mean: float
    std: float

    def to_json(self) -> Json:
        return {"hands": self.hands, "mean": self.mean, "std": self.std}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> HandsResult:
        return cls(hands=data["hands"], mean=data["mean"], std=data["std"])


@dataclass(frozen=True, kw_only=True)
class TrainingLengthPart:
    """The sparse DQN at the paper's training length (short) and at ours (long)."""

    short: HandsResult
    long: HandsResult
    paper: str

    def to_json(self) -> Json:
        return {"short": self.short.to_json(), "long": self.long.to_json(), "paper": self.paper}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TrainingLengthPart:
        return cls(short=HandsResult.from_json(data["short"]),
                   long=HandsResult.from_json(data["long"]), paper=data["paper"])  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class PanelPart:
    """The panel's cross-table and its hands per seed per pair; LBR's hands per seed against
    each member, and the street from which it bets (it checks or calls before)."""

    panel: Panel
    hands: int
    lbr_hands: int = 0
    lbr_check_until: str = "turn"

    def to_json(self) -> Json:
        found = {**self.panel.to_json(), "hands": self.hands}
        if not self.lbr_hands:  # no LBR: the keys of reports written before it
            found.pop("lbr_mbb_per_hand")
            found.pop("lbr_std_error")
            return found
        return {**found, "lbr_hands": self.lbr_hands, "lbr_check_until": self.lbr_check_until}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PanelPart:
        panel = Panel(agents=list(data["agents"]), mbb_per_hand=data["mbb_per_hand"],
                      std_error=data["std_error"],
                      lbr_mbb_per_hand=list(data.get("lbr_mbb_per_hand", [])),
                      lbr_std_error=list(data.get("lbr_std_error", [])))  # fmt: skip
        return cls(panel=panel, hands=data["hands"], lbr_hands=data.get("lbr_hands", 0),
                   lbr_check_until=data.get("lbr_check_until", "turn"))  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class CardSummary:
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
    figure: str | None = None
    below_bc: int | None = None  # runs whose reward argmax falls below their BC baseline

    def to_json(self) -> Json:
        found: Json = {
            "runs": self.runs,
            "mean_f": _stats_json(self.mean_f),
            "decision_bonus": self.decision_bonus.to_json(),
            "argmax_share": _stats_json(self.argmax_share),
            "agree_expert": self.agree_expert.to_json(),
            "agree_legal_majority": self.agree_legal_majority.to_json(),
            "legal_majority_agree_expert": self.legal_majority_agree_expert.to_json(),
            "expert_share": None if self.expert_share is None else _stats_json(self.expert_share),
            "predictions": self.predictions,
        }
        if self.figure is not None:
            found["figure"] = self.figure
        if self.below_bc is not None:
            found["below_bc"] = self.below_bc
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> CardSummary:
        expert = data.get("expert_share")
        return cls(
            runs=data["runs"],
            mean_f=_stats(data["mean_f"]),
            decision_bonus=MeanStd.from_json(data["decision_bonus"]),
            argmax_share=_stats(data["argmax_share"]),
            agree_expert=MeanStd.from_json(data["agree_expert"]),
            agree_legal_majority=MeanStd.from_json(data["agree_legal_majority"]),
            legal_majority_agree_expert=MeanStd.from_json(data["legal_majority_agree_expert"]),
            expert_share=None if expert is None else _stats(expert),
            predictions=list(data["predictions"]),
            figure=data.get("figure"),
            below_bc=data.get("below_bc"),
        )


@dataclass(frozen=True, kw_only=True)
class AuthorsRow:
    """One matchup under the authors' tournament protocol (``AuthorsMatchup.summary``), with
    the paper's Table 1 line."""

    mean: float
    paper_style_se: float
    se_over_experiments: float | None
    duplicate_mbb_per_hand: float | None
    per_experiment: list[float]
    repeats: int
    games: int
    agent_a: str
    agent_b: str
    paper: PaperLine | None

    def to_json(self) -> Json:
        return {
            "mean": self.mean,
            "paper_style_se": self.paper_style_se,
            "se_over_experiments": self.se_over_experiments,
            "duplicate_mbb_per_hand": self.duplicate_mbb_per_hand,
            "per_experiment": self.per_experiment,
            "repeats": self.repeats,
            "games": self.games,
            "agent_a": self.agent_a,
            "agent_b": self.agent_b,
            "paper": _json_or_none(self.paper),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> AuthorsRow:
        return cls(
            **{k: v for k, v in data.items() if k not in ("paper", "per_experiment")},
            per_experiment=list(data["per_experiment"]),
            paper=_paper_line(data["paper"]),
        )


@dataclass(frozen=True, kw_only=True)
class StudyReport:
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
    reward_cards: Mapping[str, CardSummary | None] | None = None
    table1_authors: Mapping[str, AuthorsRow] | None = None

    def to_json(self) -> Json:
        found: Json = {
            "format": self.format,
            "preset": self.preset,
            "runs": self.runs,
            "seeds": self.seeds,
            "hands": self.hands,
            "settings": dict(self.settings),
            "data": self.data.to_json(),
            "table1": {name: row.to_json() for name, row in self.table1.items()},
            "irl": self.irl.to_json(),
            "rl_vs_random": self.rl_vs_random.to_json(),
            "training_length": self.training_length.to_json(),
            "panel": self.panel.to_json(),
            "figures": dict(self.figures),
            "paper": dict(self.paper),
        }
        if self.reward_cards is not None:
            found["reward_cards"] = {
                algo: None if card is None else card.to_json()
                for algo, card in self.reward_cards.items()
            }
        if self.table1_authors is not None:
            found["table1_authors"] = {
                name: row.to_json() for name, row in self.table1_authors.items()
            }
        return found

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> StudyReport:
        cards = data.get("reward_cards")
        authors = data.get("table1_authors")
        return cls(
            format=data["format"],
            preset=data["preset"],
            runs=data["runs"],
            seeds=list(data["seeds"]),
            hands=data["hands"],
            settings=data["settings"],
            data=DataPart.from_json(data["data"]),
            table1={name: Table1Row.from_json(row) for name, row in data["table1"].items()},
            irl=IRLPart.from_json(data["irl"]),
            rl_vs_random=RLPart.from_json(data["rl_vs_random"]),
            training_length=TrainingLengthPart.from_json(data["training_length"]),
            panel=PanelPart.from_json(data["panel"]),
            figures=data["figures"],
            paper=data["paper"],
            reward_cards=None if cards is None else {
                algo: None if card is None else CardSummary.from_json(card)
                for algo, card in cards.items()
            },
            table1_authors=None if authors is None else {
                name: AuthorsRow.from_json(row) for name, row in authors.items()
            },
        )  # fmt: skip
