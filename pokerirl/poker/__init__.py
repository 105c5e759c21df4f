"""The poker side of reward learning: decision tables as ``Transitions`` and ``pokerirl
train`` (one run or several, with the reward card).

It sits beside ``agents/`` and ``gym/``, above ``irl/``: the IRL core trains on
``Transitions`` and knows nothing of poker; ``datasets/`` reads the tables below it; this
package joins the two. For example::

    from pokerirl.poker import read_table, train_runs

    data = read_table("table.parquet")  # Transitions
    summary = train_runs("table.parquet", "runs/hairl", runs=3)
"""

from __future__ import annotations

from typing import Any

_LAZY = {
    "read_table": "data",
    "transitions_from_arrow": "data",
    "train_runs": "train",
    "train_table": "train",
}

__all__ = ["read_table", "train_runs", "train_table", "transitions_from_arrow"]


def __getattr__(name: str) -> Any:
    # torch takes a second to import: naming a reward or an agent spec should not pay for it.
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"pokerirl.poker.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'pokerirl.poker' has no attribute {name!r}")
