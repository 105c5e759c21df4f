"""Trained agents (DQN on the sparse payoff or on a learned reward) and agent resolution.

The learned agents live here; the built-in bots in :mod:`pokerirl.game.bots`, the agents
made of an IRL run (``reward:RUN``, ``policy:RUN``) in :mod:`pokerirl.poker.run_agents`.

:func:`resolve_agent` is the one place that turns what a user typed into an agent: a built-in
name (``random``, ``raise``, ``call``, ``tightbot``, ``loosebot``), an agent folder written by
``pokerirl agent train``, or ``rlcard:PATH`` for an RLCard DQN checkpoint.
:class:`RLCardAgent` goes the other way: any agent, with RLCard's agent interface, plays in
RLCard's own environment and ``tournament``.

:func:`ship_agent` and :func:`land_agent` carry an agent to a worker as bytes (see
:mod:`pokerirl.execution`): the driver reads the files, the worker writes them into a private
folder and loads them there, so workers need no shared filesystem.

Everything but the registry needs torch and is imported on first use.

>>> import tempfile
>>> land_agent(ship_agent("raise"), tempfile.mkdtemp()).name
'raise'
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pokerirl.agents.names import CONFIG_FILE, KEPT_FILE, MODEL_FILE, RLCARD_PREFIX
from pokerirl.agents.registry import agent_fingerprint, resolve_agent
from pokerirl.game.bots import BUILT_IN_AGENTS, Agent
from pokerirl.jsonio import read_bytes
from pokerirl.poker.agent_specs import POLICY_PREFIX, REWARD_PREFIX

AGENT_FILES = (MODEL_FILE, CONFIG_FILE)  # what an agent folder's agent is made of (and
# KEPT_FILE, the authors' kept checkpoint, when there is one)


@dataclass(frozen=True, kw_only=True)
class ShippedAgent:
    """An agent spec and the bytes of its files (none for a built-in)."""

    spec: str
    files: tuple[tuple[str, bytes], ...] = ()


def ship_agent(spec: str) -> ShippedAgent:
    """``spec`` with the bytes a worker needs to load it (read here, once)."""
    if spec in BUILT_IN_AGENTS:
        return ShippedAgent(spec=spec)
    if spec.startswith(REWARD_PREFIX):
        from pokerirl.poker.reward_sources import RewardSource

        source = RewardSource.resolve(spec.removeprefix(REWARD_PREFIX))
        return ShippedAgent(spec=spec, files=source.files)
    if spec.startswith(POLICY_PREFIX):
        from pokerirl.poker.run_agents import policy_files

        files = policy_files(spec.removeprefix(POLICY_PREFIX))
        return ShippedAgent(spec=spec, files=tuple(files.items()))
    if spec.startswith(RLCARD_PREFIX):
        path = Path(spec.removeprefix(RLCARD_PREFIX))
        return ShippedAgent(spec=spec, files=(("checkpoint.pt", path.read_bytes()),))
    kept = (KEPT_FILE,) if (Path(spec) / KEPT_FILE).is_file() else ()
    names = (*AGENT_FILES, *kept)

    def read(name: str) -> bytes:  # config.json bounded: a 2 GiB sparse one was read whole
        path = Path(spec) / name
        return read_bytes(path, what="cannot load agent: ") if name == CONFIG_FILE else (
            path.read_bytes())  # fmt: skip

    return ShippedAgent(spec=spec, files=tuple((name, read(name)) for name in names))


def land_agent(shipped: ShippedAgent, folder: str | os.PathLike[str]) -> Agent:
    """Write a shipped agent's files into ``folder`` (empty, private) and load it from there.

    Its fingerprint is that of the bytes, so it equals the driver's.
    """
    if not shipped.files:
        return resolve_agent(shipped.spec)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in shipped.files:
        (folder / name).write_bytes(data)
    if shipped.spec.startswith(REWARD_PREFIX):
        from pokerirl.poker.reward_sources import AUTHORS_FILE
        from pokerirl.poker.rewards import AUTHORS_PREFIX, is_authors_spec

        source = shipped.spec.removeprefix(REWARD_PREFIX)
        landed = f"{AUTHORS_PREFIX}{folder / AUTHORS_FILE}" if is_authors_spec(source) else folder
        return resolve_agent(f"{REWARD_PREFIX}{landed}")
    if shipped.spec.startswith(POLICY_PREFIX):
        return resolve_agent(f"{POLICY_PREFIX}{folder}")
    if shipped.spec.startswith(RLCARD_PREFIX):
        from pokerirl.agents.rlcard_import import UntrustedCheckpointWarning

        # The driver warned when it read these bytes; a worker's copy needs no second warning.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UntrustedCheckpointWarning)
            return resolve_agent(f"{RLCARD_PREFIX}{folder / shipped.files[0][0]}")
    return resolve_agent(str(folder))


_LAZY = {
    "load_agent": "checkpoint",
    "DQNConfig": "config",
    "GreedyQAgent": "dqn",
    "train_dqn": "dqn",
    "import_rlcard_dqn": "rlcard_import",
    "load_rlcard_dqn": "rlcard_import",
    "RLCardAgent": "rlcard_adapter",
    "rlcard_states": "rlcard_adapter",
    "TrainConfig": "config",
    "train_agent": "train",
    "train_seeds": "train",
}

__all__ = [
    "ShippedAgent",
    "agent_fingerprint",
    "land_agent",
    "resolve_agent",
    "ship_agent",
    *_LAZY,
]


def __getattr__(name: str) -> Any:
    # torch takes a second to import; `pokerirl match random call` should not pay for it.
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"pokerirl.agents.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'pokerirl.agents' has no attribute {name!r}")
