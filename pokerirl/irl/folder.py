"""A run folder's file names and its writer: ``save_run`` (the nets, ``config.json``,
``timings.json``) and ``MetricsLog`` (``metrics.jsonl``, one line per epoch).

Below :mod:`pokerirl.irl.run` (which trains runs into folders and reads them back) so that
the trainer's :meth:`~pokerirl.irl.trainer.TrainResult.save` writes a folder without
importing the module that imports the trainer: no import loop. ``save_run`` takes any
:class:`TrainedRun` (the trainer's ``TrainResult`` is one).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from torch import Tensor, nn

from pokerirl.atomic import write_text, write_torch
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.records import EpochMetrics
from pokerirl.versions import package_versions

FORMAT_VERSION = 2
REWARD_FILE, POLICY_FILE, CONFIG_FILE = "reward.pt", "policy.pt", "config.json"
METRICS_FILE, BASELINES_FILE, SPLIT_FILE = "metrics.jsonl", "baselines.json", "split.json"
TIMINGS_FILE, SUMMARY_FILE = "timings.json", "summary.json"


class TrainedRun(Protocol):
    """What :func:`save_run` writes of a trained run (the trainer's ``TrainResult``)."""

    # Read-only (properties): a dataclass's list fields then match the sequences.
    @property
    def reward(self) -> nn.Module: ...
    @property
    def policy(self) -> nn.Module: ...
    @property
    def config(self) -> AIRLConfig: ...
    @property
    def metrics(self) -> Sequence[EpochMetrics]: ...
    @property
    def beta_used(self) -> float: ...
    @property
    def gradients(self) -> str: ...
    @property
    def epoch_seconds(self) -> Sequence[float]: ...
    @property
    def samples_per_second(self) -> float: ...


@dataclass(frozen=True)
class MetricsLog:
    """A run folder's ``metrics.jsonl``, one line per epoch."""

    path: Path
    lines: list[str] = field(default_factory=list)

    def write(self, metrics: EpochMetrics) -> None:
        # Rewrite the whole (small) file each epoch: readable live, never half-written.
        self.lines.append(json.dumps(metrics.to_json()))
        write_text(self.path, "\n".join(self.lines) + "\n")


def save_run(
    result: TrainedRun,
    out_dir: str | os.PathLike[str],
    *,
    algo: str,
    data: Mapping[str, Any],
    baselines: Mapping[str, float] | None = None,
    device: str = "cpu",
) -> None:
    """Write ``reward.pt``, ``policy.pt``, ``config.json`` and ``timings.json``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for module, name in ((result.reward, REWARD_FILE), (result.policy, POLICY_FILE)):
        # Clone: training keeps parameters as views of one flat buffer; save each on its own.
        state = {k: v.detach().cpu().clone() for k, v in module.state_dict().items()}
        write_torch(out / name, state)
    policy = result.policy
    if isinstance(getattr(policy, "low", None), Tensor):
        space: dict[str, object] = {
            "type": "box",
            "low": policy.get_buffer("low").tolist(),
            "high": policy.get_buffer("high").tolist(),
        }
    else:
        space = {"type": "discrete", "num_actions": int(policy.action_dim)}  # type: ignore[arg-type]
    config = result.config
    record = {
        "format_version": FORMAT_VERSION,
        "algo": algo,
        "architecture": {
            "obs_dim": int(result.reward.obs_dim),  # type: ignore[arg-type]
            "action_space": space,
            "reward_family": config.reward_family,
            "reward_hidden": list(config.reward_hidden),
            "policy_hidden": list(config.policy_hidden),
            "activation": config.activation,
            "layer_norm": config.layer_norm,
            "gamma": config.gamma,
        },
        "hyperparameters": config.to_dict(),
        "beta_used": result.beta_used,
        "gradients": result.gradients,
        "data": dict(data),
        "device": str(device),
        "versions": package_versions(),
        "result": {
            "epochs": len(result.metrics),
            "final_metrics": result.metrics[-1].to_json() if result.metrics else None,
            "baselines": dict(baselines or {}),
        },
    }
    write_text(out / CONFIG_FILE, json.dumps(record, indent=2) + "\n")
    timings = {
        "samples_per_second": result.samples_per_second,
        "train_seconds": sum(result.epoch_seconds),
        "epoch_seconds": result.epoch_seconds,
    }
    write_text(out / TIMINGS_FILE, json.dumps(timings, indent=2) + "\n")
