"""Play agents trained in RLCard 1.2.0: load a ``DQNAgent.save_checkpoint`` file.

RLCard's checkpoint is a pickle of the whole agent state (replay memory included), so it is
loaded with ``torch.load(..., weights_only=False)``, which can run arbitrary code: **load only
files you trust**. Its q-network (``EstimatorNetwork``: batch norm, tanh MLP) has the same
layers as :class:`pokerirl.agents.dqn.QNetwork`, so the weights carry over exactly.

RLCard 1.2.0 saves ``epsilon_start = min(epsilons)`` and ``epsilon_end = max(epsilons)``:
for its decaying schedule the two are swapped (and ``from_checkpoint`` then resumes with an
increasing epsilon). :func:`rlcard_checkpoint_config` reports them the right way round.
The greedy agent does not use epsilon, so only the record is affected.
"""

from __future__ import annotations

import hashlib
import os
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import torch

from pokerirl.agents.checkpoint import save_agent
from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.agents.names import RLCARD_PREFIX
from pokerirl.errors import InputError
from pokerirl.holdem import NUM_ACTIONS, OBS_SIZE

_LAYER_KEY = re.compile(r"^fc_layers\.(\d+)\.(.+)$")


class UntrustedCheckpointWarning(UserWarning):
    """An RLCard checkpoint is about to be unpickled: it can run any code it holds."""


def _read_checkpoint(path: Path) -> Mapping[str, Any]:
    if not path.is_file():
        raise InputError(f"{path}: no such RLCard checkpoint file")
    warnings.warn(
        f"{RLCARD_PREFIX}{path}: unpickling an RLCard checkpoint runs any code it holds; "
        "load only files you trust",
        UntrustedCheckpointWarning,
        stacklevel=4,  # the caller of load_rlcard_dqn or import_rlcard_dqn
    )
    try:
        # Trusted files only: RLCard pickles its agent (and its replay memory's namedtuples,
        # whose unpickling imports rlcard.agents, which runs `pip freeze`: about 3 s).
        checkpoint = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as error:
        reason = (str(error).strip() or repr(error)).splitlines()[0]
        raise InputError(f"{path}: cannot read RLCard checkpoint: {reason}") from None
    if not isinstance(checkpoint, dict) or checkpoint.get("agent_type") != "DQNAgent":
        raise InputError(f"{path}: not an RLCard DQNAgent checkpoint")
    for key in ("q_estimator", "num_actions"):
        if key not in checkpoint:
            raise InputError(f"{path}: not an RLCard DQNAgent checkpoint (no {key})")
    estimator = checkpoint["q_estimator"]
    if not isinstance(estimator, dict) or not {"state_shape", "mlp_layers", "qnet"} <= set(
        estimator
    ):
        raise InputError(f"{path}: not an RLCard DQNAgent checkpoint (bad q_estimator)")
    try:
        shape = list(estimator["state_shape"] or [])
        hidden = [int(width) for width in estimator["mlp_layers"]]
    except (TypeError, ValueError):
        raise InputError(f"{path}: not an RLCard DQNAgent checkpoint (bad q_estimator)") from None
    if shape != [OBS_SIZE] or checkpoint["num_actions"] != NUM_ACTIONS:
        raise InputError(
            f"{path}: state_shape {shape} and num_actions {checkpoint['num_actions']} are not "
            f"limit hold'em's [{OBS_SIZE}] and {NUM_ACTIONS}"
        )
    if not hidden or min(hidden) < 1 or not isinstance(estimator["qnet"], dict):
        raise InputError(f"{path}: not an RLCard DQNAgent checkpoint (bad q_estimator)")
    return checkpoint


def _convert_state_dict(qnet_state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """RLCard's ``fc_layers.{i}`` (0 Flatten, 1 BatchNorm, 2.. MLP) to QNetwork's keys."""
    converted = {}
    for key, value in qnet_state.items():
        match = _LAYER_KEY.match(key)
        if match is None:
            raise InputError(f"unexpected RLCard q-network key {key!r}")
        index, rest = int(match.group(1)), match.group(2)
        converted[f"norm.{rest}" if index == 1 else f"mlp.{index - 2}.{rest}"] = value
    return converted


def rlcard_checkpoint_config(checkpoint: Mapping[str, Any]) -> dict[str, float]:
    """The hyper-parameters of an RLCard checkpoint, with its epsilon fields un-swapped."""
    estimator = checkpoint["q_estimator"]
    low, high = checkpoint["epsilon_start"], checkpoint["epsilon_end"]  # min, max: see above
    return {
        "replay_size": checkpoint["memory"]["memory_size"],
        "batch_size": checkpoint["batch_size"],
        "learning_rate": estimator["learning_rate"],
        "gamma": checkpoint["discount_factor"],
        "epsilon_start": float(high),
        "epsilon_end": float(low),
        "epsilon_decay_steps": checkpoint["epsilon_decay_steps"],
        "target_update_every": checkpoint["update_target_estimator_every"],
        "train_every": checkpoint["train_every"],
        "total_t": checkpoint["total_t"],
        "train_t": checkpoint["train_t"],
    }


def load_rlcard_dqn(path: str | os.PathLike[str]) -> GreedyQAgent:
    """A greedy engine agent from an RLCard 1.2.0 ``DQNAgent`` checkpoint (trusted files only).

    Its q-values equal RLCard's ``predict`` on the same ``obs``; its ``name`` is
    ``rlcard:<path>`` and its ``fingerprint`` the sha256 of the file.

    Raises:
        ValueError: one line, for a missing, unreadable or non-limit-hold'em checkpoint.
    """
    return _agent_and_checkpoint(Path(path))[0]


def _agent_and_checkpoint(path: Path) -> tuple[GreedyQAgent, Mapping[str, Any]]:
    checkpoint = _read_checkpoint(path)
    estimator = checkpoint["q_estimator"]
    network = QNetwork(hidden=tuple(int(width) for width in estimator["mlp_layers"]))
    try:
        network.load_state_dict(_convert_state_dict(estimator["qnet"]))
    except (RuntimeError, ValueError, TypeError, AttributeError) as error:
        raise InputError(f"{path}: q-network does not fit: {str(error).splitlines()[0]}") from None
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    agent = GreedyQAgent(
        name=f"{RLCARD_PREFIX}{path}", network=network.eval(), fingerprint=f"sha256:{digest}"
    )
    return agent, checkpoint


def import_rlcard_dqn(path: str | os.PathLike[str], out: str | os.PathLike[str]) -> Path:
    """Convert an RLCard ``DQNAgent`` checkpoint (trusted files only) into an agent folder.

    The folder then loads with :func:`pokerirl.agents.load_agent` (no pickle) and works
    anywhere an agent name does. Returns ``out``.
    """
    agent, checkpoint = _agent_and_checkpoint(Path(path))
    try:
        dqn = rlcard_checkpoint_config(checkpoint)
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(f"{path}: RLCard checkpoint without its settings ({error!r})") from None
    config = {
        "hidden": [int(width) for width in checkpoint["q_estimator"]["mlp_layers"]],
        "source": {"kind": "rlcard-1.2.0-dqn", "path": str(path), "fingerprint": agent.fingerprint},
        "dqn": dqn,
    }
    save_agent(out, agent.network, config)
    return Path(out)
