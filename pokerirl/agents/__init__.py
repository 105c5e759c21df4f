"""Trained agents (DQN on the sparse payoff or on a learned reward) and agent resolution.

:func:`resolve_agent` is the one place that turns what a user typed into an agent: a built-in
name (``random``, ``raise``, ``call``) or an agent folder written by ``pokerirl agent train``.
"""

from __future__ import annotations

from pokerirl.agents.registry import agent_fingerprint, resolve_agent

__all__ = ["agent_fingerprint", "resolve_agent"]
