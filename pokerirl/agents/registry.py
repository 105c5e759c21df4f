"""Resolve agent specs: built-in names or saved agent folders.

>>> resolve_agent("raise").name, agent_fingerprint(resolve_agent("raise"))
('raise', 'builtin:raise')
"""

from __future__ import annotations

from pathlib import Path

from pokerirl.game.agents import BUILT_IN_AGENTS, Agent, make_agent


def resolve_agent(spec: str) -> Agent:
    """A built-in agent by name, or the agent saved in the folder ``spec``.

    Raises ``ValueError`` with a one-line message when ``spec`` is neither.
    """
    if spec in BUILT_IN_AGENTS:
        return make_agent(spec)
    path = Path(spec)
    if path.is_dir():
        from pokerirl.agents.checkpoint import load_agent  # torch is only needed here

        return load_agent(path)
    if path.exists():
        raise ValueError(f"{spec}: not an agent folder")
    return make_agent(spec)  # raises: unknown name, listing the built-ins


def agent_fingerprint(agent: Agent) -> str:
    """A stable identity for reports: ``builtin:<name>``, or the saved agent's fingerprint."""
    return str(getattr(agent, "fingerprint", f"builtin:{agent.name}"))
