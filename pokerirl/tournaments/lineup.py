"""What the user typed, turned into seeds and per-seed agents.

An agent spec is a built-in name (``random``, ``raise``, ``call``), an agent folder saved by
``pokerirl agent train``, an RLCard DQN checkpoint (``rlcard:PATH``), or an *agent set*: a
folder with one ``seed-<k>`` subfolder per training seed. Seed ``k`` of a tournament uses
``<set>/seed-<k>``; every other spec is the same agent for every seed.

>>> agent_spec_for_seed("raise", 5), agent_label("runs/hairl-dqn/")
('raise', 'hairl-dqn')
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from pokerirl.agents.registry import RLCARD_PREFIX
from pokerirl.errors import PokerIRLError
from pokerirl.game.agents import BUILT_IN_AGENTS
from pokerirl.seeds import format_seeds

_SEED_FOLDER = re.compile(r"seed-(\d+)")


class TournamentError(PokerIRLError, ValueError):
    """Bad tournament input or a result folder that does not fit; the message is one line."""


def _set_seeds(spec: str) -> list[int]:
    """The k of every ``seed-<k>`` subfolder of ``spec``, sorted; [] if it is not a folder."""
    path = Path(spec)
    if spec in BUILT_IN_AGENTS or not path.is_dir():
        return []
    return sorted(
        int(match[1])
        for child in path.iterdir()
        if (match := _SEED_FOLDER.fullmatch(child.name)) and child.is_dir()
    )


def is_agent_set(spec: str) -> bool:
    """Whether ``spec`` is a folder with at least one ``seed-<k>`` subfolder."""
    return bool(_set_seeds(spec))


def agent_spec_for_seed(spec: str, seed: int) -> str:
    """The spec :func:`pokerirl.agents.resolve_agent` gets for ``seed``."""
    return str(Path(spec) / f"seed-{seed}") if is_agent_set(spec) else spec


def agent_label(spec: str) -> str:
    """A short name for reports: the built-in name, or the folder's (or file's) own name."""
    if spec in BUILT_IN_AGENTS:
        return spec
    return Path(spec.removeprefix(RLCARD_PREFIX)).name or spec


def check_specs(specs: Sequence[str], seeds: Sequence[int]) -> None:
    """Check, without loading anything, that every spec exists and every set has each seed.

    Raises :class:`TournamentError` naming the first bad spec.
    """
    for spec in specs:
        path = Path(spec)
        if spec in BUILT_IN_AGENTS or spec.startswith(RLCARD_PREFIX):
            continue  # checkpoint files are checked when they load
        if not path.exists():
            known = ", ".join(sorted(BUILT_IN_AGENTS))
            raise TournamentError(
                f"{spec}: no such agent folder, and not a built-in agent ({known})"
            )
        if not path.is_dir():
            raise TournamentError(f"{spec}: not an agent folder")
        have = _set_seeds(spec)
        if have:
            missing = [seed for seed in seeds if seed not in have]
            if missing:
                raise TournamentError(
                    f"agent set {spec} has no seed-{missing[0]} folder "
                    f"({len(missing)} requested seed(s) missing; it has seeds "
                    f"{format_seeds(have)})"
                )
