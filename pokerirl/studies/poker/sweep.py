"""The poker sweep (``pokerirl sweep``): under which settings, if any, does a learned reward
help a DQN on real hands? Chosen on the earlier part of a month, shown on the later part.

A sweep varies one axis at a time around a base cell (:class:`Cell`): the encoding, the folds,
which players are the expert (all, or the winners), the IRL algorithm and its reward's weight
decay, the reward the DQN sees (transform and payoff weight), the DQN's training opponent
(random, self-play, or the pool of fixed strategies and its own snapshots) and its budget.
Every cell is judged by more than "beats random" (:class:`CellResult`): the reward's argmax
agreement with the expert on validation hands, BC's beside it; how closely each DQN follows
its reward; its action shares and how often it does what always-call would; its result
against random, call, TightBot and LooseBot; its LBR; and head to head against the sparse DQN
of the same encoding, opponent and budget, on duplicate deals.

**Splits.** The month's hands are cut by time (:class:`pokerirl.datasets.players.Period`):
the sweep reads only the ``choose`` period (the first 60% by default), chooses a cell by a rule
fixed in advance (:func:`choose`), and ``split=test`` runs that cell alone on the ``test``
period (the rest), which nothing in the choice read. Every number in a report says its split.

**Sharing.** One table per (folds, experts), one set of IRL runs per reward setting, one sparse
DQN set per (encoding, opponent, budget); every piece is a unit of :mod:`pokerirl.store` (tables,
IRL runs, agents, evaluations), so a rerun resumes and gives the same bytes. ``out``::

    <split>/tables/<folds>-<experts>.parquet   the period's table (and its summary)
    <split>/irl/<reward setting>/run-<k>        IRL runs
    <split>/agents/<cell or sparse set>/seed-<k> DQNs (learned seed k on IRL run k mod runs)
    <split>/evals/<agent>.json                  each agent's evaluation (a store record)
    <split>/sweep.json, sweep.md, sweep.csv     every cell's figures; the choice (choose split)
    <split>/sweep.png                           LBR against the head-to-head result, per cell
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import os
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import atomic_path, write_text
from pokerirl.errors import ConfigError
from pokerirl.execution import Backend
from pokerirl.jsonio import read_json
from pokerirl.serial import Omit, Serializable, meta
from pokerirl.settings import with_overrides
from pokerirl.store import (
    Fate,
    Layout,
    Unit,
    UnitOutput,
    check,
    digest,
    read_record,
    run_units,
    writing,
)
from pokerirl.studies.common import StudyError, markdown_table
from pokerirl.studies.poker.config import Experts

SWEEP_FORMAT = "pokerirl-poker-sweep/1"
JSON_FILE, MARKDOWN_FILE, CSV_FILE, FIGURE_FILE = "sweep.json", "sweep.md", "sweep.csv", "sweep.png"
EVAL_SEED = 5_151_515  # the deal seed of every evaluation (not a training seed)
LBR_SEED = 6_161_616
LBR_CHECK_UNTIL = "turn"  # as the study's LBR: checks or calls before the turn (exploit.md)
OPPONENTS = ("random", "call", "tightbot", "loosebot")  # what each agent is played against
EVAL_KIND = "pokerirl-sweep-eval"
Say = Callable[[str], None]


class Split(StrEnum):
    """Which part of the month a run reads: the earlier (choose) or the later (test)."""

    CHOOSE = "choose"
    TEST = "test"


class Axis(StrEnum):
    """The axes a sweep varies, one at a time: the fields of :class:`Cell`."""

    ENCODING = "encoding"
    FOLDS = "folds"
    EXPERTS = "experts"
    ALGO = "algo"
    REWARD_DECAY = "reward_decay"
    TRANSFORM = "transform"
    PAYOFF_WEIGHT = "payoff_weight"
    OPPONENT = "opponent"
    HANDS = "hands"


@dataclass(frozen=True, kw_only=True)
class Cell(Serializable):
    """One setting of every axis: how the expert table is made, the reward learned from it
    and the DQN trained on it."""

    encoding: str = "strength"
    folds: str = "drop"
    experts: Experts = Experts.ALL
    algo: str = "hairl"
    reward_decay: float = 0.0  # the reward net's weight decay (its regularization)
    transform: str = "advantage"
    payoff_weight: float = 0.0
    opponent: str = "pool"
    hands: int = 20_000  # the DQN's training hands

    def __post_init__(self) -> None:
        from pokerirl.agents.config import Opponent
        from pokerirl.game.encodings import EncodingName
        from pokerirl.irl.config import Algo
        from pokerirl.poker.folds import FoldsMode
        from pokerirl.poker.rewards import Transform

        object.__setattr__(self, "experts", Experts(self.experts))
        allowed: dict[str, tuple[str, ...]] = {
            "encoding": tuple(EncodingName), "folds": tuple(FoldsMode), "algo": tuple(Algo),
            "transform": tuple(Transform), "opponent": ("random", *Opponent),
        }  # fmt: skip
        for name, values in allowed.items():
            if getattr(self, name) not in values:
                raise ConfigError(f"{name} must be one of {', '.join(values)}, "
                                  f"got {getattr(self, name)!r}")  # fmt: skip
        if not 0 <= self.payoff_weight <= 1 or self.reward_decay < 0 or self.hands < 1:
            raise ConfigError("payoff_weight in [0, 1], reward_decay >= 0 and hands >= 1")

    @property
    def table_key(self) -> str:
        return f"{self.folds}-{self.experts}"

    @property
    def reward_key(self) -> str:
        """The IRL runs this cell's reward comes from (cells that share them share the key)."""
        return f"{self.table_key}-{self.encoding}-{self.algo}-decay{self.reward_decay:g}"

    @property
    def sparse_key(self) -> str:
        """The sparse DQN set this cell is compared with."""
        return f"sparse-{self.encoding}-{self.opponent}-{_hands(self.hands)}"

    @property
    def name(self) -> str:
        return (f"{self.reward_key}-{self.transform}-w{self.payoff_weight:g}-{self.opponent}-"
                f"{_hands(self.hands)}")  # fmt: skip


def _hands(hands: int) -> str:
    return f"{hands // 1000}k" if hands % 1000 == 0 else str(hands)


@dataclass(frozen=True, kw_only=True)
class SweepConfig(Serializable):
    """A sweep: the base cell, the values each axis takes (one axis at a time), and the sizes.

    ``seeds`` are the DQN seeds of every agent set (learned seed k reads IRL run k mod
    ``runs``); ``eval_hands`` duplicate hands against each opponent and head to head;
    ``lbr_hands`` LBR hands per agent; the periods are fractions of the month by time.
    """

    preset: str
    base: Cell = field(default_factory=Cell)
    axes: Mapping[str, tuple[Any, ...]] = field(default_factory=dict)
    runs: int = 2
    seeds: tuple[int, ...] = (0, 1)
    irl_epochs: int = 20
    eval_hands: int = 10_000
    lbr_hands: int = 1_000
    choose_period: tuple[float, float] = (0.0, 0.6)
    test_period: tuple[float, float] = (0.6, 1.0)
    winners_bb_per_100: float = 0.0
    winners_min_hands: int = 200
    jobs: int = field(default=2, metadata=meta(skip=True))  # does not change a result

    def __post_init__(self) -> None:
        unknown = [name for name in self.axes if name not in tuple(Axis)]
        if unknown:
            raise ConfigError(f"unknown sweep axis {unknown[0]!r} ({', '.join(Axis)})")
        checks = {
            "runs >= 1": self.runs >= 1,
            "at least one seed, each >= 0 and once": bool(self.seeds)
            and min(self.seeds) >= 0 and len(set(self.seeds)) == len(self.seeds),
            "irl_epochs >= 1": self.irl_epochs >= 1,
            "eval_hands even and >= 2": self.eval_hands >= 2 and self.eval_hands % 2 == 0,
            "lbr_hands even and >= 2": self.lbr_hands >= 2 and self.lbr_hands % 2 == 0,
            "the choose and test periods apart": self.choose_period[1] <= self.test_period[0]
            or self.test_period[1] <= self.choose_period[0],
            "winners_min_hands >= 1": self.winners_min_hands >= 1,
            "jobs >= 1": self.jobs >= 1,
        }
        broken = [name for name, ok in checks.items() if not ok]
        if broken:
            raise ConfigError(f"bad sweep settings: {', '.join(broken)}")
        self.cells()  # every cell's values checked here, before anything runs

    def cells(self) -> list[Cell]:
        """The base, then each axis's other values in the order given (no cell twice)."""
        found = [self.base]
        for axis, values in self.axes.items():
            for value in values:
                cell = dataclasses.replace(self.base, **{axis: value})
                if cell not in found:
                    found.append(cell)
        return found

    def axis_of(self, cell: Cell) -> str:
        """The axis ``cell`` varies from the base (``base`` for the base)."""
        changed = [f.name for f in dataclasses.fields(Cell)
                   if getattr(cell, f.name) != getattr(self.base, f.name)]  # fmt: skip
        return changed[0] if changed else "base"


# The base: what issue 31 recommends (strength encoding, the advantage transform) with the
# pool opponent. `sample` fits the April 1995 sample into a session on 2 cores.
PRESETS: dict[str, SweepConfig] = {
    "sample": SweepConfig(
        preset="sample",
        axes={
            "encoding": ("rlcard",),
            "folds": ("impute",),
            "experts": (Experts.WINNERS,),
            "algo": ("airl", "gail"),
            "reward_decay": (5e-3,),
            "transform": ("raw", "centered"),
            "payoff_weight": (0.5, 0.9),
            "opponent": ("random", "self"),
            "hands": (150_000,),
        },
        lbr_hands=500,  # as the quick study's: LBR dominates the evaluation's time
    ),
    # Seconds: every stage at sizes whose numbers mean nothing (tests, a first look).
    "smoke": SweepConfig(
        preset="smoke",
        base=Cell(hands=400),
        axes={"transform": ("raw",), "opponent": ("random",)},
        runs=1,
        seeds=(0,),
        irl_epochs=1,
        eval_hands=100,
        lbr_hands=20,
        winners_min_hands=20,
        jobs=1,
    ),
}


def sweep_preset(name: str, **overrides: Any) -> SweepConfig:
    """The preset ``name`` with ``overrides`` (None values ignored)."""
    return with_overrides(PRESETS, name, what="sweep preset",
                          **{k: v for k, v in overrides.items() if v is not None})  # fmt: skip


# --------------------------------------------------------------------------- results


@dataclass(frozen=True, kw_only=True)
class AgentEval(Serializable):
    """One agent's evaluation: mbb/h against each opponent and head to head against its
    sparse DQN (duplicate deals of ``EVAL_SEED``); its decisions against random (action
    shares, agreement with always-call's rule, and its reward's best action: ``follows``);
    its LBR (mbb/h the local best response wins from it, and its SE)."""

    vs: Mapping[str, float]
    shares: Mapping[str, float]
    agrees_with_call: float
    lbr: float
    lbr_se: float
    follows: float | None = field(default=None, metadata=meta(omit=Omit.NONE))
    vs_sparse: float | None = field(default=None, metadata=meta(omit=Omit.NONE))
    vs_sparse_se: float | None = field(default=None, metadata=meta(omit=Omit.NONE))


@dataclass(frozen=True, kw_only=True)
class Targets(Serializable):
    """What the issue asks of a learned-reward DQN, each met or not."""

    differs_from_call: bool  # on at least 25% of its decisions
    follows_reward: bool  # on at least 80%
    lbr_below_call_and_sparse: bool
    not_worse_than_sparse: bool  # head to head, mean >= 0
    reward_at_least_bc: bool  # f's argmax agreement with the expert >= BC's (validation)

    @property
    def met(self) -> int:
        return sum(dataclasses.astuple(self))


@dataclass(frozen=True, kw_only=True)
class CellResult(Serializable):
    """A cell over its seeds (agents) and runs (rewards), with its sparse DQN set's."""

    name: str
    axis: str
    cell: Cell
    agents: tuple[AgentEval, ...]
    sparse: tuple[AgentEval, ...]
    reward_agreement: tuple[float, ...]  # per IRL run: f's argmax vs the expert (validation)
    bc_agreement: tuple[float, ...]  # per IRL run: behaviour cloning's
    targets: Targets

    def mean(self, value: Callable[[AgentEval], float | None], sparse: bool = False) -> float:
        values = [value(a) for a in (self.sparse if sparse else self.agents)]
        return float(np.mean([v for v in values if v is not None])) if values else math.nan

    def se(self, value: Callable[[AgentEval], float | None], sparse: bool = False) -> float:
        found = [value(a) for a in (self.sparse if sparse else self.agents)]
        values = np.array([v for v in found if v is not None], float)
        return float(values.std(ddof=1) / math.sqrt(values.size)) if values.size > 1 else math.nan


@dataclass(frozen=True, kw_only=True)
class SweepResult(Serializable):
    """Every cell of one split, the always-call reference, and (choose split) the choice."""

    FORMAT = SWEEP_FORMAT

    split: Split
    config: SweepConfig
    month: str
    tables: Mapping[str, Mapping[str, Any]]  # table key -> its ingest summary's counts
    call: AgentEval
    cells: tuple[CellResult, ...]
    chosen: str | None = field(default=None, metadata=meta(omit=Omit.NONE))
    rule: str = ""


CHOICE_RULE = (
    "the cell meeting the most of the five targets (differs from always-call on >= 25% of its "
    "decisions, follows its reward on >= 80%, LBR below always-call's and its sparse DQN's, "
    "head to head against its sparse DQN >= 0, reward argmax agreement >= BC's); ties: the "
    "better mean head to head against the sparse DQN, then the lower LBR"
)


def targets_of(agents: Sequence[AgentEval], sparse: Sequence[AgentEval], call: AgentEval,
               reward: Sequence[float], bc: Sequence[float]) -> Targets:  # fmt: skip
    """The five targets of issue 40, on the means over seeds (and runs)."""
    mean = lambda values: float(np.mean(values))  # noqa: E731
    return Targets(
        differs_from_call=mean([1 - a.agrees_with_call for a in agents]) >= 0.25,
        follows_reward=mean([a.follows if a.follows is not None else 0.0 for a in agents])
        >= 0.80,
        lbr_below_call_and_sparse=mean([a.lbr for a in agents])
        < min(call.lbr, mean([s.lbr for s in sparse])),
        not_worse_than_sparse=mean([a.vs_sparse or 0.0 for a in agents]) >= 0.0,
        reward_at_least_bc=mean(reward) >= mean(bc),
    )


def choose(cells: Sequence[CellResult]) -> CellResult:
    """The cell :data:`CHOICE_RULE` picks (the first of equals, in the sweep's order)."""
    def key(cell: CellResult) -> tuple[float, ...]:
        return (cell.targets.met, cell.mean(lambda a: a.vs_sparse), -cell.mean(lambda a: a.lbr))

    return max(cells, key=key)


# --------------------------------------------------------------------------- the run


@dataclass(frozen=True)
class _Sweep:
    """A split's folder, its settings and how it runs units."""

    root: Path
    config: SweepConfig
    month: tuple[str, ...]
    period: tuple[float, float]
    backend: Backend
    overwrite: bool
    progress: bool
    say: Say


def run_sweep(
    month: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    config: SweepConfig,
    *,
    split: Split = Split.CHOOSE,
    backend: Backend | None = None,
    overwrite: bool = False,
    progress: bool = False,
    say: Say = lambda message: None,
) -> SweepResult:
    """Run the sweep's ``split`` into ``out/<split>``; return (and write) its result.

    ``choose``: every cell on the ``choose`` period, and the choice. ``test``: the cell the
    choose split chose (read from ``out/choose/sweep.json``; it must exist) on the ``test``
    period alone.
    """
    out = Path(out)
    cells = config.cells()
    period = config.choose_period
    if split == Split.TEST:
        chosen = _chosen(out)
        cells = [c for c in cells if c.name == chosen]
        if not cells:
            raise StudyError(f"{out / Split.CHOOSE / JSON_FILE}: chose {chosen!r}, which is not "
                             f"a cell of the {config.preset!r} sweep")  # fmt: skip
        period = config.test_period
    sweep = _Sweep(root=out / split, config=config, month=tuple(str(m) for m in month),
                   period=period, backend=backend or Backend(jobs=config.jobs),
                   overwrite=overwrite, progress=progress, say=say)  # fmt: skip
    sweep.root.mkdir(parents=True, exist_ok=True)
    say(f"sweep {config.preset}, {split} split (hands {period[0]:g}:{period[1]:g} of the month "
        f"by time): {len(cells)} cells")  # fmt: skip
    tables = {c.table_key: _table(sweep, c) for c in cells}
    say(f"[2/5] irl: {len({c.reward_key for c in cells})} reward settings x {config.runs} runs")
    for reward_key in dict.fromkeys(c.reward_key for c in cells):
        _irl(sweep, next(c for c in cells if c.reward_key == reward_key))
    say(f"[3/5] agents: {len(cells)} learned sets, "
        f"{len({c.sparse_key for c in cells})} sparse sets, {len(config.seeds)} seeds each")
    for cell in cells:
        _agents(sweep, cell)
    say("[4/5] evaluations: each agent against random, call, TightBot, LooseBot, its sparse "
        f"DQN ({config.eval_hands:,} duplicate hands each) and LBR ({config.lbr_hands:,} hands)")
    evals = _evaluate(sweep, cells)
    results = []
    for cell in cells:
        runs = _irl_runs(sweep, cell)
        reward, bc = _agreements(runs)
        agents = tuple(evals[_agent_folder(sweep, cell.name, s)] for s in config.seeds)
        sparse = tuple(evals[_agent_folder(sweep, cell.sparse_key, s)] for s in config.seeds)
        results.append(CellResult(
            name=cell.name, axis=config.axis_of(cell), cell=cell, agents=agents, sparse=sparse,
            reward_agreement=reward, bc_agreement=bc,
            targets=targets_of(agents, sparse, evals["call"], reward, bc),
        ))  # fmt: skip
    result = SweepResult(
        split=split, config=config, month=", ".join(sweep.month),
        tables={key: _table_counts(path) for key, path in tables.items()},
        call=evals["call"], cells=tuple(results),
        chosen=choose(results).name if split == Split.CHOOSE else None,
        rule=CHOICE_RULE if split == Split.CHOOSE else "",
    )  # fmt: skip
    say("[5/5] report")
    write_sweep(result, sweep.root)
    return result


def _chosen(out: Path) -> str:
    path = out / Split.CHOOSE / JSON_FILE
    if not path.is_file():
        raise StudyError(f"{path}: no choose split to test: run the choose split first")
    found = SweepResult.from_json(read_json(path), str(path))
    if found.chosen is None:
        raise StudyError(f"{path}: names no chosen cell")
    return found.chosen


def load_sweep(path: str | os.PathLike[str]) -> SweepResult:
    """A split's ``sweep.json`` (or the folder holding it), typed."""
    path = Path(path)
    path = path / JSON_FILE if path.is_dir() else path
    return SweepResult.from_json(read_json(path), str(path))


def _table(sweep: _Sweep, cell: Cell) -> Path:
    """The period's table of ``cell``'s folds and experts: a ``file`` unit, ingested here."""
    from pokerirl.datasets.ingest import ingest_table
    from pokerirl.studies.poker.pipeline import expert_selection

    config = sweep.config
    target = sweep.root / "tables" / f"{cell.table_key}.parquet"
    selection = expert_selection(sweep.period, winners=cell.experts == Experts.WINNERS,
                                 min_hands=config.winners_min_hands,
                                 min_bb_per_100=config.winners_bb_per_100)  # fmt: skip
    unit: Unit[None] = Unit(
        key=f"table {cell.table_key}",
        target=target,
        layout=Layout.FILE,
        config={
            "unit": "poker-sweep-table", "folds": cell.folds, "selection": selection.to_json(),
            **_sources_print(sweep.month),
        },
    )
    if check(unit, overwrite=sweep.overwrite).fate is not Fate.REUSED:
        sweep.say(f"[1/5] ingest: {cell.table_key}, hands {selection.period} of the month")
        target.parent.mkdir(parents=True, exist_ok=True)
        with writing(unit) as folder:
            if cell.folds == "impute":
                from pokerirl.poker.folds import ImputeConfig
                from pokerirl.poker.impute import ingest_imputed

                ingest_imputed(sweep.month, folder / target.name, ImputeConfig(),
                               progress=sweep.progress, recorded_as=target.name,
                               selection=selection)  # fmt: skip
            else:
                ingest_table(sweep.month, folder / target.name, progress=sweep.progress,
                             recorded_as=target.name, selection=selection)  # fmt: skip
    return target


def _sources_print(sources: Sequence[str]) -> dict[str, Any]:
    """The month's files by name and content digest, wherever the month lies. An edit of the
    test period re-ingests the choose table, whose bytes, the IRL's input, do not change."""
    from pokerirl.studies.poker.pipeline import source_files

    return {"files": [
        [item.name if item == source else str(item.relative_to(source)),
         digest(item.read_bytes())]
        for source, item in source_files(sources)
    ]}  # fmt: skip


def _table_counts(table: Path) -> dict[str, Any]:
    from pokerirl.datasets.ingest import summary_path

    summary = read_json(summary_path(table))
    keys = ("kept_hands", "rows", "hands_read_total")
    counts = {key: summary.get(key) for key in keys}
    selection = summary.get("selection") or {}
    counts["selection_steps"] = selection.get("steps", [])
    return counts


def _irl_folder(sweep: _Sweep, cell: Cell) -> Path:
    return sweep.root / "irl" / cell.reward_key


def _irl(sweep: _Sweep, cell: Cell) -> None:
    from pokerirl.game.encodings import get_encoding
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.poker.train import train_runs

    config = dataclasses.replace(AIRLConfig.for_algo(cell.algo), epochs=sweep.config.irl_epochs,
                                 reward_weight_decay=cell.reward_decay)  # fmt: skip
    out = _irl_folder(sweep, cell)
    sweep.say(f"      {cell.reward_key}: {sweep.config.runs} runs -> {out}")
    train_runs(sweep.root / "tables" / f"{cell.table_key}.parquet", out, runs=sweep.config.runs,
               algo=cell.algo, config=config, progress=sweep.progress,
               overwrite=sweep.overwrite, backend=sweep.backend,
               encoding=get_encoding(cell.encoding), single_folder=False)  # fmt: skip


def _irl_runs(sweep: _Sweep, cell: Cell) -> list[Path]:
    return [_irl_folder(sweep, cell) / f"run-{k}" for k in range(sweep.config.runs)]


def _agreements(runs: Sequence[Path]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Per run: f's argmax agreement with the expert on the validation hands (the last
    epoch's), and behaviour cloning's."""
    from pokerirl.irl.metrics import Metric
    from pokerirl.irl.run import read_baselines, read_epochs

    reward = tuple(float(Metric.VAL_REWARD_ALIGNMENT.of(read_epochs(run)[-1])) for run in runs)
    bc = tuple(float(read_baselines(run)["bc"]) for run in runs)
    return reward, bc


def _agent_folder(sweep: _Sweep, name: str, seed: int) -> Path:
    return sweep.root / "agents" / name / f"seed-{seed}"


def _agents(sweep: _Sweep, cell: Cell) -> None:
    """The cell's learned-reward DQNs (seed k on IRL run k mod runs) and its sparse set."""
    from pokerirl.agents.train import agent_preset, train_seeds

    config = sweep.config
    base = agent_preset("default", hands=cell.hands, seed=config.seeds[0],
                        eval_every=cell.hands, eval_hands=2_000, encoding=cell.encoding,
                        opponent=cell.opponent)  # fmt: skip
    common: dict[str, Any] = dict(backend=sweep.backend, progress=sweep.progress,
                                  overwrite=sweep.overwrite)  # fmt: skip
    train_seeds(sweep.root / "agents" / cell.sparse_key, base, list(config.seeds), **common)
    learned = dataclasses.replace(base, reward="learned", reward_transform=cell.transform,
                                  payoff_weight=cell.payoff_weight)  # fmt: skip
    runs = _irl_runs(sweep, cell)
    for k, run in enumerate(runs):
        group = [s for s in config.seeds if s % len(runs) == k]
        if group:
            train_seeds(sweep.root / "agents" / cell.name,
                        dataclasses.replace(learned, reward_run=str(run)), group,
                        **common)  # fmt: skip


def _evaluate(sweep: _Sweep, cells: Sequence[Cell]) -> dict[Any, AgentEval]:
    """Every agent's evaluation (and always-call's), as record units; keyed by agent folder
    (``"call"`` for always-call)."""
    from pokerirl.agents import ship_agent
    from pokerirl.agents.registry import agent_fingerprint, resolve_agent
    from pokerirl.poker.reward_sources import RewardSource

    config = sweep.config
    settings = {"kind": EVAL_KIND, "eval_hands": config.eval_hands, "eval_seed": EVAL_SEED,
                "lbr_hands": config.lbr_hands, "lbr_seed": LBR_SEED,
                "lbr_check_until": LBR_CHECK_UNTIL}  # fmt: skip
    jobs: dict[Any, tuple[str, str | None, str | None]] = {"call": ("call", None, None)}
    for cell in cells:
        runs = _irl_runs(sweep, cell)
        for seed in config.seeds:
            baseline = str(_agent_folder(sweep, cell.sparse_key, seed))
            jobs.setdefault(Path(baseline), (baseline, None, None))
            learned = _agent_folder(sweep, cell.name, seed)
            jobs[learned] = (str(learned), baseline, str(runs[seed % len(runs)]))
    units = []
    for key, (spec, sparse, reward_run) in jobs.items():
        name = "call" if key == "call" else str(Path(spec).relative_to(sweep.root / "agents"))
        inputs: dict[str, str | None] = {"agent": agent_fingerprint(resolve_agent(spec))}
        if sparse is not None:
            inputs["sparse"] = agent_fingerprint(resolve_agent(sparse))
        source = None if reward_run is None else RewardSource.read(reward_run)
        if source is not None:
            inputs["reward"] = source.fingerprint
        units.append(Unit(
            key=f"evaluate {name}",
            target=sweep.root / "evals" / f"{name.replace('/', '--')}.json",
            layout=Layout.RECORD,
            config=settings,
            inputs=inputs,
            fn=_evaluate_unit,
            args=(ship_agent(spec), None if sparse is None else ship_agent(sparse), source,
                  config.eval_hands, config.lbr_hands),
            accepts=_is_eval,
        ))  # fmt: skip
    run_units(units, sweep.backend, overwrite=sweep.overwrite, progress=sweep.progress,
              desc="evaluations")  # fmt: skip
    found: dict[Any, AgentEval] = {}
    for key, unit in zip(jobs, units, strict=True):
        record = read_record(unit.target)
        assert record is not None and record.result is not None  # run_units saved it
        found[key] = AgentEval.from_json(record.result, str(unit.target))
    return found


def _is_eval(result: Any) -> bool:
    try:
        AgentEval.from_json(result, "result")
    except (ValueError, TypeError):
        return False
    return True


def _evaluate_unit(agent_files: Any, sparse_files: Any, reward_source: Any, eval_hands: int,
                   lbr_hands: int) -> UnitOutput[None]:  # fmt: skip
    """Evaluate one agent (in a worker): matches, its decisions against random, LBR."""
    from pokerirl.agents import land_agent
    from pokerirl.agents.train import followed
    from pokerirl.game import DecisionLog, make_agent, play_match
    from pokerirl.holdem import ACTIONS
    from pokerirl.poker.reward_card import legal_majority
    from pokerirl.tournaments.exploit import lbr_of

    with tempfile.TemporaryDirectory(prefix="pokerirl-sweep-") as private:
        agent = land_agent(agent_files, Path(private, "agent"))
        vs: dict[str, float] = {}
        log: list[DecisionLog] = []
        for name in OPPONENTS:
            result = play_match(agent, make_agent(name), hands=eval_hands, seed=EVAL_SEED,
                                log=log if name == "random" else None)  # fmt: skip
            vs[name] = round(result.mbb_per_hand, 3)
        seen = DecisionLog.concatenate(log)
        shares = np.bincount(seen.actions, minlength=len(ACTIONS)) / max(len(seen.actions), 1)
        found: dict[str, Any] = {
            "vs": vs,
            "shares": {a: round(float(shares[i]), 6) for i, a in enumerate(ACTIONS)},
            "agrees_with_call": round(
                float((legal_majority(seen.legal_mask) == seen.actions).mean()), 6
            ),
        }
        if reward_source is not None:
            found["follows"] = followed(reward_source.load(), log)
        if sparse_files is not None:
            sparse = land_agent(sparse_files, Path(private, "sparse"))
            match = play_match(agent, sparse, hands=eval_hands, seed=EVAL_SEED)
            found["vs_sparse"] = round(match.mbb_per_hand, 3)
            found["vs_sparse_se"] = round(match.std_error, 3)
        lbr_spec = "call" if not agent_files.files else str(Path(private, "agent"))
        lbr = lbr_of(lbr_spec, hands=lbr_hands, seed=LBR_SEED, check_until=LBR_CHECK_UNTIL)
        found["lbr"] = round(lbr.lbr_mbb_per_hand, 3)
        found["lbr_se"] = round(lbr.lbr_std_error, 3)
    return UnitOutput(result=AgentEval.from_json(found, "evaluation").to_json())


# --------------------------------------------------------------------------- the report


def _pm(mean: float, se: float, fmt: str = "+,.0f") -> str:
    return f"{mean:{fmt}}" if math.isnan(se) else f"{mean:{fmt}} ± {se:{fmt.lstrip('+')}}"


ROW_HEAD = ("cell (axis: value)", "targets met", "reward = expert", "BC = expert",
            "follows f", "≠ always-call", "vs random", "vs call", "vs TightBot", "vs LooseBot",
            "vs sparse DQN", "LBR", "sparse DQN's LBR")  # fmt: skip


def _row(result: SweepResult, cell: CellResult) -> list[str]:
    axis = cell.axis
    label = "base" if axis == "base" else f"{axis}: {getattr(cell.cell, axis)}"
    mark = " **(chosen)**" if result.chosen == cell.name else ""
    return [
        f"{label}{mark}",
        f"{cell.targets.met}/5",
        f"{np.mean(cell.reward_agreement):.1%}",
        f"{np.mean(cell.bc_agreement):.1%}",
        f"{cell.mean(lambda a: a.follows):.0%}",
        f"{1 - cell.mean(lambda a: a.agrees_with_call):.0%}",
        *[_pm(cell.mean(lambda a, o=o: a.vs[o]), cell.se(lambda a, o=o: a.vs[o]))  # type: ignore[misc]
          for o in OPPONENTS],
        _pm(cell.mean(lambda a: a.vs_sparse), cell.se(lambda a: a.vs_sparse)),
        _pm(cell.mean(lambda a: a.lbr), cell.se(lambda a: a.lbr)),
        _pm(cell.mean(lambda a: a.lbr, True), cell.se(lambda a: a.lbr, True)),
    ]


def first_paragraph(result: SweepResult) -> str:
    """Does the learned reward help here, by how much, against what: in plain words."""
    cells = result.cells
    best = max(cells, key=lambda c: c.targets.met)
    chosen = next((c for c in cells if c.name == result.chosen), best)
    h2h = chosen.mean(lambda a: a.vs_sparse)
    h2h_se = chosen.se(lambda a: a.vs_sparse)
    everything = [c for c in cells if c.targets.met == 5]
    verdict = (
        f"{len(everything)} of {len(cells)} cells meet all five targets"
        if everything else
        f"no cell meets all five targets; the closest meet {best.targets.met} of 5"
    )  # fmt: skip
    helps = "helps" if h2h > 0 and (math.isnan(h2h_se) or h2h > 2 * h2h_se) else "does not help"
    return (
        f"On the {result.split} split ({result.month}), {verdict}. In the "
        f"{'chosen' if result.chosen else 'tested'} cell ({chosen.name}) the learned reward "
        f"{helps} its DQN against the sparse DQN trained the same way: "
        f"{_pm(h2h, h2h_se, '+,.0f')} mbb/h head to head (mean ± SE over "
        f"{len(chosen.agents)} DQN seeds); its LBR is {chosen.mean(lambda a: a.lbr):+,.0f} "
        f"mbb/h against the sparse DQN's {chosen.mean(lambda a: a.lbr, True):+,.0f} and "
        f"always-call's {result.call.lbr:+,.0f}; it follows its reward on "
        f"{chosen.mean(lambda a: a.follows):.0%} of its decisions and differs from always-call "
        f"on {1 - chosen.mean(lambda a: a.agrees_with_call):.0%}; the reward's argmax agrees "
        f"with the expert on {np.mean(chosen.reward_agreement):.1%} of validation states, BC on "
        f"{np.mean(chosen.bc_agreement):.1%}."
    )


def render_markdown(result: SweepResult) -> str:
    config = result.config
    period = config.choose_period if result.split == Split.CHOOSE else config.test_period
    lines = [
        f"# Poker sweep `{config.preset}`: the {result.split} split",
        "",
        first_paragraph(result),
        "",
        f"Every number here comes from the **{result.split}** split: hands "
        f"{period[0]:g}:{period[1]:g} of the month by time ({result.month}). "
        + ("The choice read nothing else." if result.split == Split.CHOOSE else
           "This split was read by nothing in the choice."),
        f"{config.runs} IRL runs of {config.irl_epochs} epochs per reward setting; "
        f"{len(config.seeds)} DQN seeds per agent set (seeds {', '.join(map(str, config.seeds))}; "
        f"learned seed k on IRL run k mod {config.runs}); each agent plays {config.eval_hands:,} "
        f"duplicate hands (deal seed {EVAL_SEED}) against each opponent and its sparse DQN; LBR "
        f"{config.lbr_hands:,} hands (seed {LBR_SEED}, {LBR_CHECK_UNTIL} on). ± is the SE over "
        "DQN seeds (none with one seed). Agreements are the mean over IRL runs of the last "
        "epoch's validation figure.",
        f"Always-call: LBR {result.call.lbr:+,.0f} ± {result.call.lbr_se:,.0f} mbb/h, "
        f"vs random {result.call.vs['random']:+,.0f}.",
        "",
        f"Base cell: {', '.join(f'{k} {v}' for k, v in config.base.to_json().items())}.",
        "",
    ]
    lines += markdown_table(list(ROW_HEAD), [_row(result, cell) for cell in result.cells])
    if result.chosen:
        lines += ["", f"Choice rule, fixed before the run: {result.rule}.", "",
                  f"Chosen: **{result.chosen}**."]  # fmt: skip
    lines += ["", f"![LBR against the head-to-head result]({FIGURE_FILE})", ""]
    return "\n".join(lines)


CSV_COLUMNS = ("cell", "axis", *[f.name for f in dataclasses.fields(Cell)], "targets_met",
               "reward_agreement", "bc_agreement", "follows", "differs_from_call",
               *[f"vs_{o}" for o in OPPONENTS], "vs_sparse", "vs_sparse_se", "lbr", "lbr_se",
               "sparse_lbr", "chosen")  # fmt: skip


def render_csv(result: SweepResult) -> str:
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for cell in result.cells:
        writer.writerow([
            cell.name, cell.axis, *[getattr(cell.cell, f.name) for f in dataclasses.fields(Cell)],
            cell.targets.met, f"{np.mean(cell.reward_agreement):.6f}",
            f"{np.mean(cell.bc_agreement):.6f}", f"{cell.mean(lambda a: a.follows):.6f}",
            f"{1 - cell.mean(lambda a: a.agrees_with_call):.6f}",
            *[f"{cell.mean(lambda a, o=o: a.vs[o]):.3f}" for o in OPPONENTS],  # type: ignore[misc]
            f"{cell.mean(lambda a: a.vs_sparse):.3f}", f"{cell.se(lambda a: a.vs_sparse):.3f}",
            f"{cell.mean(lambda a: a.lbr):.3f}", f"{cell.se(lambda a: a.lbr):.3f}",
            f"{cell.mean(lambda a: a.lbr, True):.3f}", int(result.chosen == cell.name),
        ])  # fmt: skip
    return stream.getvalue()


def plot_sweep(result: SweepResult, path: Path) -> None:
    """Each cell's LBR against its head-to-head result vs its sparse DQN (± SE over seeds)."""
    import matplotlib

    from pokerirl.figures import finish

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(8, 5.5))
    for cell in result.cells:
        x, y = cell.mean(lambda a: a.vs_sparse), cell.mean(lambda a: a.lbr)
        xe, ye = cell.se(lambda a: a.vs_sparse), cell.se(lambda a: a.lbr)
        chosen = cell.name == result.chosen
        axes.errorbar(x, y, xerr=None if math.isnan(xe) else xe,
                      yerr=None if math.isnan(ye) else ye, fmt="*" if chosen else "o",
                      markersize=12 if chosen else 6, capsize=2)  # fmt: skip
        label = "base" if cell.axis == "base" else f"{cell.axis}={getattr(cell.cell, cell.axis)}"
        axes.annotate(label, (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
    axes.axhline(result.call.lbr, color="grey", linestyle="--", linewidth=0.8)
    axes.annotate("always-call's LBR", (axes.get_xlim()[0], result.call.lbr), fontsize=7)
    axes.axvline(0.0, color="grey", linewidth=0.8)
    finish(axes, title=f"Poker sweep, {result.split} split: lower and to the right is better",
           xlabel="head to head vs the sparse DQN of the same encoding, opponent, budget (mbb/h)",
           ylabel="LBR: what a local best response wins from it (mbb/h)",
           spread="bars: ± 1 SE over DQN seeds; star: the chosen cell")  # fmt: skip
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", dpi=100)
    plt.close(figure)


def write_sweep(result: SweepResult, folder: Path) -> None:
    write_text(folder / JSON_FILE, json.dumps(result.to_json(), indent=2) + "\n")
    write_text(folder / MARKDOWN_FILE, render_markdown(result))
    write_text(folder / CSV_FILE, render_csv(result))
    plot_sweep(result, folder / FIGURE_FILE)


__all__ = [
    "PRESETS",
    "Cell",
    "Experts",
    "Split",
    "SweepConfig",
    "SweepResult",
    "choose",
    "load_sweep",
    "run_sweep",
    "sweep_preset",
]
