"""The study pipeline: ingest -> irl -> agents -> tournament [-> authors] -> panel -> report.

The ``authors`` stage (the authors' tournament protocol) runs when the settings ask for it
(``authors_repeats`` > 0: the ``authors`` preset).

Each stage is units of :mod:`pokerirl.store`, each with its own record: the table
(``expert.parquet``, its record ``expert.unit.json``), the IRL runs (``irl/<algo>/run-<k>``, or
``irl/<algo>`` for one run; trained offline, or online with ``irl_mode`` online:
:func:`online_runs`), the agent seeds, the tournament seeds and experiments. A stage's
result (what the report reads) is recomputed from its units' outputs on every run. A rerun
reuses every unit finished with the same settings and inputs, runs the missing ones, and
refuses, in one line naming it, a unit made with other settings or inputs unless
``overwrite``: then that unit is recomputed, and so is every unit that reads it (their inputs
hold its digest).

A study folder of an older pokerirl holds ``stages/<stage>.json`` records instead of the
table's and the single IRL run's own: those units are reused when that stage record finished
with the same settings, and refused in one line naming it when not.

Every call that trains or plays goes through :class:`Execution`, the one place that decides
where units run (processes now; the execution layer's backends later).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pokerirl.execution import Backend
from pokerirl.jsonio import read_json
from pokerirl.meanstd import Curve
from pokerirl.store import Fate, Layout, LegacyRecord, Unit, check, digest, fingerprint, writing
from pokerirl.studies.poker.config import (
    BUILT_INS,
    IRL_ALGOS,
    LBR_CHECK_UNTIL,
    Experts,
    StudyConfig,
    StudyError,
    irl_overrides,
)
from pokerirl.studies.poker.report_types import CardSummary
from pokerirl.studies.poker.results import (
    AgentsResult,
    Ingested,
    IRLResult,
    IRLRuns,
    Panel,
    Reference,
    Replaced,
    Spread,
    Table1Line,
    TrainingLength,
)

if TYPE_CHECKING:  # the layers below load lazily: ``pokerirl report`` needs none of them
    from pokerirl.agents.train import TrainConfig
    from pokerirl.datasets.players import Selection
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.tournaments import AuthorsMatchup, TournamentReport

STAGES = ("ingest", "irl", "agents", "tournament", "panel", "report")
AUTHORS_STAGES = ("ingest", "irl", "agents", "tournament", "authors", "panel", "report")
PLAYING_HANDS = 20_000  # duplicate hands of the playing checkpoint against random (authors)
STAGES_FOLDER = "stages"  # where an older pokerirl kept its stage records
TABLE = "expert.parquet"
AGENT_FOLDERS = {"dqn": "dqn", **{f"{algo}_dqn": f"{algo}-dqn" for algo in IRL_ALGOS}}
SHORT_DQN = "dqn-short"  # sparse DQN at the paper's training length

Say = Callable[[str], None]


@dataclass(frozen=True)
class Execution:
    """Where units run. The single place that calls the training and playing entry points, so
    a backend (local processes or a Ray cluster) is threaded through here and nowhere else."""

    backend: Backend = field(default_factory=Backend)
    progress: bool = False
    overwrite: bool = False  # recompute units made with other settings instead of refusing

    def train_runs(
        self, table: Path, out: Path, *, algo: str, runs: int, config: AIRLConfig, encoding: str
    ) -> None:
        from pokerirl.game.encodings import get_encoding
        from pokerirl.poker.train import train_runs

        train_runs(
            table,
            out,
            runs=runs,
            algo=algo,
            config=config,
            progress=self.progress,
            overwrite=self.overwrite,
            backend=self.backend,
            encoding=get_encoding(encoding),  # the study config's name, checked when read
        )

    def train_seeds(self, out: Path, config: TrainConfig, seeds: Sequence[int]) -> None:
        from pokerirl.agents.train import train_seeds

        train_seeds(out, config, list(seeds), backend=self.backend, progress=self.progress,
                    overwrite=self.overwrite)  # fmt: skip

    def tournament(
        self,
        matchups: Sequence[tuple[str, str]],
        *,
        hands: int,
        seeds: Sequence[int],
        out: Path,
        duplicate: bool,
    ) -> TournamentReport:
        from pokerirl.tournaments import run_tournament

        return run_tournament(
            matchups,
            hands=hands,
            seeds=seeds,
            out=out,
            duplicate=duplicate,
            overwrite=self.overwrite,
            backend=self.backend,
            progress=self.progress,
        )

    def authors_tournament(
        self,
        matchups: Sequence[tuple[str, str]],
        *,
        names: Sequence[str],
        experiments: Sequence[int],
        repeats: int,
        games: int,
        out: Path,
        duplicate: dict[str, float],
    ) -> dict[str, AuthorsMatchup]:
        from pokerirl.tournaments import run_authors_tournament

        return run_authors_tournament(
            matchups,
            names=names,
            experiments=experiments,
            repeats=repeats,
            games=games,
            out=out,
            duplicate=duplicate,
            overwrite=self.overwrite,
            backend=self.backend,
            progress=self.progress,
        )


# --------------------------------------------------------------------------- the study


def stage_names(config: StudyConfig) -> tuple[str, ...]:
    """The stages a study of ``config`` runs, in order."""
    return AUTHORS_STAGES if config.authors_repeats else STAGES


def _non_default(config: StudyConfig, *names: str) -> dict[str, Any]:
    """The settings among ``names`` that differ from their defaults: the stage records of
    studies made before they existed stay valid."""
    import dataclasses

    defaults = {f.name: f.default for f in dataclasses.fields(StudyConfig)}
    return {
        name: getattr(config, name) for name in names if getattr(config, name) != defaults[name]
    }


def source_files(sources: Sequence[str | os.PathLike[str]]) -> list[tuple[Path, Path]]:
    """Every file of the sources (a file, or a folder's files in order), with the source it
    is in; a missing source is one line."""
    files = []
    for source in sources:
        path = Path(source)
        if not path.exists():
            raise StudyError(f"{path}: no such file or folder")
        found = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
        files += [(path, item) for item in found]
    return files


def _sources_fingerprint(sources: Sequence[str | os.PathLike[str]]) -> dict[str, Any]:
    """Every source file's path, size and modification time (cheap on a large corpus)."""
    files = []
    for _, item in source_files(sources):
        stat = item.stat()
        files.append([str(item.resolve()), stat.st_size, stat.st_mtime_ns])
    return {"files": files}


@dataclass(frozen=True)
class Study:
    """A study folder, its settings, and how to run units."""

    root: Path
    config: StudyConfig
    execution: Execution
    overwrite: bool = False
    say: Say = lambda message: None

    def step(self, name: str) -> None:
        """Say that stage ``name`` starts: ``[2/6] irl``."""
        names = stage_names(self.config)
        self.say(f"[{names.index(name) + 1}/{len(names)}] {name}")

    def legacy(self, name: str, settings: dict[str, Any]) -> LegacyRecord:
        """The record an older pokerirl kept for stage ``name``, with the identity it wrote."""
        path = self.root / STAGES_FOLDER / f"{name}.json"
        return LegacyRecord(path=path, identity={"stage": name, "settings": settings})


# --------------------------------------------------------------------------- stages


def ingest_stage(study: Study, sources: Sequence[str | os.PathLike[str]]) -> Ingested:
    """The table and its summary: a ``file`` unit, ingested in this process."""
    from pokerirl.datasets.ingest import ingest_table, summary_path

    study.step("ingest")
    sources_print = _sources_fingerprint(sources)
    imputing = study.config.folds == "impute"
    folds = {"folds": "impute"} if imputing else {}  # drop: the records of before
    selection = study_selection(study.config)
    if selection is not None:  # none: the records of before
        folds["selection"] = selection.to_json()
    legacy = study.legacy("ingest", {"sources": sources_print, **folds})
    unit: Unit[None] = Unit(
        key="ingest",
        target=study.root / TABLE,
        layout=Layout.FILE,
        config={"unit": "poker-study-ingest", **sources_print, **folds},
        legacy=(legacy,),
    )
    if check(unit, overwrite=study.overwrite).fate is Fate.REUSED:
        study.say("      the table is finished already, reused")
    else:
        with writing(unit) as folder:
            if imputing:  # the default imputation (docs/folds.md), seeded
                from pokerirl.poker.folds import ImputeConfig
                from pokerirl.poker.impute import ingest_imputed

                ingest_imputed(sources, folder / TABLE, ImputeConfig(),
                               progress=study.execution.progress,
                               recorded_as=TABLE, selection=selection)  # fmt: skip
            else:
                # The summary names the table relative to the study folder, where it sits:
                # not the unit's staging path, and the same bytes in any study folder.
                ingest_table(sources, folder / TABLE, progress=study.execution.progress,
                             recorded_as=TABLE, selection=selection)  # fmt: skip
    summary = read_json(summary_path(study.root / TABLE))
    return Ingested(summary=summary, fingerprint=fingerprint(legacy.identity))


def study_selection(config: StudyConfig) -> Selection | None:
    """The study's ingest selection, or None for all hands and players (the records of
    before)."""
    if config.experts == Experts.ALL and config.period == (0.0, 1.0):
        return None
    return expert_selection(config.period, winners=config.experts == Experts.WINNERS,
                            min_hands=config.winners_min_hands,
                            min_bb_per_100=config.winners_bb_per_100)  # fmt: skip


def expert_selection(
    period: tuple[float, float], *, winners: bool, min_hands: int, min_bb_per_100: float
) -> Selection:
    """The hands of ``period`` (fractions of each month by time) and, for ``winners``, the
    players who won at least ``min_bb_per_100`` over at least ``min_hands`` of them: the
    selection of the expert for a study and for each sweep table."""
    from pokerirl.datasets.players import Period, Selection

    return Selection(
        period=Period(start=period[0], end=period[1]),
        min_hands=min_hands if winners else None,
        min_bb_per_100=min_bb_per_100 if winners else None,
    )


def run_paths(out: Path, runs: int) -> list[Path]:
    """The run folders ``train_runs`` writes: ``out`` itself for one run, else ``run-<k>``."""
    return [out] if runs == 1 else [out / f"run-{k}" for k in range(runs)]


def summarize_irl(out: Path, runs: int) -> IRLRuns:
    """Per-epoch mean/std over runs of the curves the report draws, final values per run,
    mean action distributions and the baselines."""
    from pokerirl.irl.metrics import Metric
    from pokerirl.irl.run import read_baselines, read_epochs

    metrics = [read_epochs(p) for p in run_paths(out, runs)]
    found_baselines = [read_baselines(p) for p in run_paths(out, runs)]
    epochs = min(len(m) for m in metrics)
    curves: dict[str, Curve] = {}
    final: dict[str, Spread] = {}
    for metric in (Metric.VAL_ALIGNMENT, Metric.DISC_ACC_EXPERT, Metric.DISC_ACC_POLICY,
                   Metric.VAL_REWARD_ALIGNMENT):  # fmt: skip
        if metric in metrics[0][0]:
            curves[metric] = Curve.of([[metric.of(line) for line in run[:epochs]]
                                       for run in metrics])  # fmt: skip
            final[metric] = Spread.of([metric.of(run[epochs - 1]) for run in metrics])
    dists: dict[str, Curve] = {}
    for metric in (Metric.VAL_EXPERT_DIST, Metric.VAL_POLICY_DIST):
        if metric in metrics[0][-1]:
            dists[metric] = Curve.of([metric.of(run[epochs - 1]) for run in metrics])
    return IRLRuns(
        runs=runs,
        epochs=epochs,
        curves=curves,
        final=final,
        action_dist=dists,
        baselines={key: Spread.of([b[key] for b in found_baselines]) for key in found_baselines[0]},
    )


def irl_stage(study: Study, ingested: Ingested) -> IRLResult:
    """Each algorithm's IRL runs (``run-<k>`` units, or one run as ``irl/<algo>`` itself), or
    the reward that replaces them; ``ingested``: the stage before, for an older study's
    ``stages/irl.json``."""
    from pokerirl.irl import load_config

    config = study.config
    table = study.root / TABLE
    stage = {
        "runs": config.runs,
        "epochs": config.irl_epochs,
        "seed": config.irl_seed,
        "upstream": ingested.fingerprint,
        **_non_default(config, "irl_settings", "encoding", "algos", "reward_decay"),
    }
    online = config.online_settings()
    if online is not None:  # only online: the records of before keep their bytes
        stage["online"] = online.record()
    if config.reward_sources:
        stage["reward_sources"] = reward_source_prints(config)
    legacy = study.legacy("irl", stage)
    study.step("irl")
    found: IRLResult = {}
    for algo in config.algos:
        out = study.root / "irl" / algo
        source = config.reward_source(algo)
        if source is not None:
            found[algo] = replaced_irl(study, algo, source, out)
            continue
        chosen = {"epochs": config.irl_epochs, "seed": config.irl_seed,
                  "reward_weight_decay": config.reward_decay}  # fmt: skip
        overrides = {
            **irl_overrides(config.irl_settings, algo),
            **{k: v for k, v in chosen.items() if v is not None},
        }
        settings = load_config(algo, overrides=overrides)
        study.say(f"      {algo}: {config.runs} runs{'' if online is None else ' online'} -> {out}")
        out.parent.mkdir(parents=True, exist_ok=True)
        if online is not None:
            online_runs(study, algo, settings, online, out)
        elif config.runs == 1:
            single_run(study, algo, settings, out, legacy)
        else:  # run-<k> units, each with its record
            study.execution.train_runs(table, out, algo=algo, runs=config.runs, config=settings,
                                       encoding=config.encoding)  # fmt: skip
        found[algo] = summarize_irl(out, config.runs)
    return found


def single_run(
    study: Study, algo: str, settings: AIRLConfig, out: Path, legacy: LegacyRecord
) -> None:
    """One IRL run into ``out`` itself: a ``folder`` unit trained in this process (an older
    pokerirl's has no record of its own: its ``stages/irl.json`` vouches for it)."""
    from pokerirl.datasets.decisions import read_data
    from pokerirl.game.encodings import get_encoding
    from pokerirl.irl.run import TIMINGS_FILE
    from pokerirl.poker.train import train_table_into

    table = study.root / TABLE
    encoding = study.config.encoding
    unit_config = {"unit": "poker-study-irl", "algo": algo, "settings": settings.to_dict(),
                   **_non_default(study.config, "encoding")}  # fmt: skip
    unit: Unit[None] = Unit(
        key=f"{algo} run",
        target=out,
        config=unit_config,
        inputs={"table": digest(table.read_bytes())},
        legacy=(legacy,),
    )
    if check(unit, overwrite=study.overwrite).fate is Fate.REUSED:
        return
    with writing(unit, unhashed={TIMINGS_FILE}) as folder:
        train_table_into(read_data(table, encoding=get_encoding(encoding)), folder, algo=algo,
                         config=settings, progress=study.execution.progress,
                         table=table)  # fmt: skip


def online_runs(
    study: Study, algo: str, settings: AIRLConfig, online: Any, out: Path
) -> None:
    """The online IRL runs (``train --mode online``, :mod:`pokerirl.poker.online`), in the
    folders the offline runs have (``out`` itself for one run, else ``run-<k>``): a ``folder``
    unit each, trained in this process one after another, run k with seed ``seed + k`` (the
    run ``train --mode online --runs N`` trains k-th). Its record holds the mode and the
    generator's settings: an offline run in its place is refused, or with ``overwrite``
    recomputed."""
    import shutil
    import tempfile
    from dataclasses import replace

    from pokerirl.game.encodings import get_encoding
    from pokerirl.irl.run import TIMINGS_FILE
    from pokerirl.poker.online import train_poker_online

    table = study.root / TABLE
    table_print = digest(table.read_bytes())
    for k, folder in enumerate(run_paths(out, study.config.runs)):
        run_settings = replace(settings, seed=settings.seed + k)
        unit_config = {"unit": "poker-study-irl", "algo": algo, "mode": "online",
                       "settings": run_settings.to_dict(), "online": online.record(),
                       **_non_default(study.config, "encoding")}  # fmt: skip
        unit: Unit[None] = Unit(
            key=f"{algo} {folder.name}", target=folder, config=unit_config,
            inputs={"table": table_print},
        )  # fmt: skip
        if check(unit, overwrite=study.overwrite).fate is Fate.REUSED:
            continue
        with writing(unit, unhashed={TIMINGS_FILE}) as new, \
                tempfile.TemporaryDirectory(prefix="pokerirl-online-") as scratch:  # fmt: skip
            run = Path(scratch) / "run"  # the command's own staging stays out of the unit's
            train_poker_online(table, run, algo=algo, config=run_settings, settings=online,
                               encoding=get_encoding(study.config.encoding),
                               progress=study.execution.progress)  # fmt: skip
            shutil.copytree(run, new, dirs_exist_ok=True)


def reward_source_prints(config: StudyConfig) -> dict[str, str]:
    """The fingerprint of each reward that replaces IRL runs; one-line StudyError if bad."""
    from pokerirl.poker.reward_sources import RewardSource

    try:
        sources = config.reward_sources
        return {algo: RewardSource.resolve(spec).fingerprint for algo, spec in sources}
    except ValueError as error:
        raise StudyError(str(error)) from None


def replaced_irl(study: Study, algo: str, source: str, out: Path) -> Replaced:
    """An algorithm whose IRL runs a given reward replaces: its card over the whole table."""
    from pokerirl.poker.reward_card import CardStates, reward_card, write_card
    from pokerirl.poker.reward_sources import load_reward_source

    study.say(f"      {algo}: replaced by {source}")
    card = reward_card(load_reward_source(source), CardStates.from_table(study.root / TABLE))
    write_card(card, out)
    return Replaced(source=source)


def _final_vs_random(agent_set: Path, seeds: Sequence[int]) -> list[float]:
    from pokerirl.agents.train import read_metrics

    return [read_metrics(agent_set / f"seed-{s}")[-1].eval["random"].mbb_per_hand for s in seeds]


def _follows_reward(sets: dict[str, Path], seeds: Sequence[int]) -> dict[str, list[float]] | None:
    """Each learned-reward kind's follow metric per seed; None if an agent lacks it."""
    from pokerirl.agents.train import read_metrics

    found = {
        kind: [read_metrics(out / f"seed-{s}")[-1].follows_reward for s in seeds]
        for kind, out in sets.items() if kind != "dqn"
    }  # fmt: skip
    if any(v is None for values in found.values() for v in values):
        return None
    return {kind: [float(v) for v in values if v is not None] for kind, values in found.items()}


def _curve(agent_set: Path, seeds: Sequence[int]) -> Curve:
    from pokerirl.agents.train import read_metrics

    lines = [read_metrics(agent_set / f"seed-{s}") for s in seeds]
    points = min(len(line) for line in lines)
    values = [[line[i].eval["random"].mbb_per_hand for i in range(points)] for line in lines]
    return Curve.of(values, timesteps=[lines[0][i].hands for i in range(points)])


def _playing_vs_random(agent_set: Path, seeds: Sequence[int]) -> list[float]:
    """Each seed's playing checkpoint against random, over duplicate hands (the authors'
    preset plays its kept model, which its last evaluation did not see)."""
    from pokerirl.agents import resolve_agent
    from pokerirl.agents.train import TrainConfig
    from pokerirl.game import make_agent, play_match

    return [
        play_match(resolve_agent(str(agent_set / f"seed-{s}")), make_agent("random"),
                   hands=PLAYING_HANDS, seed=TrainConfig.eval_seed).mbb_per_hand
        for s in seeds
    ]  # fmt: skip


def agents_stage(study: Study, irl: IRLResult) -> AgentsResult:
    """Every agent kind's seeds (units of ``agents.train``), learned-reward seed s on IRL run
    s mod runs of ``irl``'s algorithm; then their results against random, read again."""
    from pokerirl.agents.train import TrainConfig, agent_preset
    from pokerirl.game import make_agent, play_match

    config = study.config
    folder = study.root / "agents"
    sets = {kind: folder / AGENT_FOLDERS[kind] for kind in config.kinds}
    short = folder / SHORT_DQN
    short_is_long = config.short_agent_hands == config.agent_hands
    # The authors' evaluations are 1,000 games; the references are measured as the agents are.
    authors = config.agent_preset == "authors"
    reference_hands = PLAYING_HANDS if authors else config.eval_hands

    def train(out: Path, hands: int, algo: str | None) -> None:
        base = agent_preset(
            config.agent_preset,
            hands=hands,
            seed=config.seeds[0],
            eval_every=min(config.eval_every, hands),
            eval_hands=config.eval_hands,
            encoding=config.encoding,
            opponent=config.opponent,
        )
        if algo is None:
            study.execution.train_seeds(out, base, config.seeds)
            return
        learned = replace(base, reward="learned", reward_transform=config.reward_transform,
                          payoff_weight=config.payoff_weight)  # fmt: skip
        source = config.reward_source(algo)
        if source is not None:
            study.execution.train_seeds(out, replace(learned, reward_run=source), config.seeds)
            return
        runs = run_paths(study.root / "irl" / algo, config.runs)
        # Seed s learns from IRL run s mod runs: one call per run, its seeds side by side.
        for k, run in enumerate(runs):
            group = [s for s in config.seeds if s % config.runs == k]
            if group:
                study.execution.train_seeds(out, replace(learned, reward_run=str(run)), group)

    study.step("agents")
    for kind, out in sets.items():
        algo = None if kind == "dqn" else kind.removesuffix("_dqn")
        study.say(
            f"      {kind}: {len(config.seeds)} seeds x {config.agent_hands:,} hands -> {out}"
        )
        train(out, config.agent_hands, algo)
    if not short_is_long:
        study.say(
            f"      dqn (short): {len(config.seeds)} seeds x {config.short_agent_hands:,} hands"
        )
        train(short, config.short_agent_hands, None)
    references = {}
    for name in ("call", "raise"):
        result = play_match(
            make_agent(name), make_agent("random"), hands=reference_hands,
            seed=TrainConfig.eval_seed,
        )  # fmt: skip
        references[name] = Reference(mbb_per_hand=result.mbb_per_hand, std_error=result.std_error)
    return AgentsResult(
        final_vs_random={
            kind: _final_vs_random(out, config.seeds) for kind, out in sets.items()
        },
        curves={kind: _curve(out, config.seeds) for kind, out in sets.items()},
        training_length=TrainingLength(
            agent_hands=config.agent_hands,
            short_agent_hands=config.short_agent_hands,
            long=_final_vs_random(sets["dqn"], config.seeds),
            short=_final_vs_random(sets["dqn"] if short_is_long else short, config.seeds),
        ),
        references=references,
        follows_reward=_follows_reward(sets, config.seeds),
        playing_vs_random={
            kind: _playing_vs_random(out, config.seeds) for kind, out in sets.items()
        } if authors else None,
        playing_hands=PLAYING_HANDS if authors else None,
    )  # fmt: skip


def _comparisons(report: TournamentReport) -> list[tuple[Any, Any]]:
    """Each matchup with its comparison: the study gives one spec per side (an agent set or a
    built-in), so each matchup is one comparison, whose test is the verdict (across training
    seeds where a side has several agents)."""
    return [(report.matchups[c.matchups[0]], c) for c in report.comparisons]


def _table1_line(matchup: Any, comparison: Any) -> Table1Line:
    line = comparison.line
    return Table1Line(
        mbb_per_hand=line.mbb_per_hand,
        std_error=line.std_error,
        p_value=line.p_value,
        p_bonferroni=line.p_value_bonferroni,
        p_holm=line.p_value_holm,
        n=line.n,
        per_seed=[s.mbb_per_hand for s in matchup.seeds],
        seeds_significant_bonferroni=matchup.seeds_significant_bonferroni,
        replicated_over=str(comparison.replication),
        agents_a=comparison.agents_a,
        agents_b=comparison.agents_b,
        df=comparison.df,
        deal_std_error=comparison.deal_std_error,
    )


def tournament_stage(study: Study, agents: AgentsResult) -> dict[str, Table1Line]:
    """Table 1: each learned-reward DQN against the sparse one (``agents``: the stage before,
    whose units the tournament's seeds read)."""
    config = study.config
    folder = study.root / "agents"
    baseline = str(folder / AGENT_FOLDERS["dqn"])
    kinds = config.table1_kinds
    study.step("tournament")
    report = study.execution.tournament(
        [(str(folder / AGENT_FOLDERS[name]), baseline) for name in kinds],
        hands=config.hands,
        seeds=config.seeds,
        out=study.root / "tournament",
        duplicate=config.duplicate,
    )
    return {
        f"{name}_vs_dqn": _table1_line(matchup, comparison)
        for name, (matchup, comparison) in zip(kinds, _comparisons(report), strict=True)
    }


def authors_stage(
    study: Study, agents: AgentsResult, tournament: dict[str, Table1Line]
) -> dict[str, AuthorsMatchup]:
    """The authors' tournament: for each experiment (seed) k, 50 x 1,000 non-duplicate games
    of each learned-reward DQN against the sparse one, seats drawn per game. Each matchup's
    result is the tournaments layer's own (:class:`~pokerirl.tournaments.AuthorsMatchup`), with
    every repeat."""
    config = study.config
    folder = study.root / "agents"
    baseline = str(folder / AGENT_FOLDERS["dqn"])
    names = [f"{name}_vs_dqn" for name in config.table1_kinds]
    study.step("authors")
    return study.execution.authors_tournament(
        [(str(folder / AGENT_FOLDERS[name]), baseline) for name in config.table1_kinds],
        names=names,
        experiments=config.seeds,
        repeats=config.authors_repeats,
        games=config.authors_games,
        out=study.root / "authors",
        duplicate={name: tournament[name].mbb_per_hand for name in names},
    )


def reward_cards(root: Path, config: StudyConfig) -> dict[str, CardSummary | None]:
    """Each algorithm's reward cards (its runs' ``reward_card.json``), summarized over runs;
    None for an algorithm without cards (runs of an older pokerirl, or a table without
    cards)."""
    from pokerirl.poker.reward_card import CARD_FIGURE, card_summary, read_card

    found: dict[str, CardSummary | None] = {}
    for algo in config.algos:
        out = root / "irl" / algo
        folders = [out] if config.reward_source(algo) else run_paths(out, config.runs)
        cards = [card for folder in folders if (card := read_card(folder)) is not None]
        found[algo] = None
        if cards:
            figure = (folders[0] / CARD_FIGURE).relative_to(root)
            found[algo] = CardSummary.from_json({**card_summary(cards), "figure": str(figure)})
    return found


def panel_agents(root: Path, config: StudyConfig) -> list[tuple[str, str]]:
    """(name, spec) of every panel member: the agent kinds, then the built-ins."""
    kinds = [(kind, str(root / "agents" / AGENT_FOLDERS[kind])) for kind in config.kinds]
    return kinds + [(name, name) for name in BUILT_INS]


def panel_stage(study: Study, agents: AgentsResult) -> Panel:
    """Every panel member against every other, once per pair."""
    config = study.config
    members = panel_agents(study.root, config)
    study.step("panel")
    pairs = [(i, j) for i in range(len(members)) for j in range(i + 1, len(members))]
    report = study.execution.tournament(
        [(members[i][1], members[j][1]) for i, j in pairs],
        hands=config.panel_hands,
        seeds=config.seeds,
        out=study.root / "panel" / "tournament",
        duplicate=config.duplicate,
    )
    size = len(members)
    mbb: list[list[float | None]] = [[None] * size for _ in range(size)]
    se: list[list[float | None]] = [[None] * size for _ in range(size)]
    unit: list[list[str | None]] = [[None] * size for _ in range(size)]
    for (i, j), (_, comparison) in zip(pairs, _comparisons(report), strict=True):
        line = comparison.line  # across training seeds where a side has several agents
        mbb[i][j], mbb[j][i] = line.mbb_per_hand, -line.mbb_per_hand
        se[i][j] = se[j][i] = line.std_error
        unit[i][j] = unit[j][i] = str(comparison.replication)
    lbr = lbr_panel(study, members)
    return Panel(agents=[name for name, _ in members], mbb_per_hand=mbb, std_error=se,
                 lbr_mbb_per_hand=[m for m, _ in lbr],
                 lbr_std_error=[e for _, e in lbr], replicated_over=unit)  # fmt: skip


def lbr_panel(
    study: Study, members: list[tuple[str, str]]
) -> list[tuple[float | None, float | None]]:
    """LBR against each member on every seed, all in one fan-out (a run is one unit: run one
    by one they would leave all workers but one idle; resumable units under
    ``panel/lbr/NAME/seed-S``): per member, the mean of the seeds' win rates and its SE from
    theirs (equal hands per seed)."""
    from pokerirl.tournaments.exploit import ExploitConfig, LBRRun, run_lbr_many
    from pokerirl.tournaments.lbr import LBRSettings, parse_street
    from pokerirl.tournaments.lineup import agent_spec_for_seed

    hands, seeds = study.config.lbr_hands, study.config.seeds
    if not hands:
        return [(None, None)] * len(members)
    for name, _ in members:
        study.say(f"      LBR against {name}: {hands:,} hands x {len(seeds)} seeds")
    settings = LBRSettings(check_until=parse_street(LBR_CHECK_UNTIL))
    runs = [
        LBRRun(spec=agent_spec_for_seed(spec, seed),
               config=ExploitConfig(hands=hands, seed=seed, lbr=settings),
               out=study.root / "panel" / "lbr" / name / f"seed-{seed}")
        for name, spec in members
        for seed in seeds
    ]  # fmt: skip
    reports = run_lbr_many(runs, backend=study.execution.backend, overwrite=study.overwrite,
                           progress=study.execution.progress)  # fmt: skip
    pooled: list[tuple[float | None, float | None]] = []
    for first in range(0, len(reports), len(seeds)):
        found = reports[first : first + len(seeds)]
        mean = sum(r.lbr_mbb_per_hand for r in found) / len(found)
        error = math.sqrt(sum(r.lbr_std_error**2 for r in found)) / len(found)
        pooled.append((mean, error))
    return pooled
