"""Trained agents (DQN on the sparse payoff or on a learned reward) and agent resolution.

:func:`resolve_agent` is the one place that turns what a user typed into an agent: a built-in
name (``random``, ``raise``, ``call``), an agent folder written by ``pokerirl agent train``,
or ``rlcard:PATH`` for an RLCard DQN checkpoint.

Everything but the registry needs torch and is imported on first use.
"""

from __future__ import annotations

from typing import Any

from pokerirl.agents.registry import agent_fingerprint, resolve_agent

_LAZY = {
    "load_agent": "checkpoint",
    "DQNConfig": "dqn",
    "GreedyQAgent": "dqn",
    "train_dqn": "dqn",
    "import_rlcard_dqn": "rlcard_import",
    "load_rlcard_dqn": "rlcard_import",
    "TrainConfig": "train",
    "train_agent": "train",
    "train_seeds": "train",
}

__all__ = ["agent_fingerprint", "resolve_agent", *_LAZY]


def __getattr__(name: str) -> Any:
    # torch takes a second to import; `pokerirl match random call` should not pay for it.
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"pokerirl.agents.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'pokerirl.agents' has no attribute {name!r}")
