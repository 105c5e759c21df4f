"""Agent folders: a q-network ``state_dict`` plus ``config.json``, and :func:`load_agent`.

An agent folder holds ``model.pt`` (the q-network's ``state_dict``, loaded with
``weights_only=True``) and ``config.json`` (network shape, how it was trained: reward mode,
reward-run fingerprint, seed, hyper-parameters). Both are written atomically, ``config.json``
last, so a folder with both is finished. Training also writes ``metrics.jsonl`` and
``learning_curve.png`` there.

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp()) / "agent"
>>> save_agent(folder, QNetwork(hidden=(8,)), {"hidden": [8]})
>>> agent = load_agent(folder)
>>> agent.name == str(folder), agent.fingerprint.startswith("sha256:")
(True, True)
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from pickle import UnpicklingError
from typing import Any

import torch

from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.atomic import write_bytes, write_torch

MODEL_FILE, CONFIG_FILE = "model.pt", "config.json"
METRICS_FILE, CURVE_FILE = "metrics.jsonl", "learning_curve.png"
FORMAT = "pokerirl-dqn"
FORMAT_VERSION = 1


def is_finished(folder: str | os.PathLike[str]) -> bool:
    """Whether ``folder`` holds a complete agent (checkpoint and config, written last)."""
    return (Path(folder) / MODEL_FILE).is_file() and (Path(folder) / CONFIG_FILE).is_file()


def save_agent(folder: str | os.PathLike[str], network: QNetwork, config: dict[str, Any]) -> None:
    """Write ``network``'s weights and ``config`` (JSON-able; ``hidden`` is required).

    ``format`` and ``version`` keys are added to the config.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_torch(
        folder / MODEL_FILE, {k: v.detach().cpu().clone() for k, v in network.state_dict().items()}
    )
    record = {"format": FORMAT, "version": FORMAT_VERSION, **config}
    write_bytes(folder / CONFIG_FILE, (json.dumps(record, indent=2) + "\n").encode())


def files_fingerprint(folder: str | os.PathLike[str], names: tuple[str, ...]) -> str:
    """``sha256:<hex>`` over the bytes of the files ``names`` in ``folder``, in that order."""
    digest = hashlib.sha256()
    for name in names:
        digest.update((Path(folder) / name).read_bytes())
    return f"sha256:{digest.hexdigest()}"


def folder_fingerprint(folder: str | os.PathLike[str]) -> str:
    """``sha256:<hex>`` over the checkpoint's and the config's bytes."""
    return files_fingerprint(folder, (MODEL_FILE, CONFIG_FILE))


def load_agent(folder: str | os.PathLike[str]) -> GreedyQAgent:
    """The agent saved in ``folder``: greedy over legal actions, batched, in inference mode.

    Its ``name`` is the folder as given and ``fingerprint`` the sha256 of its two files.

    Raises:
        ValueError: one line, if the folder is not a finished agent or its files are bad.
    """
    folder = Path(folder)
    if not is_finished(folder):
        raise ValueError(f"{folder}: not an agent folder (needs {MODEL_FILE} and {CONFIG_FILE})")
    try:
        config = json.loads((folder / CONFIG_FILE).read_text())
        if config.get("format") != FORMAT:
            raise ValueError(f"format is {config.get('format')!r}, not {FORMAT!r}")
        network = QNetwork(hidden=tuple(config["hidden"]))
        network.load_state_dict(torch.load(folder / MODEL_FILE, weights_only=True))
    except UnpicklingError:
        # torch's own message suggests weights_only=False: wrong advice for a corrupt file.
        raise ValueError(
            f"{folder}: cannot load agent: {MODEL_FILE} is not a state_dict saved by pokerirl"
        ) from None
    except (ValueError, KeyError, TypeError, RuntimeError, OSError) as error:
        first_line = str(error).strip().splitlines()[0] if str(error).strip() else repr(error)
        raise ValueError(f"{folder}: cannot load agent: {first_line}") from None
    return GreedyQAgent(
        name=str(folder), network=network.eval(), fingerprint=folder_fingerprint(folder)
    )
