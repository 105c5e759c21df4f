"""What the user typed, turned into seeds and per-seed agents.

An agent spec is a built-in name (``random``, ``raise``, ``call``), an agent folder saved by
``pokerirl agent train``, an RLCard DQN checkpoint (``rlcard:PATH``), or an *agent set*: a
folder with one ``seed-<k>`` subfolder per training seed. Seed ``k`` of a tournament uses
``<set>/seed-<k>``; every other spec is the same agent for every seed.

>>> parse_seeds("0-3,7,10-11")
(0, 1, 2, 3, 7, 10, 11)
>>> agent_spec_for_seed("raise", 5), agent_label("runs/hairl-dqn/")
('raise', 'hairl-dqn')
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from pokerirl.agents.registry import RLCARD_PREFIX
from pokerirl.game.agents import BUILT_IN_AGENTS

_SEED_FOLDER = re.compile(r"seed-(\d+)")


class TournamentError(ValueError):
    """Bad tournament input or a result folder that does not fit; the message is one line."""


def parse_seeds(text: str) -> tuple[int, ...]:
    """Seeds from ``"0-19"``, ``"3"`` or ``"0-4,10,12-13"``: sorted, without repeats.

    Raises :class:`TournamentError` on an empty range (``"5-3"``), a negative seed or junk.
    """
    seeds: set[int] = set()
    for part in text.split(","):
        match = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", part)
        if match is None:
            raise TournamentError(
                f"bad seed range {text!r}: use non-negative integers like 0-19 or 0-4,10"
            )
        first = int(match[1])
        last = int(match[2]) if match[2] is not None else first
        if last < first:
            raise TournamentError(f"empty seed range {part.strip()!r}")
        seeds.update(range(first, last + 1))
    return tuple(sorted(seeds))


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


def format_seeds(seeds: Sequence[int]) -> str:
    """The inverse of :func:`parse_seeds`, with ranges collapsed.

    >>> format_seeds([0, 1, 2, 3, 7, 10, 11])
    '0-3,7,10-11'
    """
    parts: list[str] = []
    ordered = sorted(set(seeds))
    i = 0
    while i < len(ordered):
        j = i
        while j + 1 < len(ordered) and ordered[j + 1] == ordered[j] + 1:
            j += 1
        parts.append(str(ordered[i]) if i == j else f"{ordered[i]}-{ordered[j]}")
        i = j + 1
    return ",".join(parts)
