"""Run folders on disk: training runs into them (:func:`train_runs_into`), and reading runs
back (``load_reward``).

A run folder holds ``reward.pt`` and ``policy.pt`` (state_dicts), ``config.json``
(architecture, hyperparameters, data fingerprint, package versions, final metrics: what
determines the result, never wall-clock times), ``timings.json`` (samples/s, seconds),
``metrics.jsonl`` (one line per epoch), ``baselines.json``, ``split.json`` (the validation
group ids) and PNG curves. A folder of several runs holds ``run-<k>`` folders and
``summary.json`` (:func:`summarize`: mean and std over runs).

Poker-free and Gymnasium-free: ``pokerirl train`` (a poker table, the reward card, several
runs on a backend, EM) is :mod:`pokerirl.poker.train`; ``pokerirl gym irl`` is
:mod:`pokerirl.gym.irl`. Both train through :func:`train_runs_into`, adding what is theirs as
:class:`RunHooks` (an observation standardization, baselines, an epoch callback, a finish per
folder), and :func:`load_reward` reads either.

>>> import tempfile
>>> from pokerirl.irl.config import load_config
>>> rng = np.random.default_rng(0)
>>> obs = rng.integers(0, 2, size=(200, 6))
>>> data = Transitions.from_arrays(obs, obs[:, 0] + 2 * obs[:, 1], groups=np.arange(200) // 4)
>>> config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
>>> run = Path(tempfile.mkdtemp()) / "run"
>>> summary = train_into(data, run, algo="hairl", config=config)
>>> sorted(summary.baselines)
['bc', 'legal_majority', 'majority']
>>> load_reward(run)(np.zeros((3, 6)), np.array([0, 1, 3])).dtype
dtype('float32')
"""

from __future__ import annotations

import io
import json
import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.atomic import write_text
from pokerirl.errors import PokerIRLError, check_argument
from pokerirl.execution import progress_share, unit_progress
from pokerirl.irl.adversarial import baselines, default_nets, train, train_many
from pokerirl.irl.config import AIRLConfig, Algo

# A run folder's names and writer live in irl/folder.py (the trainer's `TrainResult.save`
# uses them without importing this module, which imports the trainer): importable here too.
from pokerirl.irl.folder import BASELINES_FILE as BASELINES_FILE
from pokerirl.irl.folder import CONFIG_FILE as CONFIG_FILE
from pokerirl.irl.folder import FORMAT_VERSION as FORMAT_VERSION
from pokerirl.irl.folder import METRICS_FILE as METRICS_FILE
from pokerirl.irl.folder import POLICY_FILE as POLICY_FILE
from pokerirl.irl.folder import REWARD_FILE as REWARD_FILE
from pokerirl.irl.folder import SPLIT_FILE as SPLIT_FILE
from pokerirl.irl.folder import SUMMARY_FILE as SUMMARY_FILE
from pokerirl.irl.folder import TIMINGS_FILE as TIMINGS_FILE
from pokerirl.irl.folder import MetricsLog as MetricsLog
from pokerirl.irl.folder import save_run as save_run
from pokerirl.irl.metrics import Metric, Part
from pokerirl.irl.nets import (
    ACTIVATIONS,
    REWARD_FAMILIES,
    NetSpec,
    RewardFamily,
    build_nets,
    fold_obs_standardization,
)
from pokerirl.irl.plots import plot_curves
from pokerirl.irl.records import EpochCallback, EpochMetrics
from pokerirl.irl.transitions import Transitions
from pokerirl.jsonio import parse_json, read_bytes, read_json, read_json_lines
from pokerirl.meanstd import Curve, MeanStd, mean_std
from pokerirl.parquet import first_line
from pokerirl.serial import Serializable, from_json
from pokerirl.settings import MAX_ACTIONS, MAX_LAYERS, MAX_OBS_DIM, MAX_WIDTH, enum_value

REWARD_RUN_FILES = (REWARD_FILE, CONFIG_FILE)  # what identifies a learned-reward run
POLICY_RUN_FILES = (POLICY_FILE, CONFIG_FILE)  # ... and its policy


class RunError(PokerIRLError, ValueError):
    """A run folder, or a file in it, that cannot be used: one line naming it (and, where a
    caller could get past it, a :class:`~pokerirl.errors.Remedy`)."""


@dataclass(frozen=True, kw_only=True)
class RunResult(Serializable):
    """One finished run of several: its folder, seed, metrics, baselines, speed and split."""

    out: str
    seed: int
    metrics: tuple[EpochMetrics, ...]
    baselines: Mapping[str, float]
    samples_per_second: float
    train_rows: int
    val_rows: int


@dataclass(frozen=True)
class RunSummary:
    """What :func:`train_into` did (for several runs, :func:`pokerirl.poker.train_runs`: the
    first run, and all of them in ``results``)."""

    out_dir: Path
    metrics: list[EpochMetrics]
    baselines: dict[str, float]
    samples_per_second: float
    train_rows: int
    val_rows: int
    results: tuple[RunResult, ...] = ()  # several runs: each run's result

    @classmethod
    def of(
        cls, results: Sequence[RunResult], *, out_dir: Path, several: bool = True
    ) -> RunSummary:
        """The first of ``results`` (its speed: the mean over runs that measured one), and
        all of them in ``results`` when they are ``several`` runs' (not one run's)."""
        first = results[0]
        return cls(
            out_dir=out_dir,
            metrics=list(first.metrics),
            baselines=dict(first.baselines),
            samples_per_second=float(np.nanmean([r.samples_per_second for r in results])),
            train_rows=first.train_rows,
            val_rows=first.val_rows,
            results=tuple(results) if several else (),
        )


@dataclass(frozen=True, kw_only=True)
class RunsSummary(Serializable):
    """Several runs summarized (``summary.json``): each scalar metric per epoch and each
    baseline, as mean and sample std (ddof 1) over runs."""

    seeds: tuple[int, ...]
    epochs: tuple[int, ...]
    metrics: Mapping[str, Curve]
    baselines: Mapping[str, MeanStd]

    def to_json(self) -> dict[str, Any]:
        return {"runs": len(self.seeds), **super().to_json()}  # runs: read, never stored


# --------------------------------------------------------------------------- one run


def begin_run(
    folder: Path, *, val_groups: Sequence[Any], baselines: Mapping[str, float]
) -> MetricsLog:
    """Make the run folder ``folder`` with its split and baselines; its epochs' log."""
    folder.mkdir(parents=True, exist_ok=True)
    write_text(folder / SPLIT_FILE, json.dumps({"validation_groups": val_groups}) + "\n")
    write_text(folder / BASELINES_FILE, json.dumps(baselines, indent=2) + "\n")
    return MetricsLog(folder / METRICS_FILE)


BASELINE_SHARE = 0.3  # of a run's time: behaviour cloning has no adversary to train
# Of the runs' time, where training ends: saving each run, its figures and a caller's
# finish (a reward card, a reward quality) take the rest, so the bar moves after the last epoch.
TRAINED_SHARE = 0.9


@dataclass(frozen=True, kw_only=True)
class ObsMap:
    """The nets' view of observations, ``(x - shift) / scale``, fit on a split's training
    rows by a :class:`RunHooks` ``obs_map`` (the Gymnasium layer's standardization): the runs
    train on mapped rows, and their saved nets take raw observations (the map is folded into
    their first layers). ``record`` is what ``config.json``'s ``data.obs_standardization``
    says of it (None: the map is the identity and records nothing of itself)."""

    shift: Tensor
    scale: Tensor
    record: Mapping[str, object] | None = None

    def rows(self, data: Transitions) -> Transitions:
        """``data`` with obs and next_obs mapped."""
        next_obs = None if data.next_obs is None else (data.next_obs - self.shift) / self.scale
        return replace(data, obs=(data.obs - self.shift) / self.scale, next_obs=next_obs)

    def obs(self, obs: np.ndarray) -> np.ndarray:
        """Raw observations (numpy) as the training nets see them."""
        return (obs - self.shift.numpy()) / self.scale.numpy()

    def fold(self, net: nn.Module) -> None:
        """Make ``net``, trained on mapped observations, take raw ones (in place)."""
        fold_obs_standardization(net, self.shift, self.scale)


@dataclass(frozen=True, kw_only=True)
class RunHooks:
    """What a caller adds to :func:`train_runs_into`, each optional: how it stays poker-free
    and Gymnasium-free while the poker and Gymnasium layers train through it.

    ``obs_map`` fits an :class:`ObsMap` on the training rows (the Gymnasium layer
    standardizes observations); ``baselines`` gives more baselines after the core's (a random
    policy's and the expert's return); ``callback`` makes the trainer's
    :class:`~pokerirl.irl.records.EpochCallback` once the map is known (None without
    ``obs_map``), e.g. each epoch's return in an environment; ``finish`` is called with each
    written run folder (the poker layer's reward card, the Gymnasium layer's reward quality).
    """

    obs_map: Callable[[Transitions], ObsMap] | None = None
    baselines: Callable[[], Mapping[str, float]] | None = None
    callback: Callable[[ObsMap | None], EpochCallback] | None = None
    finish: Callable[[Path], object] | None = None


@dataclass(frozen=True, kw_only=True)
class RunsTrained:
    """What :func:`train_runs_into` wrote: each run's result (in ``folders``' order), the
    baselines (the core's and the hooks'), and those drawn as lines on alignment plots."""

    results: tuple[RunResult, ...]
    baselines: dict[str, float]
    drawn: dict[str, float]


def train_runs_into(
    data: Transitions,
    folders: Sequence[Path],
    *,
    algo: str,
    config: AIRLConfig,
    hooks: RunHooks | None = None,
    device: str = "cpu",
    progress: bool = False,
    data_path: str | os.PathLike[str] | None = None,
    data_lead: Mapping[str, object] | None = None,
    data_notes: Mapping[str, object] | None = None,
) -> RunsTrained:
    """The one way runs are trained and written: ``len(folders)`` runs of ``algo`` on
    ``data`` in lock-step, run k with seed ``config.seed + k`` into the (new) ``folders[k]``.

    Split (validation is a seeded share of the *groups*, ``config.val_fraction``, never of
    rows), ``hooks.obs_map``, baselines (:func:`run_baselines`, then ``hooks.baselines``),
    :func:`begin_run` per folder, training (:func:`~pokerirl.irl.adversarial.train_many`, each epoch
    logged to each folder), then per run :func:`save_run`, its curves and ``hooks.finish``.
    ``data_path`` is where the data came from, for the record (``config.json``'s
    ``data.path``); ``data_lead`` and ``data_notes`` are the caller's own keys of ``data``,
    recorded before and after this layer's (the Gymnasium layer's ``env``, the poker layer's
    ``encoding``) without being read.
    """
    check_argument("data", data, Transitions, "Transitions")
    for folder in folders:
        check_argument("folder", folder, (str, os.PathLike), "a folder (a path)")
    algo = enum_value("algo", Algo, algo)  # the run records it: "nope" wrote a run of nope
    check_argument("config", config, AIRLConfig, "an AIRLConfig (AIRLConfig.for_algo gives one)")
    folders = [Path(folder) for folder in folders]
    hooks = hooks or RunHooks()
    train_data, val_data, val_groups = data.split(
        val_fraction=config.val_fraction, seed=config.seed
    )
    obs_map = None if hooks.obs_map is None else hooks.obs_map(train_data)
    if obs_map is not None:
        train_data, val_data = obs_map.rows(train_data), obs_map.rows(val_data)
    with progress_share(0.0, BASELINE_SHARE):  # the baseline's epochs, then the runs'
        core = run_baselines(train_data, val_data, config=config, device=device,
                             progress=progress)  # fmt: skip
    found = {**core, **(hooks.baselines() if hooks.baselines is not None else {})}
    drawn = drawn_baselines(core, data)
    seeds = [config.seed + k for k in range(len(folders))]
    nets = [default_nets(train_data, config, seed) for seed in seeds]
    logs = [begin_run(folder, val_groups=val_groups, baselines=found) for folder in folders]

    def on_epoch(all_metrics: list[EpochMetrics]) -> None:
        for log, metrics in zip(logs, all_metrics, strict=True):
            log.write(metrics)

    with progress_share(BASELINE_SHARE, TRAINED_SHARE):
        many = train_many(
            train_data,
            val_data,
            config=config,
            seeds=seeds,
            rewards=[reward for reward, _ in nets],
            policies=[policy for _, policy in nets],
            device=device,
            progress=progress,
            on_epoch=on_epoch,
            callback=None if hooks.callback is None else hooks.callback(obs_map),
        )
    data_info = {
        **(data_lead or {}),
        **data_record(data, train_data, val_data, path=data_path),
        **(data_notes or {}),
    }
    if obs_map is not None:
        data_info["obs_standardization"] = obs_map.record
    results = []
    for k, (folder, result) in enumerate(zip(folders, many.runs, strict=True)):
        if obs_map is not None:  # the saved nets take raw observations (load_reward, agents)
            obs_map.fold(result.reward)
            obs_map.fold(result.policy)
        save_run(result, folder, algo=algo, data=data_info, baselines=found, device=device)
        plot_curves(result.metrics, folder, baselines=drawn)
        if hooks.finish is not None:
            hooks.finish(folder)
        results.append(
            RunResult(
                out=str(folder),
                seed=seeds[k],
                metrics=tuple(result.metrics),
                baselines=found,
                samples_per_second=result.samples_per_second,
                train_rows=len(train_data),
                val_rows=len(val_data),
            )
        )
        with progress_share(TRAINED_SHARE, 1.0):  # the bar moves while runs are saved
            unit_progress(k + 1, len(folders))
    return RunsTrained(results=tuple(results), baselines=found, drawn=drawn)


def train_into(
    data: Transitions,
    folder: Path,
    *,
    algo: str,
    config: AIRLConfig,
    device: str = "cpu",
    progress: bool = False,
    data_path: str | os.PathLike[str] | None = None,
    data_notes: Mapping[str, object] | None = None,
) -> RunSummary:
    """One run of :func:`train_runs_into` (seed ``config.seed``) into the (new) ``folder``.

    ``data_path`` is where the data came from, for the record (``config.json``'s
    ``data.path``); ``data_notes`` are the caller's own keys of ``data`` (the poker layer's
    ``encoding``), which this layer records without reading."""
    trained = train_runs_into(
        data, [folder], algo=algo, config=config, device=device, progress=progress,
        data_path=data_path, data_notes=data_notes,
    )  # fmt: skip
    return RunSummary.of(trained.results, out_dir=Path(folder), several=False)


def data_record(
    data: Transitions,
    train_data: Transitions,
    val_data: Transitions,
    *,
    path: str | os.PathLike[str] | None,
) -> dict[str, object]:
    """What a run's ``config.json`` says of its data: where, which bytes, how it was split."""
    found: dict[str, object] = {
        "path": None if path is None else str(Path(path).resolve()),
        "sha256": data.fingerprint(),
        "rows": len(data),
        "groups": len(np.unique(data.groups)),
        "train_rows": len(train_data),
        "val_rows": len(val_data),
        "has_reward": data.rewards is not None,
        "has_next_obs": data.next_obs is not None,
    }
    if data.imputed is not None:  # only then: records of other data keep their bytes
        found["imputed_rows"] = int(data.imputed.sum())
    if data.weights is not None:
        found["total_weight"] = float(data.weights.double().sum())
    return found


def drawn_baselines(core: Mapping[str, float], data: Transitions) -> dict[str, float]:
    """Of the core's baselines (:func:`run_baselines`), those drawn as lines on alignment
    plots: shares of states, so none for continuous actions; without a legal mask
    ``legal_majority`` is ``majority`` under another name."""
    return {
        k: v for k, v in core.items()
        if data.discrete and (k != "legal_majority" or data.legal_mask is not None)
    }  # fmt: skip


def run_baselines(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    device: str = "cpu",
    progress: bool = False,
) -> dict[str, float]:
    """``majority`` and ``legal_majority`` (discrete), and ``bc``: the same policy net, same
    initialization and epochs, trained with α = 1 and no adversary, on the same split.

    ``bc`` is its final validation alignment (discrete) or validation MSE (continuous);
    with imputed rows in the data, ``bc_observed`` and ``bc_imputed`` too.
    The dict is plain: callers (the Gymnasium layer) add keys such as ``random``, ``expert``.
    """
    found = baselines(train_data, val_data) if train_data.discrete else {}
    reward, policy = default_nets(train_data, config)
    bc = train(
        train_data,
        val_data,
        config=replace(config, alpha=1.0),
        reward=reward,
        policy=policy,
        adversarial=False,
        device=device,
        progress=progress,
    )
    last = bc.metrics[-1]
    found["bc"] = (Metric.VAL_ALIGNMENT if train_data.discrete else Metric.VAL_MSE).of(last)
    for part in Part:  # data with imputed rows: BC on each part apart
        value = Metric.VAL_ALIGNMENT.on(part).of(last, None)
        if value is not None:
            found[f"bc_{part}"] = value
    return found


# --------------------------------------------------------------------------- several runs: summary


def summarize(results: Sequence[RunResult]) -> RunsSummary:
    """Mean and sample std (ddof 1) over runs of each scalar metric per epoch and of each
    baseline."""
    metrics = [r.metrics for r in results]
    by_metric = {
        key: Curve.of([[m[key] for m in run] for run in metrics]) for key in metrics[0][0].scalars()
    }
    by_baseline = {
        key: mean_std([r.baselines[key] for r in results]) for key in results[0].baselines
    }
    return RunsSummary(
        seeds=tuple(r.seed for r in results),
        epochs=tuple(m.epoch for m in metrics[0]),
        metrics=by_metric,
        baselines=by_baseline,
    )


# --------------------------------------------------------------------------- loading


def read_epochs(run_dir: str | os.PathLike[str]) -> list[EpochMetrics]:
    """A run folder's epochs (its ``metrics.jsonl``), typed: what a study reads of the runs
    it trained, instead of the file's keys; a bad line is named by file and line."""
    path = Path(run_dir) / METRICS_FILE
    lines = read_json_lines(path)
    return [EpochMetrics.from_json(line, f"{path}:{k + 1}") for k, line in enumerate(lines)]


def read_run_result(run_dir: str | os.PathLike[str]) -> RunResult:
    """A finished run folder as :func:`summarize` reads it (a run reused from a store, or
    one of an older pokerirl: its speed NaN when it has no ``timings.json``)."""
    folder = Path(run_dir)
    record = read_json(folder / CONFIG_FILE)
    timings_path = folder / TIMINGS_FILE
    timings = read_json(timings_path) if timings_path.is_file() else {}
    return RunResult(
        out=str(folder),
        seed=record["hyperparameters"]["seed"],
        metrics=tuple(read_epochs(folder)),
        baselines=read_json(folder / BASELINES_FILE),
        samples_per_second=timings.get("samples_per_second", float("nan")),
        train_rows=record["data"]["train_rows"],
        val_rows=record["data"]["val_rows"],
    )


def read_split(run_dir: str | os.PathLike[str]) -> set[str]:
    """A run folder's validation groups (its ``split.json``), as strings (the tables' hand
    ids); ``RunError`` naming the file and its field when it is not a split (a string of
    ids was read as its characters: "none of the table's rows" blamed the table)."""
    path = Path(run_dir) / SPLIT_FILE
    found = read_json(path, error=RunError)
    groups = found.get("validation_groups") if isinstance(found, dict) else None
    if not isinstance(groups, list) or not groups or not all(
        isinstance(g, str | int) and not isinstance(g, bool) for g in groups
    ):  # fmt: skip
        shown = str(groups)[:60]
        raise RunError(
            f"{path}: validation_groups must be a non-empty list of hand or episode ids, "
            f"got {shown}"
        )
    return {str(g) for g in groups}


def read_baselines(run_dir: str | os.PathLike[str]) -> dict[str, float]:
    """A run folder's baselines (its ``baselines.json``): each one's validation alignment."""
    path = Path(run_dir) / BASELINES_FILE
    return from_json(dict[str, float], read_json(path), str(path))


def load_run_config(run_dir: str | os.PathLike[str]) -> Mapping[str, Any]:
    """The ``config.json`` of a run (format 1 or 2), checked; ``RunError`` naming the file."""
    path = Path(run_dir) / CONFIG_FILE
    if not path.is_file() and (Path(run_dir) / SUMMARY_FILE).is_file():
        raise RunError(f"{run_dir} holds several runs: choose one, e.g. {run_dir}/run-0")
    if not path.is_file():
        raise RunError(f"no {CONFIG_FILE} in {run_dir}: not a training run folder")
    try:
        data = read_bytes(path, error=RunError)
    except OSError as error:
        raise RunError(f"{path}: not readable JSON ({first_line(error)})") from None
    return parse_run_config(data, where=path)


def parse_run_config(data: bytes, *, where: str | os.PathLike[str]) -> Mapping[str, Any]:
    """A run's ``config.json`` from its bytes, checked; ``RunError`` naming ``where``."""
    record = parse_json(data, where=where, error=RunError)
    if not isinstance(record, dict):
        raise RunError(f"{where}: must hold a JSON object, got {type(record).__name__}")
    version = record.get("format_version")
    if version not in (1, FORMAT_VERSION):
        raise RunError(f"{where}: unsupported format_version {version!r}")
    arch = record.get("architecture")
    if not isinstance(arch, dict):
        raise RunError(f"{where}: lacks an 'architecture' object")
    for key in ("data", "hyperparameters"):  # read with .get by many: a string crashed them
        if record.get(key) is not None and not isinstance(record[key], dict):
            found = type(record[key]).__name__
            raise RunError(f"{where}: {key!r} must be a JSON object, got {found}")
    problem = _architecture_problem(arch)
    if problem:
        raise RunError(f"{where}: architecture: {problem}")
    return record


def _architecture_problem(arch: Mapping[str, Any]) -> str | None:
    def is_int(x: Any) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    def widths(x: Any) -> bool:  # bounded before any net is built: 10^9 asked for 288 GB
        return (
            isinstance(x, list)
            and 0 < len(x) <= MAX_LAYERS
            and all(is_int(w) and 1 <= w <= MAX_WIDTH for w in x)
        )

    space = arch.get("action_space")
    if not is_int(arch.get("obs_dim")) or not 1 <= arch["obs_dim"] <= MAX_OBS_DIM:
        return f"'obs_dim' must be an integer in 1..{MAX_OBS_DIM}"
    if not isinstance(space, dict) or space.get("type") not in ("discrete", "box"):
        return "'action_space' must be {type: discrete|box, ...}"
    actions: Any = space.get("num_actions")
    if space["type"] == "discrete" and not (is_int(actions) and 1 <= actions <= MAX_ACTIONS):
        return f"'action_space.num_actions' must be an integer in 1..{MAX_ACTIONS}"
    if space["type"] == "box":
        low, high = space.get("low"), space.get("high")
        if not (_numbers(low) and _numbers(high) and len(low or ()) == len(high or ())):
            return "'action_space.low' and 'high' must be equal-length lists of numbers"
    for key in ("reward_hidden", "policy_hidden"):
        if not widths(arch.get(key)):
            return f"{key!r} must be a list of 1 to {MAX_LAYERS} integers in 1..{MAX_WIDTH}"
    if arch.get("activation", "relu") not in ACTIVATIONS:
        return f"'activation' must be one of {', '.join(ACTIVATIONS)}"
    if not isinstance(arch.get("layer_norm", False), bool):
        return "'layer_norm' must be true or false"
    if arch.get("reward_family", RewardFamily.STATE_ACTION) not in REWARD_FAMILIES:
        return f"'reward_family' must be one of {', '.join(REWARD_FAMILIES)}"
    gamma = arch.get("gamma", 0.99)
    if not isinstance(gamma, int | float) or isinstance(gamma, bool):
        return "'gamma' must be a number"
    return None


def _numbers(value: Any) -> bool:
    return (
        isinstance(value, list)
        and bool(value)
        and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)
    )


def build_from_record(record: Mapping[str, Any]) -> tuple[nn.Module, nn.Module]:
    """Untrained reward and policy nets of the architecture a run's ``config.json`` records
    (drawn from torch's global RNG, as :func:`~pokerirl.irl.nets.build_nets` draws them)."""
    arch = record["architecture"]
    space = arch["action_space"]
    spec = NetSpec(
        reward_hidden=tuple(arch["reward_hidden"]),
        policy_hidden=tuple(arch["policy_hidden"]),
        activation=arch.get("activation", "relu"),
        layer_norm=arch.get("layer_norm", False),
        reward_family=arch.get("reward_family", RewardFamily.STATE_ACTION),
        gamma=float(arch.get("gamma", 0.99)),
    )
    discrete = space["type"] == "discrete"
    return build_nets(
        spec,
        obs_dim=arch["obs_dim"],
        action_dim=space["num_actions"] if discrete else len(space["low"]),
        discrete=discrete,
        low=None if discrete else space["low"],
        high=None if discrete else space["high"],
    )


def _load_state(module: nn.Module, path: Path) -> None:
    if not path.is_file():
        raise RunError(f"checkpoint not found: {path}")
    _load_state_bytes(module, path.read_bytes(), where=path)


def _load_state_bytes(module: nn.Module, data: bytes, *, where: str | os.PathLike[str]) -> None:
    try:
        with warnings.catch_warnings():  # torch warns of a plain pickle before refusing it
            warnings.simplefilter("ignore")
            state = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
    except Exception:
        raise RunError(
            f"{where}: not a readable PyTorch state_dict (corrupt or truncated)"
        ) from None
    if not isinstance(state, dict):
        raise RunError(f"{where}: holds a {type(state).__name__}, not a state_dict")
    bad = next(
        (k for k, v in state.items() if isinstance(v, Tensor) and v.is_floating_point()
         and not bool(torch.isfinite(v).all())),
        None,
    )  # fmt: skip
    if bad is not None:  # a NaN net trains agents on NaN rewards without a word
        raise RunError(f"{where}: weights hold NaN or infinity ({bad})")
    try:
        module.load_state_dict(state)
    except (RuntimeError, TypeError, ValueError) as error:
        raise RunError(f"{where} does not match its {CONFIG_FILE}: {first_line(error)}") from None
    module.eval()


def load_policy(run_dir: str | os.PathLike[str]) -> nn.Module:
    """The trained policy of a run (on CPU, in eval mode)."""
    check_argument("run_dir", run_dir, (str, os.PathLike), "a run folder (a path)")
    _, policy = build_from_record(load_run_config(run_dir))
    _load_state(policy, Path(run_dir) / POLICY_FILE)
    return policy


def policy_from_bytes(
    record: Mapping[str, Any], policy_bytes: bytes, *, where: str | os.PathLike[str]
) -> nn.Module:
    """:func:`load_policy` from a checked ``config.json`` and the bytes of ``policy.pt``."""
    _, policy = build_from_record(record)
    _load_state_bytes(policy, policy_bytes, where=where)
    return policy


class RewardFunction:
    """A batched learned reward r(obs, actions) -> rewards.

    ``obs`` is (B, obs_dim) of any numeric dtype (the poker tables' uint8 is fine);
    ``actions`` are ids (B,) for discrete action spaces, values (B, k) for box ones.
    numpy in gives float32 numpy out; torch tensors in give a float32 tensor out.
    By default it is the transferable reward g(s, a) (all of f for the ``state_action``
    family); with ``full`` (shaped family) it is f(s, a, s') and needs ``next_obs`` and ``done``.
    """

    def __init__(self, net: nn.Module, *, num_actions: int | None, full: bool = False) -> None:
        self.net = net.eval()
        self.obs_dim = int(net.obs_dim)  # type: ignore[arg-type]
        self.num_actions = num_actions  # None: continuous actions
        self.full = full

    def __call__(
        self,
        obs: np.ndarray | Tensor,
        actions: np.ndarray | Tensor,
        next_obs: np.ndarray | Tensor | None = None,
        done: np.ndarray | Tensor | None = None,
    ) -> Any:
        as_numpy = isinstance(obs, np.ndarray)
        tensor = lambda x: torch.as_tensor(np.asarray(x) if as_numpy else x)  # noqa: E731
        obs_t, actions_t = tensor(obs), tensor(actions)
        if obs_t.ndim != 2 or obs_t.shape[1] != self.obs_dim:
            raise ValueError(f"obs must be (B, {self.obs_dim}), got {tuple(obs_t.shape)}")
        if len(actions_t) != len(obs_t):
            raise ValueError("obs and actions must have the same batch size")
        extra: tuple[Tensor, ...] = ()
        if self.full:
            if next_obs is None or done is None:
                raise ValueError("the full shaped reward needs next_obs and done")
            extra = (tensor(next_obs).float(), tensor(done).bool())
        with torch.inference_mode():
            if self.num_actions is not None:
                vectors = torch.nn.functional.one_hot(actions_t.long(), self.num_actions)
            else:
                vectors = actions_t.reshape(len(actions_t), -1)
            rewards = self.net(obs_t.float(), vectors.float(), *extra)
        return rewards.numpy() if as_numpy else rewards


def load_reward(run_dir: str | os.PathLike[str], *, full: bool = False) -> RewardFunction:
    """The learned reward of a run as a batched callable r(obs, action_ids) -> rewards.

    g(s, a) by default (see :class:`RewardFunction`); every problem with the folder is a
    :class:`RunError` (a ``ValueError``) of one line naming the file.
    """
    check_argument("run_dir", run_dir, (str, os.PathLike), "a run folder (a path)")
    record = load_run_config(run_dir)
    path = Path(run_dir) / REWARD_FILE
    if not path.is_file():
        raise RunError(f"checkpoint not found: {path}")
    return reward_from_bytes(record, path.read_bytes(), where=path, full=full)


def reward_from_bytes(
    record: Mapping[str, Any],
    reward_bytes: bytes,
    *,
    where: str | os.PathLike[str],
    full: bool = False,
) -> RewardFunction:
    """:func:`load_reward` from a checked ``config.json`` (:func:`parse_run_config`) and the
    bytes of ``reward.pt`` (``where`` names them in errors): no file is read."""
    reward, _ = build_from_record(record)
    _load_state_bytes(reward, reward_bytes, where=where)
    space = record["architecture"]["action_space"]
    num_actions = space["num_actions"] if space["type"] == "discrete" else None
    return RewardFunction(reward, num_actions=num_actions, full=full)
