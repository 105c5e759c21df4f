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

from pokerirl.poker.data import read_table, transitions_from_arrow
from pokerirl.poker.train import train_runs, train_table

__all__ = ["read_table", "train_runs", "train_table", "transitions_from_arrow"]
