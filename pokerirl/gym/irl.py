"""The IRL phase on a Gymnasium task: AIRL or H-AIRL runs in lock-step on expert rollouts,
each epoch's policy evaluated in the real environment.

``train_gym_irl`` writes into ``out``:

- ``run-<k>``: one IRL run folder per seed ``seed + k`` (the core's convention, see
  :mod:`pokerirl.irl.run`: ``reward.pt``, ``policy.pt``, ``config.json``, ``metrics.jsonl``,
  ``baselines.json``, ``split.json``, curves), readable by :func:`pokerirl.irl.load_reward`;
  each epoch's metrics add ``eval_return`` and ``eval_return_std`` (deterministic policy:
  argmax for discrete actions, the mean action clipped to the box for continuous ones;
  evaluation episode k starts from ``reset(seed=EVAL_SEED + k)``);
- ``summary.json``: mean and std over runs per metric per epoch (:func:`pokerirl.irl.run.summarize`)
  plus ``env``, ``algo``, ``expert_return``, ``irl_final_return`` and, for discrete tasks,
  ``final_alignment``;
- ``returns_bands.png`` (mean ± std of the return, the expert's and a random policy's
  returns as lines) and, for discrete tasks, ``alignment_bands.png``.

Baselines are the core's (``majority``, ``legal_majority``, ``bc``) plus ``random`` (a
uniformly random policy's return on the evaluation episodes) and ``expert`` (the expert's
return, measured once: from the data's complete episodes, else the shipped manifest).
"""

from __future__ import annotations

import functools
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.atomic import make_shareable, write_text
from pokerirl.errors import ConfigError, InputError, Remedy
from pokerirl.gym.envs import make_env
from pokerirl.gym.episodes import play_episodes, policy_actions, random_return
from pokerirl.gym.manifest import shipped_experts
from pokerirl.gym.presets import IRLSettings
from pokerirl.gym.quality import has_true_reward, write_reward_quality
from pokerirl.gym.tasks import task
from pokerirl.irl.config import AIRLConfig, Algo, NoiseSchedule
from pokerirl.irl.metrics import Metric
from pokerirl.irl.plots import new_figure, plot_bands, save_figure
from pokerirl.irl.records import EpochRecord
from pokerirl.irl.run import (
    SUMMARY_FILE,
    ObsMap,
    RunError,
    RunHooks,
    RunResult,
    RunsSummary,
    summarize,
    train_runs_into,
)
from pokerirl.irl.run import TRAINED_SHARE as TRAINED_SHARE  # importable here as before
from pokerirl.irl.transitions import Transitions
from pokerirl.jsonio import read_json
from pokerirl.meanstd import MeanStd
from pokerirl.serial import Omit, Serializable, meta
from pokerirl.store import staged_files, tidy

RETURNS_FILE = "returns_bands.png"
STAGE_KEY = "irl"  # the staged write's hidden folders in OUT: .irl.new-*, .irl.swap-*


@dataclass(frozen=True, kw_only=True)
class GymIRLSummary(Serializable):
    """A ``gym irl`` folder's ``summary.json``: the runs summarized (:class:`RunsSummary`, its
    keys beside these), the expert's return, and the last epoch's mean and std over runs of
    the evaluation return and (discrete tasks) the validation alignment."""

    env: str
    algo: str
    expert_return: float
    irl_final_return: MeanStd
    final_alignment: MeanStd | None = field(  # discrete tasks only
        default=None, metadata=meta(omit=Omit.NONE)
    )
    over_runs: RunsSummary = field(metadata=meta(flatten=True))

    @classmethod
    def read(cls, folder: Path) -> GymIRLSummary:
        """The ``summary.json`` of the ``gym irl`` folder ``folder``."""
        return cls.from_json(read_json(folder / SUMMARY_FILE))


@dataclass(frozen=True, kw_only=True)
class GymIRLResult:
    """What :func:`train_gym_irl` wrote: the summary and the headline finals."""

    out: Path
    runs: int
    summary: GymIRLSummary
    baselines: dict[str, float]

    @property
    def final_return(self) -> MeanStd:
        return self.summary.irl_final_return

    @property
    def final_alignment(self) -> MeanStd | None:
        return self.summary.final_alignment


def irl_config(algo: str, settings: IRLSettings, *, seed: int) -> AIRLConfig:
    """The task's IRL settings as an :class:`AIRLConfig`: nets, epochs, one learning rate for
    both nets, batch, the reward's weight decay, the log σ floor, the authors' noise schedule
    with decay k; α, β, σ, the noise and supervised forms for H-AIRL only (``airl`` and
    ``gail`` keep α = β = 0 and no noise)."""
    overrides: dict[str, Any] = {
        "policy_hidden": settings.policy_hidden,
        "reward_hidden": settings.reward_hidden,
        "epochs": settings.epochs,
        "reward_lr": settings.learning_rate,
        "policy_lr": settings.learning_rate,
        "reward_weight_decay": settings.reward_weight_decay,
        "batch_size": settings.batch_size,
        "noise_schedule": NoiseSchedule.AUTHORS,
        "noise_decay": settings.sigma_decay,
        "log_std_min": settings.log_std_min,
        "seed": seed,
    }
    if algo == Algo.HAIRL:
        overrides.update(
            alpha=settings.alpha,
            beta=settings.beta,
            sigma_start=settings.sigma_start,
            sigma_end=settings.sigma_end,
            noise_form=settings.noise_form,
            supervised_form=settings.supervised_form,
        )
    return AIRLConfig.for_algo(algo, **overrides)


def load_env_transitions(env_id: str, data_path: str | os.PathLike[str]) -> Transitions:
    """The expert Parquet as :class:`Transitions` with the *env's* action space: K from
    ``Discrete.n`` (not the largest action in the data), or the box's low and high."""
    env = make_env(env_id)
    try:
        space: Any = env.action_space  # Discrete (n) or Box (low, high)
        obs_space: Any = env.observation_space
    finally:
        env.close()
    if hasattr(space, "n"):
        data = Transitions.from_parquet(data_path)
        if not data.discrete:
            raise InputError(f"{data_path}: continuous actions, but {env_id} has discrete ones")
        if int(data.actions.max()) >= int(space.n) or int(data.actions.min()) < 0:
            raise InputError(f"{data_path}: action ids outside {env_id}'s 0..{int(space.n) - 1}")
        data = replace(data, num_actions=int(space.n))
    else:
        low, high = space.low.astype(float).tolist(), space.high.astype(float).tolist()
        data = Transitions.from_parquet(data_path, low=low, high=high)
        if data.discrete or data.action_dim != len(low):
            raise InputError(f"{data_path}: actions do not fit {env_id}'s box of {len(low)} dims")
    if data.obs_dim != int(np.prod(obs_space.shape)):
        raise InputError(
            f"{data_path}: observations have {data.obs_dim} dims, {env_id} has {obs_space.shape}"
        )
    return data


def obs_standardization(data: Transitions, *, enabled: bool = True) -> tuple[Tensor, Tensor]:
    """(shift, scale): the observations' mean and std (scale 1 where a dimension is constant);
    (0, 1) when not ``enabled``."""
    if not enabled:
        return torch.zeros(data.obs_dim), torch.ones(data.obs_dim)
    std = data.obs.std(dim=0)
    return data.obs.mean(dim=0), torch.where(std > 1e-6, std, torch.ones_like(std))


def standardized(data: Transitions, shift: Tensor, scale: Tensor) -> Transitions:
    """``data`` with obs and next_obs mapped to ``(x - shift) / scale``."""
    return ObsMap(shift=shift, scale=scale).rows(data)


def standardization(data: Transitions, *, enabled: bool) -> ObsMap:
    """The runs' :class:`~pokerirl.irl.run.ObsMap` (a :class:`~pokerirl.irl.run.RunHooks`
    ``obs_map``): :func:`obs_standardization` of the training rows, recorded in each run's
    ``config.json`` when ``enabled`` (None when not)."""
    shift, scale = obs_standardization(data, enabled=enabled)
    record = {"shift": shift.tolist(), "scale": scale.tolist()} if enabled else None
    return ObsMap(shift=shift, scale=scale, record=record)


# --------------------------------------------------------------------------- evaluation


@dataclass(frozen=True, kw_only=True)
class EnvReturns:
    """The runs' :class:`~pokerirl.irl.records.EpochCallback`: each policy's return in the
    environment after each epoch (``eval_return``, ``eval_return_std``), its observations
    mapped as the policy was trained (``obs_map``; None: as they come)."""

    obs_map: ObsMap | None
    env_id: str
    discrete: bool
    episodes: int

    def __call__(self, record: EpochRecord) -> list[Mapping[str, float]]:
        # The nets' parameters were written back: evaluate each policy in the env.
        extras: list[Mapping[str, float]] = []
        for policy in record.policies:
            was_training = policy.training
            policy.eval()
            (evaluation,) = play_episodes(
                self.env_id, functools.partial(self.actions, policy), episodes=self.episodes
            )
            policy.train(was_training)
            extras.append(
                {Metric.EVAL_RETURN: evaluation.mean, Metric.EVAL_RETURN_STD: evaluation.std}
            )
        return extras

    def actions(self, policy: nn.Module, obs: np.ndarray) -> np.ndarray:
        """:func:`policy_actions` of a policy trained on mapped observations."""
        mapped = obs if self.obs_map is None else self.obs_map.obs(obs)
        return policy_actions(policy, mapped, discrete=self.discrete)


def expert_return(env_id: str, data_path: str | os.PathLike[str]) -> float:
    """The expert's mean return over the data's complete episodes (ended by termination or
    time limit); the shipped manifest's when the data has none; NaN when neither exists."""
    import pyarrow.parquet as pq

    with open(data_path, "rb") as file:  # a file object: pyarrow cannot name non-UTF-8 paths
        table = pq.read_table(file)
    names = [n for n in ("reward", "episode", "done", "truncated") if n in table.column_names]
    columns = {n: table.column(n).to_numpy(zero_copy_only=False) for n in names}
    ended = columns["done"] | columns.get("truncated", np.zeros_like(columns["done"]))
    episodes = np.unique(columns["episode"][ended])
    if len(episodes):
        keep = np.isin(columns["episode"], episodes)
        sums = np.bincount(
            np.searchsorted(episodes, columns["episode"][keep]),
            weights=columns["reward"][keep].astype(float),
        )
        return float(sums.mean())
    try:
        entries = [e for e in shipped_experts() if e.env == env_id]
    except ValueError:
        entries = []
    return float(entries[0].return_mean) if entries else math.nan


# --------------------------------------------------------------------------- training


def train_gym_irl(
    env_id: str,
    data_path: str | os.PathLike[str],
    *,
    algo: str,
    runs: int,
    settings: IRLSettings | None = None,
    seed: int = 0,
    out: str | os.PathLike[str],
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
    data_label: str | os.PathLike[str] | None = None,
) -> GymIRLResult:
    """``runs`` IRL runs (seeds ``seed + k``) of ``algo`` on ``data_path`` in lock-step.

    ``settings`` default to the task's (the authors'); a preset's come from
    ``PRESETS[name].irl(env_id)``. ``out`` may already hold other files (the expert data);
    run folders and the summary are built in a hidden folder inside it and moved into place
    at the end, refusing to replace earlier results unless ``overwrite``. ``data_label`` is
    the data's path the run configs record (default ``data_path``; a worker that got the data
    as bytes names the driver's file, so the bytes do not depend on its scratch folder).
    """
    if runs < 1:
        raise ConfigError("runs must be at least 1")
    settings = settings or task(env_id).irl  # refuses an unknown id in one line
    out = Path(out)
    check_destination(out, runs=runs, overwrite=overwrite)
    config = irl_config(algo, settings, seed=seed)
    data = load_env_transitions(env_id, data_path)
    hooks = RunHooks(
        obs_map=functools.partial(standardization, enabled=settings.standardize_obs),
        baselines=lambda: {
            "random": random_return(env_id, episodes=settings.eval_episodes),
            "expert": expert_return(env_id, data_path),
        },
        callback=lambda obs_map: EnvReturns(
            obs_map=obs_map, env_id=env_id, discrete=data.discrete,
            episodes=settings.eval_episodes,
        ),
        # The learned reward against the true one (EPIC, Pearson): reward_quality.json, for a
        # task whose true reward is known (the paper's).
        finish=functools.partial(write_reward_quality, env_id=env_id, data_path=data_path)
        if has_true_reward(env_id)
        else None,
    )
    # Staged by the store: a kill leaves the earlier outputs or the new ones, never a mix, and
    # the next run removes what a dead one left (also an older version's .irl.XXXXXXXX.tmp).
    with staged_files(out, key=STAGE_KEY) as stage:
        make_shareable(stage)
        trained = train_runs_into(
            data, [stage / f"run-{k}" for k in range(runs)], algo=algo, config=config,
            hooks=hooks, device=device, progress=progress, data_path=data_label or data_path,
            data_lead={"env": env_id},
        )  # fmt: skip
        results = [replace(r, out=str(out / Path(r.out).name)) for r in trained.results]
        summary = write_summary(
            stage, env_id=env_id, algo=algo, results=results, expert=trained.baselines["expert"],
            drawn=trained.drawn if data.discrete else None,
        )  # fmt: skip
    return GymIRLResult(out=out, runs=runs, summary=summary, baselines=trained.baselines)


def check_destination(out: Path, *, runs: int, overwrite: bool) -> None:
    """Refuse ``out`` unless it can take ``runs`` run folders and the summary (a file, or
    earlier results without ``overwrite``), after finishing or removing what a killed run
    left there."""
    products = [f"run-{k}" for k in range(runs)] + [SUMMARY_FILE, RETURNS_FILE]
    if out.exists() and not out.is_dir():
        raise RunError(f"{out} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    if out.is_dir():
        tidy(out, key=STAGE_KEY)  # finish or remove what a killed run left
    taken = [p for p in products if (out / p).exists()] if out.is_dir() else []
    if taken and not overwrite:
        raise RunError(f"{out} already holds {taken[0]}", remedy=Remedy.REPLACE)


def write_summary(
    stage: Path,
    *,
    env_id: str,
    algo: str,
    results: Sequence[RunResult],
    expert: float,
    drawn: Mapping[str, float] | None,
) -> GymIRLSummary:
    """The runs' ``summary.json`` and returns figure in ``stage``, and (``drawn``: the
    alignment baselines drawn, discrete actions only) the alignment bands."""
    over_runs = summarize(results)
    curves = over_runs.metrics

    def last(metric: Metric) -> MeanStd:
        curve = metric.of(curves)
        return MeanStd(mean=curve.mean[-1], std=curve.std[-1])

    summary = GymIRLSummary(
        env=env_id,
        algo=algo,
        expert_return=expert,
        irl_final_return=last(Metric.EVAL_RETURN),
        final_alignment=last(Metric.VAL_ALIGNMENT) if Metric.VAL_ALIGNMENT in curves else None,
        over_runs=over_runs,
    )
    as_json = summary.to_json()
    write_text(stage / SUMMARY_FILE, json.dumps(as_json, indent=2) + "\n")
    plot_returns(summary, stage / RETURNS_FILE)
    if drawn is not None:
        bands = {k: over_runs.baselines[k].to_json() for k in drawn}
        plot_bands({**as_json, "baselines": bands}, stage)
    return summary


def plot_returns(summary: GymIRLSummary, path: Path) -> Path:
    """Mean ± std over runs of the evaluation return per epoch, the expert and random lines."""
    figure, axes = new_figure()
    runs = summary.over_runs
    epochs = list(runs.epochs)
    curve = Metric.EVAL_RETURN.of(runs.metrics)
    mean, std = np.array(curve.mean), np.array(curve.std)
    label = f"{summary.algo} policy (mean of {len(runs.seeds)} runs)"
    axes.plot(epochs, mean, color="C0", label=label)
    axes.fill_between(epochs, mean - std, mean + std, color="C0", alpha=0.25, label="± 1 std")
    for i, name in enumerate(("expert", "random")):
        value = runs.baselines[name].mean
        if value is not None and math.isfinite(value):
            axes.axhline(value, linestyle="--", linewidth=1, color=f"C{i + 1}", label=name)
    return save_figure(figure, axes, path, f"{summary.env}: IRL-phase return", "return")
