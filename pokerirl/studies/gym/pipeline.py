"""The paper's Gymnasium study in one call: :func:`run_gym_study` (``pokerirl gym study``).

For every task: the shipped expert's data -> IRL (AIRL and H-AIRL, ``runs`` runs each, in
lock-step) -> RL (SB3 on the env reward, on each AIRL run's reward and on each H-AIRL run's
reward; RL run k uses seed ``seed + k`` and IRL run k) -> ``summary.json``, figures and
``report.md`` beside the authors' final values.

One task writes into ``out`` itself; several write ``out/<env>/`` each (the same layout) and
``out/summary.json`` and ``out/report.md`` over all of them::

    expert.parquet, expert.unit.json     the expert data and its record
    irl/airl/, irl/hairl/                gym irl folders (run-<k>, summary.json, figures)
    rl/env/, rl/airl/, rl/hairl/         run-<k>: gym rl run folders (metrics.jsonl, ...)
    figures/irl_returns.png              IRL-phase return, mean ± std over runs (Figure 1)
    figures/alignment.png                validation alignment, discrete tasks (Figure 2)
    figures/rl_returns.png               RL-phase true return (Figure 3)
    figures/reward_map.png               f's preferred action over the states (Figure 4;
                                         2-d observations and discrete actions: MountainCar)
    summary.json, report.md

Every unit (data, IRL, RL run) is resumable on its own (:mod:`pokerirl.studies.gym.units`): a rerun
keeps the finished ones and refuses, in one line, units made with other settings unless
``overwrite``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pokerirl.atomic import write_text
from pokerirl.errors import PokerIRLError
from pokerirl.execution import Backend
from pokerirl.gym.irl import GymIRLSummary
from pokerirl.gym.quality import has_true_reward
from pokerirl.gym.rl import DEFAULT_RL_BACKEND, RLBackend, read_curve
from pokerirl.gym.tasks import task
from pokerirl.irl.config import IRLMode
from pokerirl.irl.metrics import Metric
from pokerirl.irl.run import read_epochs
from pokerirl.meanstd import Curve, MeanStd, mean_std
from pokerirl.studies.common import (
    REPORT_MD,
    SUMMARY_JSON,
    StudyError,
    study_folder,
)
from pokerirl.studies.gym.config import StudyPreset, authors_budget, task_root
from pokerirl.studies.gym.figures import LABELS, draw_figures, draw_reward_map
from pokerirl.studies.gym.report import (
    SUMMARY_FORMAT,
    GymStudySummary,
    render_report,
)
from pokerirl.studies.gym.results import (
    AlgoCurves,
    AlgoSummary,
    EnvRewardSummary,
    PaperFinals,
    RLCurve,
    StudySettings,
    TaskSummary,
)
from pokerirl.studies.gym.units import (
    DATA_FILE,
    DataJob,
    IRLJob,
    RLJob,
    Say,
    run_data_jobs,
    run_irl_jobs,
    run_rl_jobs,
)

if TYPE_CHECKING:  # torch: loaded only for an online study
    from pokerirl.gym.online import OnlineSettings

STEPS = 4


@dataclass(frozen=True, kw_only=True)
class GymStudyResult:
    """What :func:`run_gym_study` wrote: one summary per task, and the report."""

    out: Path
    summaries: dict[str, TaskSummary]  # env -> the task's summary.json
    markdown: str


# --------------------------------------------------------------------------- the jobs


def data_job(root: Path, env: str, preset: StudyPreset, *, expert: Path | None = None) -> DataJob:
    """The expert data: from the shipped expert, or (``expert``) from an expert folder."""
    transitions = preset.irl(env).transitions
    return DataJob(
        env=env, transitions=transitions, seed=preset.seed, path=root / DATA_FILE, expert=expert
    )


def irl_job(
    root: Path, env: str, algo: str, preset: StudyPreset, *, data: Path, **settings: Any
) -> IRLJob:
    """``algo``'s runs on ``data`` into ``root/irl/<algo>``; ``settings`` override the preset's."""
    return IRLJob(
        env=env,
        algo=algo,
        runs=preset.runs,
        settings=replace(preset.irl(env), **settings),
        seed=preset.seed,
        data=data,
        folder=root / "irl" / algo,
    )


def rl_jobs(
    root: Path,
    env: str,
    reward: str,
    irl: IRLJob | None,
    preset: StudyPreset,
    *,
    backend: str = RLBackend.SB3,
) -> list[RLJob]:
    """RL run k on the env reward (``irl`` None) or on ``irl``'s run k, seed ``seed + k``,
    trained by the RL ``backend`` (lockstep: the unfinished runs of ``rl/<reward>`` as one
    group; each run folder keeps its own record either way)."""
    return [
        RLJob(
            env=env,
            reward=reward,
            reward_run=None if irl is None else irl.run(k),
            seed=preset.seed + k,
            settings=preset.rl(env),
            evaluations=preset.rl_evaluations,
            eval_episodes=preset.irl(env).eval_episodes,
            folder=root / "rl" / reward / f"run-{k}",
            backend=backend,
        )
        for k in range(preset.runs)
    ]


# --------------------------------------------------------------------------- the study


def run_gym_study(
    out: str | os.PathLike[str],
    preset: StudyPreset,
    *,
    backend: Backend | None = None,
    overwrite: bool = False,
    progress: bool = False,
    say: Say = lambda message: None,
    rl_backend: str = DEFAULT_RL_BACKEND,
    expert: str | os.PathLike[str] | None = None,
    online: OnlineSettings | None = None,
) -> GymStudyResult:
    """Run (or resume) the study of ``preset.tasks`` into ``out``; ``say`` hears a line per step.

    The IRL stage trains offline (the paper's), or with ``online`` online
    (:func:`pokerirl.gym.online.train_gym_online`, a PPO generator in the env); every later
    stage reads its runs alike. The mode is part of the IRL units' records: a folder made in
    the other mode is refused (or, with ``overwrite``, recomputed).

    The expert data comes from the shipped expert, or from the expert folder ``expert`` (one
    task only; needed for a task the paper does not have, which ships none).

    Units run on ``backend`` (default: this process); results do not depend on it. The RL
    runs train with ``rl_backend`` (``pokerirl.gym.rl.RL_BACKENDS``; sb3, one unit per run, or
    lockstep, one unit per task and reward kind), which is part of their records.

    Raises:
        StudyError: ``out`` is a file, or a unit was made with other settings or inputs
            (without ``overwrite``); the message names it.
    """
    from pokerirl.gym.envs import require_gym
    from pokerirl.gym.expert_policies import read_expert_record

    require_gym()
    check_rl_backend(rl_backend)
    tasks = preset.tasks
    expert_dir = None if expert is None else Path(expert)
    if expert_dir is not None and len(tasks) > 1:
        raise StudyError("an expert folder is for one task; give one task, not several")
    if expert_dir is not None:  # the user's folder, named here: the unit reads a scratch copy
        trained_for = read_expert_record(expert_dir)["env"]
        if trained_for != tasks[0]:
            raise StudyError(f"{expert_dir}: the expert is for {trained_for}, not {tasks[0]}")
    generic = [env for env in tasks if task(env).generic]
    if generic and expert_dir is None:
        raise StudyError(
            f"no shipped expert for {generic[0]!r} (only the paper's tasks ship one): train one "
            f"with `pokerirl gym expert {generic[0]}` and give its folder"
        )
    backend = backend or Backend()
    out = study_folder(out)
    roots = {env: task_root(out, env, tasks) for env in tasks}
    names = ", ".join(tasks)
    options: dict[str, Any] = {"backend": backend, "overwrite": overwrite, "progress": progress}
    try:
        data = [data_job(roots[env], env, preset, expert=expert_dir) for env in tasks]
        say(f"[1/{STEPS}] expert data: {names}")
        reused = run_data_jobs(data, **options)
        _said_reused(say, reused, len(data))

        irl = {
            (env, algo): replace(
                irl_job(roots[env], env, algo, preset, data=roots[env] / DATA_FILE),
                online=online,  # None: offline
            )
            for env in tasks
            for algo in preset.algos
        }
        mode = "" if online is None else f" (online, {online.rounds} rounds)"
        say(f"[2/{STEPS}] IRL{mode}: {_and(preset.algos)}, {preset.runs} runs each, on {names}")
        reused = run_irl_jobs(list(irl.values()), **options)
        _said_reused(say, reused, len(irl))

        rl = [
            job
            for env in tasks
            for reward in preset.rewards()
            for job in rl_jobs(roots[env], env, reward, irl.get((env, reward)), preset,
                               backend=rl_backend)
        ]
        say(f"[3/{STEPS}] RL: env reward, {_and(preset.algos)} rewards, {preset.runs} runs each"
            + ("" if rl_backend == RLBackend.SB3 else f" ({rl_backend} backend)"))
        reused = run_rl_jobs(rl, **options)
        _said_reused(say, reused, len(rl))
    except PokerIRLError:
        raise  # a unit's conflict keeps its remedy for the command line's advice
    except ValueError as error:
        raise StudyError(str(error)) from None

    report = out / REPORT_MD
    say(f"[4/{STEPS}] report -> {report}")
    summaries = {}
    for env in tasks:
        summary = task_summary(roots[env], env, preset, rl_backend=rl_backend, online=online)
        write_text(roots[env] / SUMMARY_JSON, json.dumps(summary.to_json(), indent=2) + "\n")
        draw_figures(roots[env], summary)
        if len(tasks) > 1:
            write_text(roots[env] / REPORT_MD, render_report({env: summary}, preset.name))
        summaries[env] = summary
    overall = GymStudySummary(
        preset=preset.name, runs=preset.runs, tasks=summaries, several=len(tasks) > 1
    )
    if overall.several:
        write_text(out / SUMMARY_JSON, json.dumps(overall.to_json(), indent=2) + "\n")
    markdown = overall.render()
    write_text(report, markdown)
    return GymStudyResult(out=out, summaries=summaries, markdown=markdown)


def check_rl_backend(rl_backend: str) -> None:
    """Refuse an unknown RL backend before any work."""
    from pokerirl.gym.rl import RL_BACKENDS

    if rl_backend not in RL_BACKENDS:
        raise StudyError(
            f"unknown RL backend {rl_backend!r}; choose one of {', '.join(RL_BACKENDS)}"
        )


def _and(algos: Sequence[str]) -> str:
    """``AIRL and H-AIRL``, ``AIRL, H-AIRL and GAIL``."""
    labels = [LABELS[algo] for algo in algos]
    return ", ".join(labels[:-1]) + " and " + labels[-1]


def _said_reused(say: Say, reused: int, total: int) -> None:
    if reused:
        say(f"      {reused} of {total} finished already, reused")


# --------------------------------------------------------------------------- summaries


@dataclass(frozen=True, kw_only=True)
class RLCurves:
    """One reward kind's RL runs: the true return at each evaluation (mean and std over runs)
    and each run's last value."""

    curve: Curve  # as summary.json holds it (curves.rl)
    per_run_final: list[float]


def rl_curves(root: Path, reward: str, runs: int) -> RLCurves:
    """The RL runs' true-return curves: timesteps, per-run values, mean and std per point."""
    curves = [read_curve(root / "rl" / reward / f"run-{k}") for k in range(runs)]
    points = min(len(curve) for curve in curves)
    values = np.array([[p.return_mean for p in curve[:points]] for curve in curves])
    return RLCurves(
        curve=Curve.of(values, timesteps=[p.timesteps for p in curves[0][:points]]),
        per_run_final=values[:, -1].tolist(),
    )


def task_summary(
    root: Path,
    env: str,
    preset: StudyPreset,
    *,
    rl_backend: str = DEFAULT_RL_BACKEND,
    online: OnlineSettings | None = None,
) -> TaskSummary:
    """The task's ``summary.json``: final values (mean ± std over runs) of every phase, the
    curves behind the figures, the baselines, the settings, and the authors' finals; with the
    reward map drawn (Figure 4) where the task has one; a task the paper does not have has
    no authors' finals and (no true reward known) no reward quality."""
    found_task = task(env)
    algos: dict[str, AlgoSummary] = {}
    irl_summaries = {}
    for algo in preset.algos:
        irl = GymIRLSummary.read(root / "irl" / algo)
        irl_summaries[algo] = irl
        metrics = irl.over_runs.metrics
        rl = rl_curves(root, algo, preset.runs)
        algos[algo] = AlgoSummary(
            irl_final_return=irl.irl_final_return,
            rl_final_return=mean_std(rl.per_run_final),
            baselines=dict(irl.over_runs.baselines),
            irl_per_run_final=_per_run_final(root / "irl" / algo, preset.runs),
            rl_per_run_final=rl.per_run_final,
            curves=AlgoCurves(
                irl_epochs=list(irl.over_runs.epochs),
                irl_return=Metric.EVAL_RETURN.of(metrics),
                rl=rl.curve,
                alignment=Metric.VAL_ALIGNMENT.of(metrics)
                if found_task.discrete
                else None,
            ),
            final_alignment=irl.final_alignment if found_task.discrete else None,
            final_reward_alignment=_last(Metric.VAL_REWARD_ALIGNMENT.of(metrics))
            if found_task.discrete
            else None,
            final_disc_acc_expert=_last_of(metrics, Metric.DISC_ACC_EXPERT),
            final_disc_acc_policy=_last_of(metrics, Metric.DISC_ACC_POLICY),
            **(reward_quality(root, env, algo, preset.runs) if has_true_reward(env) else {}),
        )
    env_rl = rl_curves(root, "env", preset.runs)
    baselines = irl_summaries["hairl"].over_runs.baselines
    paper = found_task.paper
    return TaskSummary(
        format=SUMMARY_FORMAT,
        env=env,
        preset=preset.name,
        runs=preset.runs,
        seeds=[preset.seed + k for k in range(preset.runs)],
        discrete=found_task.discrete,
        expert_return=irl_summaries["hairl"].expert_return,
        random_return=baselines["random"].measured[0],
        algos=algos,
        env_reward=EnvRewardSummary(
            rl_final_return=mean_std(env_rl.per_run_final),
            rl_per_run_final=env_rl.per_run_final,
            curves=RLCurve(rl=env_rl.curve),
        ),
        settings=StudySettings(  # through JSON: tuples become lists, as in summary.json
            irl=json.loads(json.dumps(asdict(preset.irl(env)))),
            rl=json.loads(json.dumps(asdict(preset.rl(env)))),
            rl_evaluations=preset.rl_evaluations,
            rl_eval_episodes=preset.irl(env).eval_episodes,
            seed=preset.seed,
            authors_budget=authors_budget(env, preset),
            rl_backend=rl_backend,
            mode=None if online is None else IRLMode.ONLINE.value,
            online=None if online is None else online_record(online),
        ),
        paper=None
        if paper is None
        else PaperFinals(
            irl_final_return={"airl": paper.irl_airl, "hairl": paper.irl_hairl},
            expert_return=paper.irl_expert.mean,
            rl_final_return={
                "airl": paper.rl_airl,
                "hairl": paper.rl_hairl,
                "env_reward": paper.rl_env_reward,
            },
            final_alignment={"airl": paper.alignment_airl, "hairl": paper.alignment_hairl}
            if found_task.discrete
            else None,
            random_return=found_task.random_return,
        ),
        reward_map=draw_reward_map(root, env, preset.algos),
    )


def online_record(online: OnlineSettings) -> dict[str, Any]:
    """What a summary says of an online study's generator: the settings its command takes
    (each run's config.json records the rest: PPO's, the initial log-std)."""
    return {"rounds": online.rounds, "generator_steps": online.generator_steps,
            "envs": online.envs}  # fmt: skip


def _last(curve: Curve) -> MeanStd:
    """A per-epoch curve's last point."""
    return MeanStd(mean=curve.mean[-1], std=curve.std[-1])


def _last_of(metrics: Mapping[str, Curve], metric: Metric) -> MeanStd | None:
    """The last point of the runs' ``metric`` curve; None where they lack it (older runs)."""
    curve = metric.of(metrics, None)
    return None if curve is None else _last(curve)


def reward_quality(root: Path, env: str, algo: str, runs: int) -> dict[str, Any]:
    """:class:`AlgoSummary`'s ``quality`` (by score) and ``reward_quality`` (per run, γ,
    coverage, the true reward)."""
    # Mean and std over runs of each IRL run's ``reward_quality.json`` (computed there first
    # when a run lacks it, e.g. one made before it existed); a value null in a run (a constant
    # reward) is left out of its mean.
    from pokerirl.gym.quality import SCORES, run_quality

    found = [
        run_quality(root / "irl" / algo / f"run-{k}", env_id=env, data_path=root / DATA_FILE)
        for k in range(runs)
    ]
    quality = {}
    for key in SCORES:
        values = [q[key] for q in found if q.get(key) is not None]
        quality[key] = mean_std(values) if values else MeanStd(mean=None)
    return {
        "quality": quality,
        "reward_quality": {
            "per_run": {key: [q.get(key) for q in found] for key in SCORES},
            "gamma": found[0]["gamma"],
            "coverage": found[0]["coverage"],
            "true_reward": found[0]["true_reward"],
        },
    }


def _per_run_final(folder: Path, runs: int) -> list[float]:
    """Each run's last evaluation return."""
    return [Metric.EVAL_RETURN.of(read_epochs(folder / f"run-{k}")[-1]) for k in range(runs)]


