"""Resolve agent specs: built-in names, saved agent folders or RLCard DQN checkpoints.

>>> resolve_agent("raise").name, agent_fingerprint(resolve_agent("raise"))
('raise', 'builtin:raise')
"""

from __future__ import annotations

import os
from pathlib import Path

from pokerirl.agents.names import RLCARD_PREFIX
from pokerirl.errors import InputError, check_argument
from pokerirl.game.bots import BUILT_IN_AGENTS, Agent, make_agent
from pokerirl.poker.agent_specs import POLICY_PREFIX, REWARD_PREFIX


def resolve_agent(spec: str) -> Agent:
    """A built-in agent by name, the agent saved in the folder ``spec``, ``reward:RUN`` (the
    argmax of a learned reward; ``reward:authors:FILE`` too), ``policy:RUN`` (an IRL run's
    policy, greedy), or, for ``rlcard:PATH``, the greedy policy of an RLCard ``DQNAgent``
    checkpoint file (which is unpickled: trusted files only).

    Raises ``ValueError`` with a one-line message when ``spec`` is none of these, and
    ``TypeError`` when it is not a string or a path.
    """
    check_argument("spec", spec, (str, os.PathLike), "an agent spec (a string) or a folder")
    spec = os.fspath(spec)
    if spec in BUILT_IN_AGENTS:
        return make_agent(spec)
    if spec.startswith(REWARD_PREFIX):
        from pokerirl.poker.run_agents import reward_agent

        return reward_agent(spec)
    if spec.startswith(POLICY_PREFIX):
        from pokerirl.poker.run_agents import policy_agent

        return policy_agent(spec)
    if spec.startswith(RLCARD_PREFIX):
        from pokerirl.agents.rlcard_import import load_rlcard_dqn

        return load_rlcard_dqn(spec.removeprefix(RLCARD_PREFIX))
    path = Path(spec)
    if path.is_dir():
        from pokerirl.agents.checkpoint import load_agent  # torch is only needed here

        return load_agent(path)
    if path.exists():
        raise InputError(f"{spec}: not an agent folder")
    if len(path.parts) > 1:  # a path, not a name (named as it is: repr would hide its bytes)
        known = ", ".join(sorted(BUILT_IN_AGENTS))
        raise InputError(f"{spec}: no such agent folder, and not a built-in agent ({known})")
    return make_agent(spec)  # raises: unknown name, listing the built-ins


def agent_fingerprint(agent: Agent) -> str:
    """A stable identity for reports: ``builtin:<name>``, or the saved agent's fingerprint."""
    return str(getattr(agent, "fingerprint", f"builtin:{agent.name}"))
