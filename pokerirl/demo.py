"""The whole study on built-in synthetic data, small enough for a few minutes on a CPU.

1. ``synth``: a month of heads-up 10-20 hands between two scripted players, in IRC format;
2. ``ingest``: the expert state-action table;
3. ``train``: H-AIRL and AIRL reward runs;
4. ``agent train``: DQN agents on the sparse payoff and on each learned reward, one per seed;
5. ``tournament``: each reward-shaped DQN against the sparse-reward DQN, over the seeds.

Each step's output is a folder of ``out`` that the matching CLI command could have written.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pokerirl.agents.train import TrainConfig, train_seeds
from pokerirl.datasets.ingest import ingest
from pokerirl.game.synth import write_synthetic_month
from pokerirl.irl import load_config, train_table
from pokerirl.tournaments import TournamentReport, run_tournament

REWARD_ALGOS = ("hairl", "airl")
BASELINE = "dqn"


@dataclass(frozen=True, kw_only=True)
class DemoConfig:
    """Sizes of the demo; the defaults finish in a couple of minutes on two cores."""

    synthetic_hands: int = 20_000
    irl_epochs: int = 10
    agent_hands: int = 30_000
    agent_seeds: tuple[int, ...] = (0, 1, 2)
    tournament_hands: int = 100_000
    jobs: int = 2
    seed: int = 0


@dataclass(frozen=True)
class DemoResult:
    table: Path
    ingest_summary: dict[str, Any]
    reward_runs: dict[str, Path]
    irl_alignment: dict[str, tuple[float, float]]  # algo -> (validation, majority baseline)
    agent_sets: dict[str, Path]
    report_dir: Path
    report: TournamentReport


def run_demo(
    out: str | os.PathLike[str],
    config: DemoConfig = DemoConfig(),
    *,
    say: Callable[[str], None] = lambda message: None,
    progress: bool = False,
) -> DemoResult:
    """Run the five steps into ``out``; ``say`` hears one line as each step starts."""
    root = Path(out)
    root.mkdir(parents=True, exist_ok=True)

    say(f"[1/5] synth: {config.synthetic_hands:,} heads-up hands, seed {config.seed}")
    month = write_synthetic_month(root / "irc", hands=config.synthetic_hands, seed=config.seed)

    table = root / "expert.parquet"
    say(f"[2/5] ingest: {month} -> {table}")
    summary = ingest([month], table, progress=progress)

    reward_runs: dict[str, Path] = {}
    alignment: dict[str, tuple[float, float]] = {}
    for algo in REWARD_ALGOS:
        run_dir = root / "runs" / algo
        say(f"[3/5] train {algo}: {config.irl_epochs} epochs -> {run_dir}")
        settings = load_config(algo, overrides={"epochs": config.irl_epochs, "seed": config.seed})
        result = train_table(
            table, run_dir, algo=algo, config=settings, progress=progress, overwrite=True
        )
        alignment[algo] = (result.metrics[-1]["val_alignment"], result.baselines["majority"])
        reward_runs[algo] = run_dir

    agent_sets: dict[str, Path] = {}
    seeds = list(config.agent_seeds)
    rewards: dict[str, str | None] = {BASELINE: None}
    rewards.update({f"{algo}-{BASELINE}": str(path) for algo, path in reward_runs.items()})
    for name, reward_run in rewards.items():
        agent_set = root / "agents" / name
        say(
            f"[4/5] agent train {name}: {len(seeds)} seeds x {config.agent_hands:,} hands "
            f"-> {agent_set}"
        )
        train_config = TrainConfig(
            hands=config.agent_hands,
            seed=seeds[0],
            reward="sparse" if reward_run is None else "learned",
            reward_run=reward_run,
            eval_every=config.agent_hands,
        )
        train_seeds(agent_set, train_config, seeds, jobs=config.jobs, progress=progress)
        agent_sets[name] = agent_set

    report_dir = root / "report"
    baseline = str(agent_sets[BASELINE])
    matchups = [(str(path), baseline) for name, path in agent_sets.items() if name != BASELINE]
    say(
        f"[5/5] tournament: {len(matchups)} matchups x {len(seeds)} seeds x "
        f"{config.tournament_hands:,} hands -> {report_dir}"
    )
    report = run_tournament(
        matchups,
        hands=config.tournament_hands,
        seeds=seeds,
        out=report_dir,
        jobs=config.jobs,
        progress=progress,
    )
    return DemoResult(
        table=table,
        ingest_summary=summary,
        reward_runs=reward_runs,
        irl_alignment=alignment,
        agent_sets=agent_sets,
        report_dir=report_dir,
        report=report,
    )
