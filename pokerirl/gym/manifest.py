"""The shipped experts' manifest (``pokerirl/gym/experts/manifest.json``), read and written
without torch, Gymnasium or SB3: ``pokerirl gym experts`` only prints it, and should start in
a fraction of a second (issue 34). It also names an expert folder's files, which
:mod:`pokerirl.gym.expert_policies` writes and reads.

>>> [entry.env for entry in shipped_experts()][:2]
['Acrobot-v1', 'MountainCar-v0']
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from pokerirl.atomic import write_text
from pokerirl.errors import InputError
from pokerirl.jsonio import read_json
from pokerirl.serial import Serializable

MODEL_FILE, CONFIG_FILE, METRICS_FILE = "model.pt", "config.json", "metrics.jsonl"
MANIFEST_FILE = "manifest.json"
MANIFEST_KEYS = ("env", "algo", "return_mean", "return_std", "episodes", "seed", "timesteps")


@dataclass(frozen=True, kw_only=True)
class ManifestEntry(Serializable):
    """One shipped expert in ``manifest.json``: :data:`MANIFEST_KEYS`, then ``settings``
    (``hyper`` first, then the hyper-parameters it was trained with)."""

    env: str
    algo: str
    return_mean: float
    return_std: float
    episodes: int
    seed: int
    timesteps: int
    settings: dict[str, Any]


def shipped_dir() -> Path:
    """The folder of the experts shipped in the package (``pokerirl/gym/experts``)."""
    return Path(str(resources.files("pokerirl.gym") / "experts"))


def shipped_manifest() -> list[Mapping[str, Any]]:
    """The shipped experts' manifest as JSON: one object per expert with
    :data:`MANIFEST_KEYS`, then ``settings`` (:func:`shipped_experts`: typed).
    """
    path = shipped_dir() / MANIFEST_FILE
    if not path.is_file():
        raise InputError(f"{path}: no shipped experts in this installation")
    manifest: list[Mapping[str, Any]] = read_json(path)
    return manifest


def shipped_experts() -> tuple[ManifestEntry, ...]:
    """The shipped experts' manifest, in task order."""
    return tuple(ManifestEntry.from_json(entry) for entry in shipped_manifest())


def manifest_entry(record: Mapping[str, Any]) -> dict[str, object]:
    """The manifest's object for one expert record: :data:`MANIFEST_KEYS`, plus its settings."""
    entry: dict[str, object] = {key: record[key] for key in MANIFEST_KEYS}
    entry["settings"] = {"hyper": record["hyper"], **record["settings"]}
    return entry


def write_manifest(folder: str | os.PathLike[str]) -> list[dict[str, object]]:
    """Write ``folder/manifest.json`` from the expert folders inside it, in task order."""
    from pokerirl.gym.presets import TASK_ORDER

    folder = Path(folder)
    records = [
        read_json(folder / env_id / CONFIG_FILE)
        for env_id in TASK_ORDER
        if (folder / env_id / CONFIG_FILE).is_file()
    ]
    manifest = [manifest_entry(record) for record in records]
    write_text(folder / MANIFEST_FILE, json.dumps(manifest, indent=2) + "\n")
    return manifest
