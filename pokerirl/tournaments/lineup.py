"""What the user typed, turned into seeds and per-seed agents.

An agent spec is a built-in name (``random``, ``raise``, ``call``), an agent folder saved by
``pokerirl agent train``, an RLCard DQN checkpoint (``rlcard:PATH``), or an *agent set*: a
folder with one ``seed-<k>`` subfolder per training seed. Seed ``k`` of a tournament uses
``<set>/seed-<k>``; every other spec is the same agent for every seed.

A side of a matchup is one spec, or several (agents trained with different seeds): every agent
of one side then meets every agent of the other, one matchup per pair (:func:`expand_sides`).

>>> agent_spec_for_seed("raise", 5), agent_label("runs/hairl-dqn/")
('raise', 'hairl-dqn')
>>> lineup = expand_sides([(["a/hairl/seed-0", "a/hairl/seed-1"], "raise")])
>>> lineup.pairs[1], lineup.labels[1], lineup.groups[0].agent_a
(('a/hairl/seed-1', 'raise'), ('hairl/seed-1', 'raise'), 'hairl')
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from pokerirl.agents.names import RLCARD_PREFIX
from pokerirl.errors import PokerIRLError
from pokerirl.game.bots import BUILT_IN_AGENTS
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


Side = str | Sequence[str]  # one agent spec, or several agents (training seeds) of one side


@dataclass(frozen=True, kw_only=True)
class Group:
    """The matchups (indices) that make one comparison, and its two sides' names."""

    agent_a: str
    agent_b: str
    matchups: tuple[int, ...]


@dataclass(frozen=True, kw_only=True)
class Lineup:
    """Sides turned into matchups: each (A, B) agent pair, its labels, and the comparisons
    (one per pair of sides) that group them."""

    pairs: list[tuple[str, str]]
    labels: list[tuple[str, str]]
    groups: list[Group]


def member_label(spec: str) -> str:
    """An agent's label among several of its side: ``<set>/seed-<k>`` for a seed folder (two
    sides' ``seed-0`` must not read alike), else :func:`agent_label`."""
    label = agent_label(spec)
    parent = Path(spec.removeprefix(RLCARD_PREFIX)).parent.name
    return f"{parent}/{label}" if _SEED_FOLDER.fullmatch(label) and parent else label


def side_label(members: Sequence[str]) -> str:
    """A side's name: its agent's label, or for several the folder that holds them all (the
    set they were trained into), else their labels joined by ``+``."""
    if len(members) == 1:
        return agent_label(members[0])
    parents = {Path(spec.removeprefix(RLCARD_PREFIX)).parent for spec in members}
    if len(parents) == 1 and (parent := parents.pop().name):
        return parent
    return "+".join(member_label(spec) for spec in members)


def parse_side(text: str, *, cross: bool = False) -> Side:
    """A side as the command line gives it: one spec, or several joined by commas (a path
    that exists is never split); with ``cross`` an agent set stands for all its
    ``seed-<k>`` agents, each one of the side's agents, instead of pairing by seed.

    >>> parse_side("a/seed-0,a/seed-1"), parse_side("raise", cross=True)
    (['a/seed-0', 'a/seed-1'], 'raise')
    """
    specs = [text] if "," not in text or Path(text).exists() else text.split(",")
    if cross:  # a spec that is no set is its own one member
        specs = [member for spec in specs
                 for member in ([str(Path(spec) / f"seed-{k}") for k in _set_seeds(spec)]
                                or [spec])]  # fmt: skip
    return specs[0] if len(specs) == 1 else specs


def expand_sides(matchups: Sequence[tuple[Side, Side]]) -> Lineup:
    """Every (A, B) agent pair of every pair of sides, in order (A's agents outer), with its
    labels and the comparison each belongs to.

    Raises :class:`TournamentError` for a side with no agent, one agent twice on a side, or an
    agent set beside several agents (a set pairs by seed; give its ``seed-<k>`` folders).
    """
    pairs: list[tuple[str, str]] = []
    labels: list[tuple[str, str]] = []
    groups: list[Group] = []
    for side_a, side_b in matchups:
        members = [[side] if isinstance(side, str) else list(side) for side in (side_a, side_b)]
        for side in members:
            if not side:
                raise TournamentError("a side with no agent: give at least one per side")
            if len(set(side)) < len(side):
                raise TournamentError(f"the same agent is listed twice on one side: {side}")
        several = any(len(side) > 1 for side in members)
        for spec in (spec for side in members for spec in side):
            if several and is_agent_set(spec):
                raise TournamentError(
                    f"{spec}: an agent set (seed k plays seed k) cannot meet several agents; "
                    "list its seed-<k> folders instead"
                )
        names = [[member_label(s) if len(side) > 1 else agent_label(s) for s in side]
                 for side in members]  # fmt: skip
        first = len(pairs)
        for i, a in enumerate(members[0]):
            for j, b in enumerate(members[1]):
                pairs.append((a, b))
                labels.append((names[0][i], names[1][j]))
        groups.append(Group(agent_a=side_label(members[0]), agent_b=side_label(members[1]),
                            matchups=tuple(range(first, len(pairs)))))  # fmt: skip
    return Lineup(pairs=pairs, labels=labels, groups=groups)
