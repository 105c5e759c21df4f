"""Training runs on disk: configs, the Parquet front end, checkpoints and ``load_reward``.

A run directory holds ``reward.pt`` and ``policy.pt`` (state_dicts), ``config.json``
(architecture, hyperparameters, data fingerprint, package versions, final metrics),
``metrics.jsonl`` (one line per epoch) and PNG learning curves.

>>> import tempfile, pyarrow.parquet as pq
>>> from pokerirl.irl.toy import toy_expert_table
>>> tmp = Path(tempfile.mkdtemp())
>>> pq.write_table(toy_expert_table(num_hands=200), tmp / "table.parquet")
>>> config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
>>> summary = train_table(tmp / "table.parquet", tmp / "run", algo="hairl", config=config,
...                       progress=False)
>>> reward = load_reward(tmp / "run")
>>> reward(np.zeros((3, 72), np.uint8), np.array([0, 1, 3])).dtype
dtype('float32')
"""

from __future__ import annotations

import dataclasses
import json
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor

from pokerirl.atomic import write_text, write_torch
from pokerirl.irl.airl import AIRLConfig, TrainResult, resolve_device, train
from pokerirl.irl.nets import DiscretePolicy, GaussianPolicy, Policy, RewardNet
from pokerirl.irl.plots import plot_curves
from pokerirl.irl.table import first_line, read_expert_table, split_by_hand
from pokerirl.versions import package_versions

FORMAT_VERSION = 1
REWARD_FILE, POLICY_FILE, CONFIG_FILE, METRICS_FILE = (
    "reward.pt",
    "policy.pt",
    "config.json",
    "metrics.jsonl",
)


def load_config(
    algo: str,
    *,
    config_file: str | os.PathLike[str] | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> AIRLConfig:
    """The algorithm's defaults, then a TOML file's settings, then ``overrides`` (CLI flags).

    The TOML file is flat, with :class:`AIRLConfig` field names as keys::

        epochs = 20
        alpha = 0.5
        policy_hidden = [128, 64]
    """
    settings: dict[str, Any] = {}
    if config_file is not None:
        path = Path(config_file)
        if not path.is_file():
            raise FileNotFoundError(f"config file not found: {path}")
        try:
            settings = tomllib.loads(path.read_text())
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
            raise ValueError(f"cannot parse {path} as TOML: {error}") from None
        if "algo" in settings:
            raise ValueError(f"{path}: choose the algorithm with --algo, not in the config file")
    settings.update({k: v for k, v in (overrides or {}).items() if v is not None})
    try:
        return AIRLConfig.for_algo(algo, **settings)
    except TypeError as error:  # e.g. a string where a number belongs
        raise ValueError(f"invalid setting: {error}") from None


@dataclass(frozen=True)
class RunSummary:
    """What :func:`train_table` did."""

    out_dir: Path
    metrics: list[dict[str, Any]]
    samples_per_second: float
    train_rows: int
    val_rows: int


def train_table(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    algo: str = "hairl",
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
) -> RunSummary:
    """Train on a Parquet decision table and write the run directory ``out_dir``.

    Validation is a seeded share of the *hands* (``config.val_fraction``), never of rows.
    """
    config = config or AIRLConfig.for_algo(algo)
    resolve_device(device)  # fail before reading a large table
    expert = read_expert_table(table)
    train_rows, val_rows = split_by_hand(
        expert.hand_index, expert.num_hands, val_fraction=config.val_fraction, seed=config.seed
    )
    data_info = {
        "path": str(Path(table).resolve()),
        "sha256": expert.fingerprint(),
        "rows": len(expert),
        "hands": expert.num_hands,
        "train_rows": len(train_rows),
        "val_rows": len(val_rows),
        "has_reward": expert.rewards is not None,
    }
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    metrics_lines: list[str] = []

    def log_epoch(metrics: dict[str, Any]) -> None:
        # Rewrite the whole (small) file each epoch: readable live, never half-written.
        metrics_lines.append(json.dumps(metrics))
        write_text(out / METRICS_FILE, "\n".join(metrics_lines) + "\n")

    result = train(
        expert.to_expert_data(train_rows),
        expert.to_expert_data(val_rows),
        config=config,
        device=device,
        progress=progress,
        on_epoch=log_epoch,
    )
    save_run(result, out, algo=algo, data=data_info, device=device)
    plot_curves(result.metrics, out)
    return RunSummary(
        out_dir=out,
        metrics=result.metrics,
        samples_per_second=result.samples_per_second,
        train_rows=len(train_rows),
        val_rows=len(val_rows),
    )


def save_run(
    result: TrainResult,
    out_dir: str | os.PathLike[str],
    *,
    algo: str,
    data: Mapping[str, Any],
    device: str = "cpu",
) -> None:
    """Write ``reward.pt``, ``policy.pt`` and ``config.json`` for a finished :func:`train`."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _save_state_dict(result.reward_net, out / REWARD_FILE)
    _save_state_dict(result.policy, out / POLICY_FILE)
    policy = result.policy
    if isinstance(policy, DiscretePolicy):
        action_space: dict[str, Any] = {"type": "discrete", "num_actions": policy.action_dim}
    else:
        action_space = {"type": "box", "low": policy.low.tolist(), "high": policy.high.tolist()}
    record = {
        "format_version": FORMAT_VERSION,
        "algo": algo,
        "architecture": {
            "obs_dim": result.reward_net.obs_dim,
            "action_space": action_space,
            "reward_hidden": list(result.config.reward_hidden),
            "policy_hidden": list(result.config.policy_hidden),
            "activation": "relu",
        },
        "hyperparameters": dataclasses.asdict(result.config),
        "beta_used": result.beta_used,
        "data": dict(data),
        "device": str(device),
        "versions": package_versions(),
        "result": {
            "epochs": len(result.metrics),
            "samples_per_second": result.samples_per_second,
            "final_metrics": result.metrics[-1] if result.metrics else None,
        },
    }
    write_text(out / CONFIG_FILE, json.dumps(record, indent=2) + "\n")


# --------------------------------------------------------------------------- loading


def load_run_config(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``config.json`` of a run, checked for the format this code writes."""
    path = Path(run_dir) / CONFIG_FILE
    if not path.is_file():
        raise FileNotFoundError(f"no {CONFIG_FILE} in {run_dir}: not a training run directory")
    record = json.loads(path.read_text())
    if record.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: unsupported format_version {record.get('format_version')!r}")
    return record


def _build_from_record(record: Mapping[str, Any]) -> tuple[RewardNet, Policy]:
    arch = record["architecture"]
    space = arch["action_space"]
    action_dim = space["num_actions"] if space["type"] == "discrete" else len(space["low"])
    reward_net = RewardNet(
        obs_dim=arch["obs_dim"], action_dim=action_dim, hidden=arch["reward_hidden"]
    )
    policy: Policy
    if space["type"] == "discrete":
        policy = DiscretePolicy(
            obs_dim=arch["obs_dim"], num_actions=action_dim, hidden=arch["policy_hidden"]
        )
    else:
        policy = GaussianPolicy(
            obs_dim=arch["obs_dim"],
            low=space["low"],
            high=space["high"],
            hidden=arch["policy_hidden"],
        )
    return reward_net, policy


def _load_state(module: torch.nn.Module, path: Path) -> None:
    if not path.is_file():
        raise FileNotFoundError(f"checkpoint not found: {path}")
    try:
        module.load_state_dict(torch.load(path, map_location="cpu", weights_only=True))
    except RuntimeError as error:  # e.g. a checkpoint from an older layout of the nets
        raise ValueError(f"{path} does not match its {CONFIG_FILE}: {first_line(error)}") from None
    module.eval()


def load_policy(run_dir: str | os.PathLike[str]) -> Policy:
    """The trained policy of a run (on CPU, in eval mode)."""
    _, policy = _build_from_record(load_run_config(run_dir))
    _load_state(policy, Path(run_dir) / POLICY_FILE)
    return policy


class RewardFunction:
    """A batched learned reward f(obs, actions) -> rewards.

    ``obs`` is (B, obs_dim) of any numeric dtype (the poker tables' uint8 is fine);
    ``actions`` are ids (B,) for discrete action spaces, values (B, k) for box ones.
    numpy in gives float32 numpy out; torch tensors in give a float32 tensor out.
    """

    def __init__(self, reward_net: RewardNet, *, num_actions: int | None) -> None:
        self.net = reward_net.eval()
        self.num_actions = num_actions  # None: continuous actions

    def __call__(self, obs: np.ndarray | Tensor, actions: np.ndarray | Tensor) -> Any:
        as_numpy = isinstance(obs, np.ndarray)
        obs_t = torch.from_numpy(np.asarray(obs)) if as_numpy else obs
        actions_t = torch.as_tensor(np.asarray(actions) if as_numpy else actions)
        if obs_t.ndim != 2 or obs_t.shape[1] != self.net.obs_dim:
            raise ValueError(f"obs must be (B, {self.net.obs_dim}), got {tuple(obs_t.shape)}")
        if len(actions_t) != len(obs_t):
            raise ValueError("obs and actions must have the same batch size")
        with torch.inference_mode():
            if self.num_actions is not None:
                action_vec = torch.nn.functional.one_hot(actions_t.long(), self.num_actions)
            else:
                action_vec = actions_t.reshape(len(actions_t), -1)
            rewards = self.net(obs_t.float(), action_vec.float())
        return rewards.numpy() if as_numpy else rewards


def load_reward(run_dir: str | os.PathLike[str]) -> RewardFunction:
    """The learned reward of a run as a batched callable f(obs, action_ids) -> rewards.

    Runs on CPU under ``torch.inference_mode``; see :class:`RewardFunction`.
    """
    record = load_run_config(run_dir)
    reward_net, _ = _build_from_record(record)
    _load_state(reward_net, Path(run_dir) / REWARD_FILE)
    space = record["architecture"]["action_space"]
    num_actions = space["num_actions"] if space["type"] == "discrete" else None
    return RewardFunction(reward_net, num_actions=num_actions)


# --------------------------------------------------------------------------- files


def _save_state_dict(module: torch.nn.Module, path: Path) -> None:
    # Clone: FlatAdam keeps parameters as views of one buffer; save each on its own.
    write_torch(path, {k: v.detach().cpu().clone() for k, v in module.state_dict().items()})
