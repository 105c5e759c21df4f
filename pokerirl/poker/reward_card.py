"""The reward card: what a poker reward prefers, in one JSON file and one figure.

For a reward (any :class:`~pokerirl.poker.rewards.PokerReward`: a run folder's f, an
``authors:FILE``, a transform of either) over a set of decision states (a decision table's
rows, or a run's validation hands), the card holds:

* ``mean_f`` / ``std_f``: f of each action over the states where it is legal;
* ``decision_bonus``: the mean over states of the mean of f over the legal actions that go on
  with the hand (all but fold, whose f is what ending the hand costs): the reward a DQN
  collects per decision whatever it plays, and ``decision_bonus_sign``. A positive bonus pays
  an agent to prolong hands (raise); a negative one to end them;
* ``argmax_share``: the share of states where each action is f's argmax over the *legal*
  actions, overall, ``argmax_share_by_street`` (preflop .. river) and
  ``argmax_share_by_strength`` (buckets of equity against a random hand, see
  :func:`equity`);
* ``agree_expert`` (the argmax is the expert's action) and ``agree_legal_majority`` (it is
  the legal-majority rule's: check if legal, else call), with the rule's own agreement with
  the expert beside them;
* ``prediction``: in one line, what the card predicts a DQN will learn from it;
* ``expert_share`` (and ``expert_share_by_strength``): the expert's own actions on the same
  states, to read the argmax shares against.

On a table of ``ingest --folds impute`` (``weight`` and ``imputed`` columns) every share and
mean weighs each row by its weight (a hidden decision counts once over its draws), and
``by_part`` gives the main numbers over the observed rows and the imputed ones apart.

>>> from pokerirl.poker.rewards import ObsReward
>>> states = CardStates.from_arrays(
...     obs=np.zeros((2, 72), np.uint8), legal_mask=np.array([[1, 1, 1, 0], [0, 1, 1, 1]], bool),
...     cards=np.array([[0, 13, -1, -1, -1, -1, -1]] * 2), expert=np.array([0, 3]))
>>> card = reward_card(ObsReward(lambda obs, a: (a == 3).astype(np.float32)), states)
>>> card.argmax_share["check"], card.argmax_share["call"], card.agree_expert
(0.5, 0.5, 1.0)
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from pokerirl.datasets.decisions import check_legal_actions, table_cards
from pokerirl.errors import InputError
from pokerirl.game.bots import street_of
from pokerirl.game.evaluator import hand_strength
from pokerirl.holdem import ACTIONS, CALL, CHECK, FOLD, NUM_ACTIONS
from pokerirl.irl.metrics import Metric
from pokerirl.jsonio import parse_json, read_bytes, read_json
from pokerirl.poker.rewards import ObservedDecisions, PokerReward
from pokerirl.serial import Omit, Serializable, meta

CARD_FILE, CARD_FIGURE = "reward_card.json", "reward_card.png"
CARD_FORMAT = "pokerirl-reward-card/1"
STREETS = ("preflop", "flop", "turn", "river")
STRENGTH_EDGES = (0.25, 0.5, 0.75)  # equity buckets: < 25%, 25-50%, 50-75%, >= 75%
STRENGTH_LABELS = ("<25%", "25-50%", "50-75%", ">=75%")
EQUITY_SAMPLES = 256
EQUITY_SEED = 20_240_601
BONUS_TOLERANCE = 0.05  # |bonus| below this reads as "about 0 per decision"
TABLE_COLUMNS = ("hand_id", "obs", "legal_mask", "action_id", "hole_cards", "board")
WEIGHT_COLUMNS = ("weight", "imputed")  # a table of ingest --folds impute
PARTS = ("observed", "imputed")


# --------------------------------------------------------------------------- states


def equity(cards: np.ndarray, *, samples: int = EQUITY_SAMPLES, seed: int = EQUITY_SEED,
           chunk: int = 256, progress: bool = False) -> np.ndarray:  # fmt: skip
    """(N,) equity against a random hand: P(win) + P(tie) / 2 over ``samples`` draws of the
    opponent's hole cards and the board still to come (seeded: the same cards, the same
    numbers). ``cards``: (N, 7) hole cards then the board shown, -1 beyond. ``progress``: a
    bar over the states (about 3,000 a second: a 30,000-hand table takes 40 s).

    >>> from pokerirl.holdem import parse_card
    >>> aces = [parse_card(c) for c in "As Ah".split()] + [-1] * 5
    >>> float(equity(np.array([aces]))[0]) > 0.8
    True
    """
    cards = np.asarray(cards, dtype=np.int64)
    rng = np.random.default_rng(seed)
    found = np.empty(len(cards))
    bar = tqdm(total=len(cards), desc="reward card: equity", unit=" states", disable=not progress)
    for first in range(0, len(cards), chunk):
        block = cards[first : first + chunk]
        n = len(block)
        keys = rng.random((n, samples, 52))
        rows = np.repeat(np.arange(n), 7)
        shown = block.reshape(-1) >= 0
        keys[rows[shown], :, block.reshape(-1)[shown]] = 2.0  # known cards are never drawn
        draw = np.argsort(keys, axis=2)[:, :, :7]  # opponent's 2, then board fillers
        board = np.broadcast_to(block[:, None, 2:], (n, samples, 5)).copy()
        missing = board < 0
        fill = np.cumsum(missing, axis=2) - 1
        board = np.where(missing, np.take_along_axis(draw[:, :, 2:], np.maximum(fill, 0), 2), board)
        mine = np.concatenate([np.broadcast_to(block[:, None, :2], (n, samples, 2)), board], 2)
        theirs = np.concatenate([draw[:, :, :2], board], axis=2)
        ours = hand_strength(mine.reshape(-1, 7)).reshape(n, samples)
        other = hand_strength(theirs.reshape(-1, 7)).reshape(n, samples)
        found[first : first + n] = ((ours > other) + 0.5 * (ours == other)).mean(axis=1)
        bar.update(n)
    bar.close()
    return found


def legal_majority(legal_mask: np.ndarray) -> np.ndarray:
    """The legal-majority rule: check if legal, else call."""
    return np.where(np.asarray(legal_mask)[:, CHECK], CHECK, CALL)


@dataclass(frozen=True, kw_only=True)
class CardStates:
    """The decision states a card is drawn on: what was seen, the expert's action if known,
    the street and the equity of each."""

    decisions: ObservedDecisions
    expert: np.ndarray | None  # (N,) action ids
    street: np.ndarray  # (N,) 0..3
    strength: np.ndarray  # (N,) equity against a random hand
    source: str = ""
    weights: np.ndarray | None = None  # (N,) each state's weight (imputed tables)
    imputed: np.ndarray | None = None  # (N,) bool: the hole cards are a posterior draw

    @classmethod
    def from_arrays(
        cls,
        *,
        obs: np.ndarray,
        legal_mask: np.ndarray,
        cards: np.ndarray,
        expert: np.ndarray | None = None,
        source: str = "",
        weights: np.ndarray | None = None,
        imputed: np.ndarray | None = None,
        progress: bool = False,
    ) -> CardStates:
        decisions = ObservedDecisions(
            obs=np.asarray(obs, np.uint8),
            legal_mask=np.asarray(legal_mask, bool),
            cards=np.asarray(cards, np.int8),
        )
        if expert is not None:
            check_legal_actions(np.asarray(expert, np.int64), decisions.legal_mask,
                                source or "the states")  # fmt: skip
        return cls(
            decisions=decisions,
            expert=None if expert is None else np.asarray(expert, np.int64),
            street=street_of(decisions.obs),
            strength=equity(decisions.cards, progress=progress),  # type: ignore[arg-type]
            source=source,
            weights=None if weights is None else np.asarray(weights, np.float64),
            imputed=None if imputed is None else np.asarray(imputed, bool),
        )

    @classmethod
    def from_table(
        cls,
        path: str | os.PathLike[str],
        *,
        groups: set[str] | None = None,
        label: str | None = None,
        progress: bool = False,
    ) -> CardStates:
        """The rows of a decision table (``pokerirl ingest``'s), or of its hands ``groups``;
        ``label`` names the table in ``source`` (default: ``path``); ``progress``: a bar over
        the states' equity, the slow part."""
        from pokerirl.parquet import fixed_width, read_parquet

        table = read_parquet(path, TABLE_COLUMNS, WEIGHT_COLUMNS, what="table")
        hand_ids = table.column("hand_id").to_pylist()
        keep = np.ones(len(hand_ids), bool) if groups is None else np.isin(hand_ids, list(groups))
        if not keep.any():
            raise InputError(f"{path}: none of its rows are in the states asked for")
        index = np.flatnonzero(keep)
        return cls.from_arrays(
            obs=fixed_width(table, "obs", 72, str(path))[index],
            legal_mask=fixed_width(table, "legal_mask", NUM_ACTIONS, str(path))[index],
            cards=table_cards(table, str(path))[index],
            expert=table.column("action_id").to_numpy()[index],
            source=f"{label or path}" + ("" if groups is None else f" ({len(groups)} hands)"),
            progress=progress,
            **{
                name: table.column(column).to_numpy(zero_copy_only=False)[index]
                for name, column in (("weights", "weight"), ("imputed", "imputed"))
                if column in table.column_names
            },
        )


# --------------------------------------------------------------------------- the card


def _shares(actions: np.ndarray, weights: np.ndarray | None = None) -> dict[str, float]:
    if weights is not None:
        found = np.bincount(actions, weights=weights, minlength=NUM_ACTIONS)
        total = found.sum() if found.sum() > 0 else 1.0
        return {name: float(found[a] / total) for a, name in enumerate(ACTIONS)}
    counts = np.bincount(actions, minlength=NUM_ACTIONS)
    total = max(int(counts.sum()), 1)
    return {name: float(counts[a] / total) for a, name in enumerate(ACTIONS)}


@dataclass(frozen=True, kw_only=True)
class RewardCard(Serializable):
    """See the module docstring; the JSON names are the fields'."""

    reward: str
    fingerprint: str
    source: str
    states: int
    mean_f: dict[str, float | None]
    std_f: dict[str, float | None]
    decision_bonus: float
    decision_bonus_sign: int
    argmax_share: dict[str, float]
    argmax_share_by_street: list[dict[str, float]]
    states_by_street: list[int]
    argmax_share_by_strength: list[dict[str, float]]
    states_by_strength: list[int]
    strength_buckets: list[str]
    agree_expert: float | None
    agree_legal_majority: float
    legal_majority_agree_expert: float | None
    prediction: str
    preference_spread: float | None = None  # mean over states of max - min f, legal, no fold
    expert_share: dict[str, float] | None = None  # the expert's own actions, for comparison
    expert_share_by_strength: list[dict[str, float]] | None = None
    # A run's own validation numbers (run_card): f's argmax alignment beside its BC baseline.
    reward_alignment: float | None = None
    bc_alignment: float | None = None
    format: str = CARD_FORMAT
    # Imputed tables only (left out of the JSON otherwise): the states' total weight, and
    # per part ("observed", "imputed"): weight, argmax_share, agree_expert, expert_share.
    weighted_states: float | None = field(default=None, metadata=meta(omit=Omit.NONE))
    by_part: dict[str, dict[str, Any]] | None = field(default=None, metadata=meta(omit=Omit.NONE))

    @property
    def below_bc(self) -> bool:
        """Whether the run's reward agrees with the expert less than its BC baseline."""
        reward, bc = self.reward_alignment, self.bc_alignment
        return reward is not None and bc is not None and reward < bc

    def to_text(self) -> str:
        """``reward_card.json``'s text."""
        return json.dumps(self.to_json(), indent=2) + "\n"

    @classmethod
    def from_text(cls, text: str, where: str = "") -> RewardCard:
        data = parse_json(text, where=where or "the text")
        if not isinstance(data, dict) or data.get("format") != CARD_FORMAT:
            raise InputError(f"{where or 'the text'}: not a pokerirl reward card")
        return cls.from_json(data, where)

    def render(self) -> str:
        """A few lines for the terminal."""

        def row(shares: dict[str, float]) -> str:
            return "  ".join(f"{name} {shares[name]:5.1%}" for name in ACTIONS)

        def value(v: float | None) -> str:
            return "   n/a" if v is None else f"{v:+6.2f}"

        lines = [
            f"reward card: {self.reward} on {self.states:,} states ({self.source})",
            "  mean f (legal): " + "  ".join(f"{a} {value(self.mean_f[a])}" for a in ACTIONS),
            f"  per-decision bonus {self.decision_bonus:+.3f}",
            "  argmax over legal actions: " + row(self.argmax_share),
        ]
        for name, shares, count in zip(STREETS, self.argmax_share_by_street,
                                       self.states_by_street, strict=True):  # fmt: skip
            lines.append(f"    {name:<8} ({count:>6,}): {row(shares)}")
        for name, shares, count in zip(self.strength_buckets, self.argmax_share_by_strength,
                                       self.states_by_strength, strict=True):  # fmt: skip
            lines.append(f"    eq {name:<6} ({count:>6,}): {row(shares)}")
        if self.expert_share is not None:
            lines.append("  the expert's own actions:   " + row(self.expert_share))
        expert = "n/a" if self.agree_expert is None else f"{self.agree_expert:.1%}"
        rule = self.legal_majority_agree_expert
        lines.append(
            f"  argmax = expert {expert}, = legal majority {self.agree_legal_majority:.1%}"
            + ("" if rule is None else f" (legal majority = expert {rule:.1%})")
        )
        for part, numbers in (self.by_part or {}).items():
            agree = numbers.get("agree_expert")
            lines.append(
                f"  {part} rows (weight {numbers['weight']:,.0f}): argmax "
                f"{row(numbers['argmax_share'])}"
                + ("" if agree is None else f"; = expert {agree:.1%}")
            )
        lines.append(f"  prediction: {self.prediction}")
        if self.below_bc:
            lines.append(
                f"  warning: on its validation hands the run's reward argmax agrees with the "
                f"expert {self.reward_alignment:.1%}, below its behaviour cloning's "
                f"{self.bc_alignment:.1%}"
            )
        return "\n".join(lines)


def predict(
    bonus: float,
    shares: dict[str, float],
    agree_legal_majority: float,
    fold_f: float | None = None,
    spread: float = float("inf"),
) -> str:
    """What a DQN on this reward is expected to learn, in one line (a heuristic: the sign of
    the per-decision bonus, then the argmax's dominant style, or raise-heavy when a positive
    bonus outweighs the state's preferences (``spread``: how far apart f puts the actions),
    since raising prolongs the hand; then whether folding costs).

    >>> predict(0.8, {"call": 0.2, "raise": 0.68, "fold": 0.0, "check": 0.12}, 0.3, -8.5)
    'pays +0.80 per decision: expect long, raise-heavy hands; folding costs 8.50'
    >>> predict(12.0, {"call": 0.2, "raise": 0.04, "fold": 0.0, "check": 0.76}, 0.96, None, 2.0)
    'pays +12.00 per decision: expect long, raise-heavy (bonus over preferences) hands'
    """
    if bonus > max(spread, BONUS_TOLERANCE):
        style = "raise-heavy (bonus over preferences)"
    elif shares["raise"] >= 0.5:
        style = "raise-heavy"
    elif agree_legal_majority >= 0.8:
        style = "calling-station (check if legal, else call)"
    elif shares["fold"] >= 0.3:
        style = "fold-heavy"
    else:
        style = f"mixed (mostly {max(shares, key=shares.__getitem__)})"
    if bonus > BONUS_TOLERANCE:
        line = f"pays {bonus:+.2f} per decision: expect long, {style} hands"
    elif bonus < -BONUS_TOLERANCE:
        line = f"costs {-bonus:.2f} per decision: expect short hands, {style} play"
    else:
        line = f"about 0 per decision ({bonus:+.2f}): expect {style} play"
    if fold_f is not None and fold_f < min(bonus, 0.0) - 1.0:
        line += f"; folding costs {-fold_f:.2f}"
    return line


def reward_card(reward: PokerReward, states: CardStates) -> RewardCard:
    """The card of ``reward`` over ``states`` (the argmax is over each state's legal actions)."""
    legal = states.decisions.legal_mask
    values = reward.action_values(states.decisions).astype(np.float64)
    best = np.where(legal, values, -np.inf).argmax(axis=1)
    if states.weights is not None or states.imputed is not None:
        return _weighted_card(reward, states, values, best)
    going_on = legal.copy()
    going_on[:, FOLD] = False  # every state has a legal call or check
    bonus = float((np.where(going_on, values, 0.0).sum(axis=1) / going_on.sum(axis=1)).mean())
    spread = float(
        (
            np.where(going_on, values, -np.inf).max(1) - np.where(going_on, values, np.inf).min(1)
        ).mean()
    )
    mean_f: dict[str, float | None] = {}
    std_f: dict[str, float | None] = {}
    for action, name in enumerate(ACTIONS):
        seen = values[legal[:, action], action]
        mean_f[name] = float(seen.mean()) if seen.size else None
        std_f[name] = float(seen.std()) if seen.size else None
    bucket = np.searchsorted(np.array(STRENGTH_EDGES), states.strength, side="right")
    rule = legal_majority(legal)
    agree_rule = float((best == rule).mean())
    shares = _shares(best)
    return RewardCard(
        reward=reward.name,
        fingerprint=reward.fingerprint,
        source=states.source,
        states=len(best),
        mean_f=mean_f,
        std_f=std_f,
        decision_bonus=bonus,
        decision_bonus_sign=int(np.sign(bonus)),
        argmax_share=shares,
        argmax_share_by_street=[_shares(best[states.street == s]) for s in range(4)],
        states_by_street=[int((states.street == s).sum()) for s in range(4)],
        argmax_share_by_strength=[_shares(best[bucket == b]) for b in range(len(STRENGTH_LABELS))],
        states_by_strength=[int((bucket == b).sum()) for b in range(len(STRENGTH_LABELS))],
        strength_buckets=list(STRENGTH_LABELS),
        agree_expert=None if states.expert is None else float((best == states.expert).mean()),
        agree_legal_majority=agree_rule,
        legal_majority_agree_expert=(
            None if states.expert is None else float((rule == states.expert).mean())
        ),
        prediction=predict(bonus, shares, agree_rule, mean_f["fold"], spread),
        preference_spread=spread,
        expert_share=None if states.expert is None else _shares(states.expert),
        expert_share_by_strength=(
            None
            if states.expert is None
            else [_shares(states.expert[bucket == b]) for b in range(len(STRENGTH_LABELS))]
        ),
    )


def _weighted_card(
    reward: PokerReward, states: CardStates, values: np.ndarray, best: np.ndarray
) -> RewardCard:
    """:func:`reward_card` with each state weighed, and the observed and imputed states apart."""
    n = len(best)
    w = np.ones(n) if states.weights is None else np.asarray(states.weights, np.float64)
    imputed = np.zeros(n, bool) if states.imputed is None else np.asarray(states.imputed, bool)
    legal = states.decisions.legal_mask
    expert = states.expert

    def mean(x: np.ndarray, rows: np.ndarray | slice = slice(None)) -> float:
        return float(np.average(x[rows], weights=w[rows])) if w[rows].sum() > 0 else 0.0

    going_on = legal.copy()
    going_on[:, FOLD] = False
    bonus = mean(np.where(going_on, values, 0.0).sum(axis=1) / going_on.sum(axis=1))
    spread = mean(np.where(going_on, values, -np.inf).max(1)
                  - np.where(going_on, values, np.inf).min(1))  # fmt: skip
    mean_f: dict[str, float | None] = {}
    std_f: dict[str, float | None] = {}
    for action, name in enumerate(ACTIONS):
        rows = legal[:, action]
        if rows.any() and w[rows].sum() > 0:
            mu = mean(values[:, action], rows)
            mean_f[name] = mu
            std_f[name] = float(np.sqrt(mean((values[:, action] - mu) ** 2, rows)))
        else:
            mean_f[name] = std_f[name] = None
    bucket = np.searchsorted(np.array(STRENGTH_EDGES), states.strength, side="right")
    rule = legal_majority(legal)
    agree_rule = mean((best == rule).astype(float))
    shares = _shares(best, w)
    buckets = range(len(STRENGTH_LABELS))
    by_part: dict[str, dict[str, Any]] = {}
    for part, rows in (("observed", ~imputed), ("imputed", imputed)):
        if rows.any():
            by_part[part] = {
                "states": int(rows.sum()),
                "weight": float(w[rows].sum()),
                "argmax_share": _shares(best[rows], w[rows]),
                "agree_expert": None if expert is None else mean((best == expert) * 1.0, rows),
                "agree_legal_majority": mean((best == rule) * 1.0, rows),
                "expert_share": None if expert is None else _shares(expert[rows], w[rows]),
            }
    return RewardCard(
        reward=reward.name,
        fingerprint=reward.fingerprint,
        source=states.source,
        states=n,
        mean_f=mean_f,
        std_f=std_f,
        decision_bonus=bonus,
        decision_bonus_sign=int(np.sign(bonus)),
        argmax_share=shares,
        argmax_share_by_street=[
            _shares(best[states.street == s], w[states.street == s]) for s in range(4)
        ],
        states_by_street=[int((states.street == s).sum()) for s in range(4)],
        argmax_share_by_strength=[_shares(best[bucket == b], w[bucket == b]) for b in buckets],
        states_by_strength=[int((bucket == b).sum()) for b in buckets],
        strength_buckets=list(STRENGTH_LABELS),
        agree_expert=None if expert is None else mean((best == expert) * 1.0),
        agree_legal_majority=agree_rule,
        legal_majority_agree_expert=None if expert is None else mean((rule == expert) * 1.0),
        prediction=predict(bonus, shares, agree_rule, mean_f["fold"], spread),
        preference_spread=spread,
        expert_share=None if expert is None else _shares(expert, w),
        expert_share_by_strength=(
            None
            if expert is None
            else [_shares(expert[bucket == b], w[bucket == b]) for b in buckets]
        ),
        weighted_states=float(w.sum()),
        by_part=by_part,
    )


# --------------------------------------------------------------------------- files


def card_figure(card: RewardCard) -> bytes:
    """PNG: f per action (mean ± std over legal states), and the argmax shares by street and
    by strength bucket as stacked bars."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12, 3.8), dpi=100)
    FigureCanvasAgg(figure)
    left, middle, right = figure.subplots(1, 3)
    means = [np.nan if card.mean_f[a] is None else card.mean_f[a] for a in ACTIONS]
    stds = [0.0 if card.std_f[a] is None else card.std_f[a] for a in ACTIONS]
    left.bar(ACTIONS, means, yerr=stds, color=[f"C{i}" for i in range(4)], capsize=3)
    left.axhline(card.decision_bonus, color="black", linestyle="--", linewidth=1,
                 label=f"per-decision bonus {card.decision_bonus:+.2f}")  # fmt: skip
    left.set(title="f by action (legal states)", ylabel="f(s, a)")
    left.legend(fontsize=8)
    for axes, groups, labels, title in (
        (middle, card.argmax_share_by_street, STREETS, "argmax over legal actions, by street"),
        (right, card.argmax_share_by_strength, card.strength_buckets, "... by equity"),
    ):
        bottom = np.zeros(len(groups))
        for i, name in enumerate(ACTIONS):
            heights = np.array([g[name] for g in groups])
            axes.bar(labels, heights, bottom=bottom, color=f"C{i}", label=name)
            bottom += heights
        axes.set(title=title, ylim=(0, 1), ylabel="share of states")
    middle.legend(fontsize=8, loc="lower right")
    figure.suptitle(f"{card.reward}: {card.prediction}", fontsize=9)
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def card_files(card: RewardCard) -> dict[str, bytes]:
    """``reward_card.json`` and ``reward_card.png``."""
    return {CARD_FILE: card.to_text().encode(), CARD_FIGURE: card_figure(card)}


def write_card(card: RewardCard, out: str | os.PathLike[str]) -> Path:
    """Write the card's two files into the folder ``out`` (atomically each); return it."""
    from pokerirl.atomic import write_bytes

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for name, data in card_files(card).items():
        write_bytes(out / name, data)
    return out


def read_card(folder: str | os.PathLike[str]) -> RewardCard | None:
    """The card in ``folder``, or None when it has none (or an unreadable one)."""
    try:
        path = Path(folder) / CARD_FILE
        return RewardCard.from_text(read_bytes(path).decode("utf-8"), str(path))
    except (OSError, ValueError, TypeError):
        return None


def run_card(
    run_dir: str | os.PathLike[str], table: str | os.PathLike[str], *, label: str | None = None
) -> RewardCard:
    """The card of a run folder's reward over its validation hands (``split.json``) of
    ``table``, the decision table it was trained on; ``label`` names the table in the card
    (default: ``table``'s path; a worker's scratch copy passes the real table's path)."""
    from pokerirl.irl.run import CONFIG_FILE, read_split
    from pokerirl.poker.reward_sources import load_reward_source

    groups = read_split(run_dir)
    states = CardStates.from_table(table, groups=groups, label=label)
    record = read_json(Path(run_dir) / CONFIG_FILE)
    reward = load_reward_source(run_dir)
    reward.name = f"{record['algo']} reward (seed {record['hyperparameters']['seed']})"
    return with_run_alignments(reward_card(reward, states), record)


def with_run_alignments(card: RewardCard, record: Mapping[str, Any]) -> RewardCard:
    """``card`` with its run's own validation numbers (a run's ``config.json``): f's argmax
    alignment and the BC baseline's, so that a reward below BC is flagged."""
    result = record.get("result") or {}
    final = result.get("final_metrics") or {}
    return dataclasses.replace(
        card,
        reward_alignment=Metric.VAL_REWARD_ALIGNMENT.of(final, None),
        bc_alignment=(result.get("baselines") or {}).get("bc"),
    )


def card_summary(cards: list[RewardCard]) -> dict[str, object]:
    """Mean and std over runs of a card's numbers, for the study report."""

    def stat(values: list[float]) -> dict[str, float]:
        array = np.asarray(values, dtype=float)
        std = float(array.std(ddof=1)) if array.size > 1 else 0.0
        return {"mean": float(array.mean()), "std": std}

    return {
        "runs": len(cards),
        "mean_f": {a: stat([f for c in cards if (f := c.mean_f[a]) is not None]) for a in ACTIONS},
        "decision_bonus": stat([c.decision_bonus for c in cards]),
        "argmax_share": {a: stat([c.argmax_share[a] for c in cards]) for a in ACTIONS},
        "agree_expert": stat([c.agree_expert or 0.0 for c in cards]),
        "agree_legal_majority": stat([c.agree_legal_majority for c in cards]),
        "legal_majority_agree_expert": stat([c.legal_majority_agree_expert or 0.0 for c in cards]),
        "expert_share": {
            a: stat([c.expert_share[a] for c in cards if c.expert_share]) for a in ACTIONS
        }
        if all(c.expert_share for c in cards)
        else None,
        "predictions": [c.prediction for c in cards],
        **(
            {"below_bc": sum(c.below_bc for c in cards)}
            if any(c.bc_alignment is not None for c in cards)
            else {}
        ),
    }


__all__ = [
    "CARD_FIGURE",
    "CARD_FILE",
    "CardStates",
    "RewardCard",
    "card_files",
    "card_summary",
    "equity",
    "read_card",
    "reward_card",
    "run_card",
    "write_card",
]
