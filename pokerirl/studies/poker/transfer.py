"""The transfer test (``pokerirl transfer``): does a learned reward teach the expert's play?

For one reward (an IRL run folder or ``authors:FILE``), DQNs are trained on each reward
transform (``raw`` f, ``centered``, ``log_softmax``, ``advantage``;
:mod:`pokerirl.poker.rewards`) and each
payoff weight, and a sparse DQN on the same seeds and hands, all on the reward run's encoding
(or ``encoding``). Beside them, two agents that need no RL: f's argmax (``reward:RUN``) and the
IRL policy π played greedily (``policy:RUN``): if f's argmax plays like the expert and the DQNs
do not, the RL failed, not the reward. Each agent then plays ``eval_hands`` duplicate hands
against random and against each expert bot, which gives:

* its result against random and head to head against each expert bot (mbb/h; mean and SE
  over seeds): against random alone rewards calling stations;
* the share of its decisions where it takes the action of each expert rule (the synthetic
  months' ``tightbot`` and ``loosebot`` without their noise), on the states it visits, and
  of the legal-majority rule (check if legal, else call: a calling station's);
* its action shares (call, raise, fold, check).

Beside them: each expert bot's own result against random (with its noise), always-call's
and the sparse DQN's. ``best`` is the transform (and weight) whose agents agree most with the
expert rules (ties, or no expert rule: the better result against random); on synthetic data
the truth is known.

Agents are units of :func:`pokerirl.agents.train.train_seeds` under ``<out>/agents/``: a rerun
reuses them; the evaluations are recomputed (they are cheap and deterministic).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import write_text
from pokerirl.errors import ConfigError
from pokerirl.execution import Backend
from pokerirl.holdem import ACTIONS
from pokerirl.serial import Serializable, meta
from pokerirl.studies.common import markdown_table
from pokerirl.studies.poker.config import AGENT_PRESETS

TRANSFER_FILE, TRANSFER_MARKDOWN = "transfer.json", "transfer.md"
EVAL_SEED = 4_242_424
EXPERTS = ("tightbot", "loosebot")
RULES = (*EXPERTS, "legal_majority")  # what an agent's actions are compared with


@dataclass(frozen=True, kw_only=True)
class TransferConfig:
    """What to train and how to judge it."""

    transforms: tuple[str, ...] = ("raw", "centered", "log_softmax", "advantage")
    payoff_weights: tuple[float, ...] = (0.0,)
    seeds: tuple[int, ...] = (0, 1, 2)
    hands: int = 50_000  # DQN training hands
    agent_preset: str = "default"
    eval_hands: int = 20_000
    experts: tuple[str, ...] = RULES
    encoding: str | None = None  # the DQNs' encoding; None: the reward run's own

    def __post_init__(self) -> None:
        from pokerirl.poker.rewards import TRANSFORMS

        if not self.transforms or any(t not in TRANSFORMS for t in self.transforms):
            raise ConfigError(f"transforms must be some of {', '.join(TRANSFORMS)}")
        if not self.payoff_weights or any(not 0 <= w <= 1 for w in self.payoff_weights):
            raise ConfigError("payoff weights must lie in [0, 1]")
        if not self.seeds or self.hands < 1 or self.eval_hands < 2 or self.eval_hands % 2:
            raise ConfigError("need seeds, hands >= 1 and an even eval_hands >= 2")
        if len(set(self.seeds)) != len(self.seeds):
            repeated = next(s for s in self.seeds if self.seeds.count(s) > 1)
            raise ConfigError(f"seed {repeated} is given twice: every DQN seed once")
        unknown = [e for e in self.experts if e not in RULES]
        if unknown:
            raise ConfigError(f"unknown rule {unknown[0]!r} ({', '.join(RULES)})")
        if self.agent_preset not in AGENT_PRESETS:
            raise ConfigError(
                f"unknown agent preset {self.agent_preset!r}; choose {', '.join(AGENT_PRESETS)}"
            )
        if self.encoding is not None:
            from pokerirl.game.encodings import get_encoding

            get_encoding(self.encoding)


@dataclass(frozen=True, kw_only=True)
class TransferRow(Serializable):
    """One agent kind over its seeds (or one fixed agent: a single 'seed')."""

    label: str
    transform: str | None  # None: not a learned-reward DQN
    payoff_weight: float | None
    vs_random: list[float]  # mbb/h per seed
    agreement: dict[str, list[float]]  # expert rule -> share per seed
    action_shares: list[dict[str, float]]  # per seed
    vs_experts: dict[str, list[float]] = field(default_factory=dict)  # bot -> mbb/h per seed
    kind: str = "dqn"  # dqn, argmax (f's), policy (π greedy), or fixed (a bot, a rule)
    # Learned-reward DQNs: the share of their decisions against random that take f's best
    # legal action, per seed (how closely the DQN follows its reward); empty for the others.
    follows_reward: list[float] = field(default_factory=list)

    @property
    def mean_vs_random(self) -> float:
        return float(np.mean(self.vs_random))

    @property
    def se_vs_random(self) -> float:
        values = np.asarray(self.vs_random)
        return float(values.std(ddof=1) / math.sqrt(values.size)) if values.size > 1 else 0.0

    def mean_agreement(self, expert: str | None = None) -> float:
        """Mean agreement with ``expert``'s rule, or with every expert bot's (not the
        legal-majority rule's); 0 without any."""
        experts = [expert] if expert else [e for e in self.agreement if e in EXPERTS]
        return float(np.mean([np.mean(self.agreement[e]) for e in experts])) if experts else 0.0

    def mean_share(self, action: str) -> float:
        return float(np.mean([shares[action] for shares in self.action_shares]))

    def mean_vs(self, expert: str) -> float:
        return float(np.mean(self.vs_experts[expert]))

    def se_vs(self, expert: str) -> float:
        values = np.asarray(self.vs_experts[expert])
        return float(values.std(ddof=1) / math.sqrt(values.size)) if values.size > 1 else 0.0

    def to_json(self) -> dict[str, Any]:  # with the means and SEs, for the file's reader
        return {
            **super().to_json(),
            "mean_vs_random": self.mean_vs_random,
            "se_vs_random": self.se_vs_random,
            "mean_vs_experts": {e: self.mean_vs(e) for e in self.vs_experts},
            "se_vs_experts": {e: self.se_vs(e) for e in self.vs_experts},
            "mean_agreement": {e: self.mean_agreement(e) for e in self.agreement},
            "mean_action_shares": {a: self.mean_share(a) for a in ACTIONS},
            "mean_follows_reward": (
                float(np.mean(self.follows_reward)) if self.follows_reward else None
            ),
        }


@dataclass(frozen=True, kw_only=True)
class TransferResult(Serializable):
    FORMAT = "pokerirl-transfer/2"

    reward: str
    config: TransferConfig
    eval_seed: int = EVAL_SEED
    encoding: str = "rlcard"  # the DQNs'
    rows: tuple[TransferRow, ...]
    best: str
    notes: list[str] = field(default_factory=list, metadata=meta(skip=True))  # transfer.md's

    def to_text(self) -> str:
        """``transfer.json``'s text."""
        return json.dumps(self.to_json(), indent=2) + "\n"

    def markdown(self) -> str:
        experts = list(self.config.experts)
        bots = [e for e in experts if e in EXPERTS]
        head = ["agent", "vs random (mbb/h)", *[f"vs {b} (mbb/h)" for b in bots],
                *[f"= {e} rule" for e in experts], *[f"{a} share" for a in ACTIONS],
                "follows f"]  # fmt: skip
        lines = [
            f"# Transfer test: {self.reward}",
            "",
            f"{len(self.config.seeds)} seeds x {self.config.hands:,} training hands "
            f"({self.config.agent_preset} DQN preset, {self.encoding} encoding); each agent "
            f"then plays {self.config.eval_hands:,} duplicate hands against random and against "
            f"each expert bot (seed {self.eval_seed}); its actions against random are compared "
            "with the expert rules (noiseless). ± is the SE over seeds. `f argmax` and "
            "`π greedy` need no RL: they are the reward's and the IRL policy's own play.",
            "",
        ]

        def result(mean: float, se: float) -> str:
            return f"{mean:+,.0f} ± {se:,.0f}"

        lines += markdown_table(
            head,
            (
                [row.label, result(row.mean_vs_random, row.se_vs_random),
                 *[result(row.mean_vs(b), row.se_vs(b)) if b in row.vs_experts else "-"
                   for b in bots],
                 *[f"{row.mean_agreement(e):.1%}" for e in experts],
                 *[f"{row.mean_share(a):.1%}" for a in ACTIONS],
                 f"{np.mean(row.follows_reward):.1%}" if row.follows_reward else "-"]
                for row in self.rows
            ),
        )  # fmt: skip
        lines += [
            "",
            f"Best transform (most agreement with the expert rules): **{self.best}**.",
            "",
        ]
        return "\n".join(lines)


def _label(transform: str, weight: float) -> str:
    return transform if weight == 0 else f"{transform}, payoff weight {weight:g}"


def _folder(transform: str, weight: float) -> str:
    return transform if weight == 0 else f"{transform}-w{weight:g}"


def _rule(name: str, seen: Any) -> np.ndarray:
    """The actions of rule ``name`` on logged decisions."""
    from pokerirl.game import make_agent
    from pokerirl.poker.reward_card import legal_majority

    if name == "legal_majority":
        return legal_majority(seen.legal_mask)
    return make_agent(name).rule(seen.obs, seen.legal_mask, seen.cards)  # type: ignore[attr-defined]


@dataclass(frozen=True, kw_only=True)
class _Judged:
    vs_random: float
    agreement: dict[str, float]
    shares: dict[str, float]
    vs_experts: dict[str, float]
    follows_reward: float | None


def _judge(agent: Any, config: TransferConfig, reward: Any = None) -> _Judged:
    """An agent against random (mbb/h, agreement with each expert rule, action shares, and
    given its ``reward``, how often it takes f's best action) and head to head against each
    expert bot (mbb/h), all on the same duplicate deals."""
    from pokerirl.agents.train import followed
    from pokerirl.game import DecisionLog, make_agent, play_match

    log: list[DecisionLog] = []
    result = play_match(agent, make_agent("random"), hands=config.eval_hands, seed=EVAL_SEED,
                        log=log)  # fmt: skip
    seen = DecisionLog.concatenate(log)
    agreement = {rule: float((_rule(rule, seen) == seen.actions).mean()) for rule in config.experts}
    counts = np.bincount(seen.actions, minlength=len(ACTIONS)) / max(len(seen.actions), 1)
    vs_experts = {}
    for bot in (e for e in config.experts if e in EXPERTS):
        match = play_match(agent, make_agent(bot), hands=config.eval_hands, seed=EVAL_SEED)
        vs_experts[bot] = match.mbb_per_hand
    return _Judged(vs_random=result.mbb_per_hand, agreement=agreement,
                   shares={a: float(counts[i]) for i, a in enumerate(ACTIONS)},
                   vs_experts=vs_experts,
                   follows_reward=None if reward is None else followed(reward, log))  # fmt: skip


def _row(label: str, agents: list[Any], config: TransferConfig, transform: str | None = None,
         weight: float | None = None, kind: str = "dqn",
         reward: Any = None) -> TransferRow:  # fmt: skip
    judged = [_judge(agent, config, reward) for agent in agents]
    return TransferRow(
        label=label,
        transform=transform,
        payoff_weight=weight,
        vs_random=[j.vs_random for j in judged],
        agreement={e: [j.agreement[e] for j in judged] for e in config.experts},
        action_shares=[j.shares for j in judged],
        vs_experts={b: [j.vs_experts[b] for j in judged] for b in judged[0].vs_experts},
        kind=kind,
        follows_reward=[j.follows_reward for j in judged if j.follows_reward is not None],
    )


def run_transfer(
    reward_run: str | os.PathLike[str],
    out: str | os.PathLike[str],
    config: TransferConfig = TransferConfig(),
    *,
    backend: Backend | None = None,
    progress: bool = False,
    say: Callable[[str], None] = lambda message: None,
) -> TransferResult:
    """Train and judge the agents of the transfer test into ``out``; write
    ``transfer.json`` and ``transfer.md`` there."""
    from pokerirl.agents import resolve_agent
    from pokerirl.agents.train import agent_preset, train_seeds
    from pokerirl.poker.agent_specs import POLICY_PREFIX, REWARD_PREFIX
    from pokerirl.poker.reward_sources import RewardSource

    source = RewardSource.resolve(reward_run)  # one line for a bad reward, before anything runs
    reward = source.load()  # f's best action is each transform's: they shift f per state
    encoding = config.encoding or source.encoding or "rlcard"
    out = Path(out)
    base = agent_preset(config.agent_preset, hands=config.hands, seed=config.seeds[0],
                        eval_every=config.hands, eval_hands=2_000,
                        encoding=encoding)  # fmt: skip

    def agents_of(folder: Path) -> list[Any]:
        return [resolve_agent(str(folder / f"seed-{s}")) for s in config.seeds]

    def train(folder: Path, train_config: Any) -> None:
        train_seeds(folder, train_config, list(config.seeds), backend=backend, progress=progress)

    rows: list[TransferRow] = []
    say(f"transfer: f's argmax and the IRL policy (no RL), {config.eval_hands:,} hands each")
    rows.append(_row("f argmax", [resolve_agent(f"{REWARD_PREFIX}{reward_run}")], config,
                     kind="argmax"))  # fmt: skip
    if not source.is_authors:  # an authors' file holds a reward only
        rows.append(_row("π greedy", [resolve_agent(f"{POLICY_PREFIX}{reward_run}")], config,
                         kind="policy"))  # fmt: skip
    for transform in config.transforms:
        for weight in config.payoff_weights:
            folder = out / "agents" / _folder(transform, weight)
            say(f"transfer: {_label(transform, weight)}: {len(config.seeds)} seeds -> {folder}")
            learned = dataclasses.replace(
                base, reward="learned", reward_run=str(reward_run), reward_transform=transform,
                payoff_weight=weight,
            )  # fmt: skip
            train(folder, learned)
            rows.append(_row(_label(transform, weight), agents_of(folder), config, transform,
                             weight, reward=reward))  # fmt: skip
    say(f"transfer: sparse DQN: {len(config.seeds)} seeds -> {out / 'agents' / 'sparse'}")
    train(out / "agents" / "sparse", base)
    rows.append(_row("sparse DQN", agents_of(out / "agents" / "sparse"), config))
    bots = [e for e in config.experts if e in EXPERTS]
    for name in (*bots, "call", "raise"):
        rows.append(_row(name if name in bots else f"always-{name}", [resolve_agent(name)],
                         config, kind="fixed"))  # fmt: skip
    learned_rows = [row for row in rows if row.transform is not None]
    best = max(learned_rows, key=lambda row: (round(row.mean_agreement(), 3), row.mean_vs_random))
    result = TransferResult(reward=str(reward_run), config=config, rows=tuple(rows),
                            best=best.label, encoding=encoding)  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / TRANSFER_FILE, result.to_text())
    write_text(out / TRANSFER_MARKDOWN, result.markdown())
    return result


def parse_list(text: str, kind: type = str) -> tuple[Any, ...]:
    """``"a,b"`` as ``("a", "b")`` (``kind`` applied); ``"none"`` or ``""`` as ``()``."""
    parts = [part.strip() for part in text.split(",") if part.strip()]
    if parts in ([], ["none"]):
        return ()
    try:
        return tuple(kind(part) for part in parts)
    except ValueError:
        raise ConfigError(f"{text!r}: not a list of {kind.__name__} values") from None


__all__ = ["TransferConfig", "TransferResult", "TransferRow", "parse_list", "run_transfer"]
