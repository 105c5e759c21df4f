"""Seed lists as users write them: ``0-19``, ``3``, ``0-4,10,12-13``.

>>> parse_seeds("0-3,7,10-11")
(0, 1, 2, 3, 7, 10, 11)
>>> seeds_as_written("7,0-2,1")
(7, 0, 1, 2, 1)
>>> format_seeds([0, 1, 2, 3, 7, 10, 11])
'0-3,7,10-11'
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from pokerirl.errors import ConfigError


def parse_seeds(text: str) -> tuple[int, ...]:
    """Seeds from ``"0-19"``, ``"3"`` or ``"0-4,10,12-13"``: sorted, without repeats.

    Raises ``ValueError`` on an empty range (``"5-3"``), a negative seed or junk.
    """
    return tuple(sorted(set(seeds_as_written(text))))


def seeds_as_written(text: str) -> tuple[int, ...]:
    """The seeds of :func:`parse_seeds` in the order written, repeats kept: for a caller whose
    order matters (the poker study: its first seed seeds the agents) or that refuses repeats."""
    seeds: list[int] = []
    for part in text.split(","):
        match = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", part)
        if match is None:
            raise ConfigError(
                f"bad seed range {text!r}: use non-negative integers like 0-19 or 0-4,10"
            )
        first = int(match[1])
        last = int(match[2]) if match[2] is not None else first
        if last < first:
            raise ConfigError(f"empty seed range {part.strip()!r}")
        seeds.extend(range(first, last + 1))
    return tuple(seeds)


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
