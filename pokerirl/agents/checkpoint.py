"""Agent folders: a q-network ``state_dict`` plus ``config.json``, and :func:`load_agent`.

An agent folder holds ``model.pt`` (the q-network's ``state_dict``, loaded with
``weights_only=True``) and ``config.json`` (network shape, how it was trained: reward mode,
reward-run fingerprint, seed, hyper-parameters). Both are written atomically, ``config.json``
last, so a folder with both is finished. Training also writes ``metrics.jsonl`` and
``learning_curve.png`` there. An agent trained with the authors' protocol also holds
``kept.pt``, the checkpoint their "> 0.8 x best" rule keeps; ``config.json``'s ``plays`` says
which of the two the agent plays (``final``, the default, or ``kept``).

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
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import torch

from pokerirl.agents.config import PLAYS, Plays
from pokerirl.agents.dqn import GreedyQAgent, QNetwork, input_norm
from pokerirl.agents.names import CONFIG_FILE, KEPT_FILE, MODEL_FILE
from pokerirl.atomic import write_bytes, write_torch
from pokerirl.errors import ConfigError, InputError, check_argument
from pokerirl.game.encodings import Encoding, EncodingName, recorded_encoding
from pokerirl.jsonio import check_format, read_json
from pokerirl.settings import MAX_LAYERS, MAX_WIDTH

METRICS_FILE, CURVE_FILE = "metrics.jsonl", "learning_curve.png"
FORMAT = "pokerirl-dqn"
FORMAT_VERSION = 1


def is_finished(folder: str | os.PathLike[str]) -> bool:
    """Whether ``folder`` holds a complete agent (checkpoint and config, written last)."""
    return (Path(folder) / MODEL_FILE).is_file() and (Path(folder) / CONFIG_FILE).is_file()


def save_agent(
    folder: str | os.PathLike[str],
    network: QNetwork,
    config: Mapping[str, Any],
    *,
    kept: dict[str, torch.Tensor] | None = None,
) -> None:
    """Write ``network``'s weights and ``config`` (JSON-able; ``hidden`` is required), and
    ``kept`` (a ``state_dict``) as ``kept.pt`` when given.

    ``format`` and ``version`` keys are added to the config.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_torch(
        folder / MODEL_FILE, {k: v.detach().cpu().clone() for k, v in network.state_dict().items()}
    )
    if kept is not None:
        write_torch(folder / KEPT_FILE, {k: v.detach().cpu().clone() for k, v in kept.items()})
    record = {"format": FORMAT, "version": FORMAT_VERSION, **config}
    write_bytes(folder / CONFIG_FILE, (json.dumps(record, indent=2) + "\n").encode())


def files_fingerprint(folder: str | os.PathLike[str], names: tuple[str, ...]) -> str:
    """``sha256:<hex>`` over the bytes of the files ``names`` in ``folder``, in that order."""
    digest = hashlib.sha256()
    for name in names:
        digest.update((Path(folder) / name).read_bytes())
    return f"sha256:{digest.hexdigest()}"


def agent_files(folder: str | os.PathLike[str]) -> tuple[str, ...]:
    """The files an agent folder's agent is made of: the checkpoints, then the config."""
    kept = (KEPT_FILE,) if (Path(folder) / KEPT_FILE).is_file() else ()
    return (MODEL_FILE, *kept, CONFIG_FILE)


def folder_fingerprint(folder: str | os.PathLike[str]) -> str:
    """``sha256:<hex>`` over the checkpoints' and the config's bytes."""
    return files_fingerprint(folder, agent_files(folder))


def load_agent(folder: str | os.PathLike[str]) -> GreedyQAgent:
    """The agent saved in ``folder``: greedy over legal actions, batched, in inference mode.

    Its ``name`` is the folder as given and ``fingerprint`` the sha256 of its two files.

    Raises:
        ValueError: one line naming the bad file, if the folder is not a finished agent or
            its files are bad.
    """
    check_argument("folder", folder, (str, os.PathLike), "an agent folder (a path)")
    folder = Path(folder)
    if not is_finished(folder):
        raise InputError(f"{folder}: not an agent folder (needs {MODEL_FILE} and {CONFIG_FILE})")
    hidden, plays, encoding = _read_config(folder / CONFIG_FILE)
    checkpoint = folder / (KEPT_FILE if plays == Plays.KEPT else MODEL_FILE)
    state = _read_state_dict(checkpoint)
    network = QNetwork(hidden=hidden, obs_size=encoding.width, input_norm=input_norm(encoding))
    try:
        network.load_state_dict(state)
    except (RuntimeError, ValueError, TypeError) as error:
        raise _bad(
            checkpoint,
            f"does not fit {CONFIG_FILE}'s hidden {list(hidden)} on the {encoding.spec} "
            f"encoding ({encoding.width}-d): {_first_line(error)}",
        ) from None
    return GreedyQAgent(
        name=str(folder),
        network=network.eval(),
        fingerprint=folder_fingerprint(folder),
        encoding=encoding.spec,
    )


_CANNOT_LOAD = "cannot load agent: "


def _bad(path: Path, reason: str) -> InputError:
    return InputError(f"{path}: {_CANNOT_LOAD}{reason}")


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def _read_config(path: Path) -> tuple[tuple[int, ...], str, Encoding]:
    """The hidden widths in an agent's ``config.json``, which checkpoint plays and the
    encoding it reads (``rlcard`` for agents made before encodings); ValueError naming
    ``path`` if bad."""
    try:
        config = read_json(path, what=_CANNOT_LOAD)
    except OSError as error:
        raise _bad(path, f"cannot read ({error.strerror or error})") from None
    if not isinstance(config, dict):
        raise _bad(path, f"not an agent config (a JSON object), got {type(config).__name__}")
    check_format(
        config, where=path, kind=("format", FORMAT), version=("version", (FORMAT_VERSION,)),
        what=_CANNOT_LOAD,
    )  # fmt: skip
    hidden = config.get("hidden")
    if (
        not isinstance(hidden, list)
        or not 0 < len(hidden) <= MAX_LAYERS
        or not all(type(width) is int and 0 < width <= MAX_WIDTH for width in hidden)
    ):
        raise _bad(
            path,
            f"hidden must be a list of at most {MAX_LAYERS} integers in 1..{MAX_WIDTH}, "
            f"got {str(hidden)[:60]}",
        )
    plays = config.get("plays", Plays.FINAL)
    if plays not in PLAYS:
        raise _bad(path, f"plays must be final or kept, got {str(plays)[:40]!r}")
    if plays == Plays.KEPT and not (path.parent / KEPT_FILE).is_file():
        raise _bad(path, f"plays the kept checkpoint, but there is no {KEPT_FILE}")
    try:  # a bare "strength" (before versions) is strength-v1
        encoding = recorded_encoding(config.get("encoding", EncodingName.RLCARD))
    except ConfigError as error:
        raise _bad(path, str(error)) from None
    return tuple(hidden), plays, encoding


def _read_state_dict(path: Path) -> dict[str, torch.Tensor]:
    """The ``state_dict`` in ``path``, loaded without unpickling code; ValueError naming
    ``path`` if it is not one. torch's own messages are not passed on: for a corrupt file they
    suggest ``weights_only=False``, which is the wrong advice."""
    try:
        empty = path.stat().st_size == 0
        with warnings.catch_warnings():  # torch warns of a plain pickle before refusing it
            warnings.simplefilter("ignore")
            state = None if empty else torch.load(path, map_location="cpu", weights_only=True)
    except OSError as error:
        raise _bad(path, f"cannot read ({error.strerror or error})") from None
    except Exception:
        raise _bad(path, "corrupt or truncated (not a model saved by pokerirl)") from None
    if empty:
        raise _bad(path, "empty file (not a model saved by pokerirl)")
    if not isinstance(state, dict) or not all(
        isinstance(key, str) and isinstance(value, torch.Tensor) for key, value in state.items()
    ):
        raise _bad(path, "not a state_dict (a mapping of names to tensors)")
    bad = [k for k, v in state.items() if v.is_floating_point() and not torch.isfinite(v).all()]
    if bad:  # a NaN network plays whatever argmax NaN gives, without a word
        raise _bad(path, f"weights hold NaN or infinity ({bad[0]})")
    return state
