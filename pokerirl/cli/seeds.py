"""Seeds on the command line: the range a seed option takes (:data:`SEED_OPTION`) and the
check of a ``--seeds`` list (:func:`seed_list`), before any work. The lists themselves are
parsed by :func:`pokerirl.seeds.parse_seeds`.
"""

from __future__ import annotations

import re
from typing import Any

import typer

MAX_SEED = 2**32 - 1  # the largest seed numpy's and Gymnasium's generators take
MAX_SEEDS = 10_000  # seeds in one --seeds list
SEED_OPTION: dict[str, Any] = {"min": 0, "max": MAX_SEED}  # typer.Option(..., **SEED_OPTION)


def seed_list(text: str | None) -> str | None:
    """Check a ``--seeds`` value (``0-19``, ``0-4,10``) before it is expanded: every seed
    within 0..2^32-1, at most :data:`MAX_SEEDS` of them (a typer callback: exit 2)."""
    if text is None:
        return None
    from pokerirl.seeds import parse_seeds

    count = 0
    for part in text.split(","):
        numbers = [int(n) for n in re.findall(r"\d+", part)]
        if any(n > MAX_SEED for n in numbers):
            raise typer.BadParameter(f"seeds must be at most {MAX_SEED:,}, got {max(numbers):,}")
        count += numbers[-1] - numbers[0] + 1 if len(numbers) == 2 else 1
    if count > MAX_SEEDS:
        raise typer.BadParameter(f"at most {MAX_SEEDS:,} seeds, got {count:,} in {text!r}")
    try:
        parse_seeds(text)
    except ValueError as error:
        raise typer.BadParameter(str(error)) from None
    return text
