"""Poker decision tables as :class:`~pokerirl.irl.Transitions`, the trainer's data.

The table is read and validated below ``irl/`` (:mod:`pokerirl.datasets.decisions`, numpy
only); here, above both, its arrays become ``Transitions``. ``irl/`` itself knows nothing of
poker.

>>> from pokerirl.datasets.toy import toy_expert_table
>>> data = transitions_from_arrow(toy_expert_table(num_hands=30, seed=1))
>>> data.discrete, data.obs_dim, data.action_dim
(True, 72, 4)
"""

from __future__ import annotations

import os

import pyarrow as pa

from pokerirl.datasets.decisions import Table, decisions_from_arrow, read_data
from pokerirl.game.encodings import Encoding
from pokerirl.irl.transitions import Transitions


def read_table(path: str | os.PathLike[str], *, encoding: Encoding | None = None) -> Transitions:
    """The decisions at ``path`` (a table of ``pokerirl ingest``, or Leduc demonstrations) as
    ``Transitions``, a hold'em table's states in ``encoding`` (default ``rlcard``; see
    :mod:`pokerirl.game.encodings`).

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` for anything else wrong
    (see :func:`pokerirl.datasets.decisions.read_data`).
    """
    return as_transitions(read_data(path, encoding=encoding))


def transitions_from_arrow(
    table: pa.Table, *, source: str = "table", encoding: Encoding | None = None
) -> Transitions:
    """An Arrow table with the decision-table schema as ``Transitions``, validated."""
    return as_transitions(decisions_from_arrow(table, source=source, encoding=encoding))


def as_transitions(decisions: Table) -> Transitions:
    d = decisions
    return Transitions.from_arrays(d.obs, d.action_ids, groups=d.groups, next_obs=d.next_obs,
                                   dones=d.dones, rewards=d.rewards, legal_mask=d.legal_mask,
                                   num_actions=d.num_actions, weights=d.weights,
                                   imputed=d.imputed)  # fmt: skip
